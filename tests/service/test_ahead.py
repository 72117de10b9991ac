"""The ahead check with no frame held, as the cycle's fast path takes it (FixtureCycle._frame)."""

from __future__ import annotations

import math

import numpy as np

from hexapod_model.service.cycle.ahead import AheadCheck


def test_with_no_frame_held_a_frame_that_opens_no_newer_instant_is_offered_alone_and_none_is_held():
    rng = np.random.default_rng(0)
    opened = alone = 0
    for _ in range(2000):
        check = AheadCheck()
        newest = float(rng.uniform(0.0, 1.0))
        skew = math.nan if rng.uniform() < 0.1 else float(rng.uniform(0.0, 0.01))  # NaN: the period not yet known
        t = newest + float(rng.uniform(-0.02, 0.02))
        out = check.offer(2, b"\x01", t, skew, newest, newest)
        if t > newest + skew:  # it would open a newer instant: held until the next frame
            assert out == [] and check.held == (2, b"\x01", t)
            opened += 1
        else:  # what the cycle takes at once without calling offer()
            assert out == [(2, b"\x01", t)] and check.held is None and not check.legs
            alone += 1
    assert opened > 100 and alone > 100
