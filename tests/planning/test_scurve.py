"""The carry's S-curve and the jerk the tracker tolerates.

The S-curve goes from rest at 0 to rest at 1 within its rate, acceleration and jerk bounds,
with a continuous acceleration, and :meth:`~hexapod_model.planning.scurve.SCurve.times`
inverts it; the tracker's motion model, run on a constant-jerk motion at the stated jerk,
misses by the stated share of its innovation sigma.
"""

from __future__ import annotations

import numpy as np
import pytest

from hexapod_model.exceptions import HexapodError
from hexapod_model.planning.scurve import DEFAULT_CARRY_JERK, SCurve, tracker_jerk_limit
from hexapod_model.tracking.reading_tests import DEFAULT_READING_NOISE, MotionModel


@pytest.mark.parametrize(("v", "a", "j"), [(0.1, 0.05, 0.2), (10.0, 50.0, 20.0), (10.0, 1.0, 20.0), (0.5, 0.2, 30.0)])
def test_the_s_curve_is_rest_to_rest_within_its_bounds(v, a, j):
    c = SCurve(v, a, j)
    t = np.linspace(0.0, c.duration, 20001)
    s, sd, sdd, sddd = c(t)
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0, abs=1e-12)
    assert abs(sd[-1]) < 1e-12 and abs(sdd[-1]) < 1e-12 and sd[0] == sdd[0] == 0.0
    assert np.all(np.diff(s) >= -1e-15)
    assert np.all(np.abs(sd) <= v * (1 + 1e-12)) and np.all(np.abs(sdd) <= a * (1 + 1e-12))
    assert np.all(np.abs(sddd) <= j)
    # the acceleration never steps: between two instants it changes by at most j times their distance
    assert np.all(np.abs(np.diff(sdd)) <= j * np.diff(t) * (1 + 1e-9))
    probe = np.linspace(0.0, 1.0, 101)
    np.testing.assert_allclose(c(c.times(probe))[0], probe, atol=1e-9)


def test_the_s_curve_refuses_a_bound_that_is_not_positive():
    with pytest.raises(HexapodError, match="j"):
        SCurve(1.0, 1.0, 0.0)


@pytest.mark.parametrize("rate", [50.0, 100.0])
def test_the_trackers_model_misses_a_constant_jerk_by_the_stated_share(rate):
    jerk = tracker_jerk_limit(rate, DEFAULT_READING_NOISE, 0.5)
    dt = 1.0 / rate
    t = -dt * np.arange(1, 7)
    w, spread = MotionModel().weights(tuple(range(1, 7)))
    for t0 in (0.0, 0.3, -0.7):  # the cubic seen anywhere along the move: the quadratic's error does not change
        x = jerk * (t + t0) ** 3 / 6.0
        miss = abs(jerk * t0**3 / 6.0 - w @ x)
        assert miss == pytest.approx(0.5 * DEFAULT_READING_NOISE * spread, rel=1e-6)
    assert DEFAULT_CARRY_JERK == pytest.approx(tracker_jerk_limit(), abs=0.005)
