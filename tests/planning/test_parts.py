"""The planner's parts: the Lipschitz bound between samples, the timing, the order, the missing extra."""

from __future__ import annotations

import importlib.metadata
import itertools

import numpy as np
import pytest

from hexapod_model.extras import MissingExtraError
from hexapod_model.lie import xyz_rpy_to_pose
from hexapod_model.planning import Blocked, carry, robot
from hexapod_model.planning.order import EXACT_UP_TO, best_order
from hexapod_model.planning.timing import line, line_duration

from ..conftest import hexapod


def test_the_bound_between_samples_is_below_the_true_minimum():
    s = np.linspace(0.0, 1.0, 41)
    fine = np.linspace(0.0, 1.0, 40001)
    for freq in (1.0, 3.0, 7.0):
        values, dense = (np.sin(2 * np.pi * freq * x) + 1.2 for x in (s, fine))
        bound = carry.lower_bound(values[:, None], s)[:, 0]
        for k in range(len(s) - 1):
            inside = dense[(fine >= s[k]) & (fine <= s[k + 1])]
            assert bound[k] <= inside.min() + 1e-12


def test_a_carry_out_of_the_stroke_names_the_leg():
    hexa = hexapod("reference")
    start, target = hexa.home_pose, xyz_rpy_to_pose([0.0, 0.0, 0.62, 0.0, 0.0, 0.0])
    with pytest.raises(Blocked, match=r"fixture 'f', \d+% of the way: stroke limit: leg\d_prismatic"):
        carry.carry_path(hexa, start, target, "f", 0.2)


def test_a_carry_samples_densely_enough():
    hexa = hexapod("reference")
    target = xyz_rpy_to_pose([0.01, -0.02, 0.412, 5.0, -3.0, 10.0])
    path = carry.carry_path(hexa, hexa.home_pose, target, "f", 0.2)
    steps = np.diff(path.poses[:, :3, 3], axis=0)
    assert np.linalg.norm(steps, axis=1).max() <= carry.STEP[0] * (1 + 1e-9)
    np.testing.assert_array_equal(path.poses[-1], target)
    assert 0.0 < path.stroke_margin <= np.min(np.minimum(path.readings + 0.16, 0.2 - path.readings)) + 1e-12


def test_a_free_move_is_within_its_limits_and_ends_at_rest():
    vmax, amax = np.array([2.16, 2.16, 3.15, 3.2, 3.2, 3.2]), np.full(6, 2.0)
    qa, qb = np.zeros(6), np.array([1.0, -0.5, 2.0, 0.1, 0.0, -3.0])
    m = line(qa, qb, vmax, amax)
    assert np.all(np.abs(m.qd) <= vmax) and np.all(np.abs(m.qdd) <= amax)
    np.testing.assert_array_equal(m.q[-1], qb)
    assert np.all(m.qd[0] == 0) and np.all(m.qd[-1] == 0)
    assert m.t[-1] == pytest.approx(line_duration(qa, qb, vmax, amax)[0])
    # the distance covered by the profile is the move's: integrate qd
    covered = np.trapezoid(m.qd, m.t, axis=0) if hasattr(np, "trapezoid") else np.trapz(m.qd, m.t, axis=0)
    np.testing.assert_allclose(covered, qb - qa, atol=2e-2)


def test_the_order_is_exact_for_a_few_and_greedy_beyond():
    rng = np.random.default_rng(3)
    n = 5
    start, between, back = rng.uniform(1, 5, n), rng.uniform(1, 5, (n, n)), rng.uniform(1, 5, n)

    def cost(o):
        return start[o[0]] + back[o[-1]] + sum(between[a, b] for a, b in itertools.pairwise(o))

    order, method = best_order(start, between, back)
    assert method == "exact"
    assert cost(order) == min(cost(o) for o in itertools.permutations(range(n)))
    n = EXACT_UP_TO + 1
    order, method = best_order(rng.uniform(1, 5, n), rng.uniform(1, 5, (n, n)), rng.uniform(1, 5, n))
    assert method == "greedy" and sorted(order) == list(range(n))


def test_without_example_robot_data_the_planner_names_the_extra(monkeypatch):
    real = importlib.metadata.distribution

    def missing(name: str):
        if name == "example-robot-data":
            raise importlib.metadata.PackageNotFoundError(name)
        return real(name)

    monkeypatch.setattr(importlib.metadata, "distribution", missing)
    robot.ur10_models.cache_clear()
    try:
        with pytest.raises(MissingExtraError, match=r"example-robot-data is not installed .*hexapod_model\[plan\]"):
            robot.Arm.load()
    finally:
        monkeypatch.undo()
        robot.ur10_models.cache_clear()


def test_the_sampled_rates_bound_the_rates_between_samples(monkeypatch):
    """Ten times denser samples find no leg rate above SAFETY times the one the planner's samples give."""
    hexa = hexapod("reference")
    target = xyz_rpy_to_pose([0.01, -0.02, 0.412, 5.0, -3.0, 10.0])
    coarse = carry.carry_path(hexa, hexa.home_pose, target, "f", 0.2)
    monkeypatch.setattr(carry, "STEP", (carry.STEP[0] / 10, carry.STEP[1] / 10))
    fine = carry.carry_path(hexa, hexa.home_pose, target, "f", 0.2)

    def rate(path):
        return np.max(np.abs(np.diff(path.readings, axis=0)) / np.diff(path.s)[:, None], axis=0)

    assert np.all(rate(fine) <= carry.SAFETY * rate(coarse))
    assert fine.stroke_margin >= coarse.stroke_margin - 1e-12  # the coarse bound is below the finer one
