"""What the certificate cannot vouch for is never ``converged``: the 3-6 fold case.

tests/data/three_six_fold.json: warm starts whose plain Newton result lies across a fold from
the start (det J changes sign, a dense continuation from the start is blocked). They were
returned ``converged`` with only the ``near_singular`` flag.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.tracking.types import POSED_STATUSES

from ..conftest import hexapod, limits_only

CASES = Path(__file__).parents[1] / "data" / "three_six_fold.json"


@functools.cache
def _cases() -> list[dict]:
    return json.loads(CASES.read_text())["cases"]


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("k", [0, 1])
def test_a_warm_result_across_a_fold_is_uncertified_not_converged(k, compiled):
    # the stroke and joint limits alone: the fold lies beyond the cones
    hexa = limits_only("3-6") if compiled else hm.Hexapod.from_preset("3-6", compiled=False, check_body=False)
    case = _cases()[k]
    start, readings = np.array(case["start_q"]), np.array(case["readings_m"])
    for guess in (start, hexa.forward(hexa.lengths_of(start), guess=start, check=False)):
        sol = hexa.forward(readings, guess=guess, check=False)
        assert sol.status == "uncertified" and not sol.converged
        assert sol.flags == ("near_singular",) and "could not be certified" in sol.message
        np.testing.assert_allclose(hexa.inverse(sol.pose).lengths, readings, atol=1e-9)  # it does close
        with pytest.raises(hm.AssemblyError, match="^uncertified: "):
            hexa.forward(readings, guess=guess)


def test_batches_and_the_tracker_do_not_call_it_converged():
    hexa = hexapod("3-6")
    case = _cases()[0]
    start, readings = np.array(case["start_q"]), np.array(case["readings_m"])
    res = hexa.forward_batch(readings[None], guess=start)
    assert res.status[0] == "uncertified" and not res.converged[0] and np.isnan(res.poses[0]).all()
    assert "uncertified" in hm.STATUSES and "uncertified" in POSED_STATUSES


def test_the_tracker_flags_an_uncertified_sample_and_never_calls_it_ok():
    from hexapod_model.tracking.tracker import Tracker

    hexa = hexapod("3-6")
    case = _cases()[0]
    start, readings = np.array(case["start_q"]), np.array(case["readings_m"])
    tracker = Tracker(hexa, initial=start)
    r = tracker.step(readings)
    assert r.solution.status == "uncertified" and "branch_uncertain" in r.flags
