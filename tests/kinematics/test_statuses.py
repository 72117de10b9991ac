"""Statuses that say what happened when no closed configuration is found (docs/solver.md)."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.exceptions import WorkspaceError
from hexapod_model.kinematics.three_six import ThreeSixFK
from hexapod_model.tracking.types import posed

from ..conftest import hexapod


def test_poses_whose_iterate_leaves_the_limits_are_out_of_limits_not_max_iterations():
    """+-200 mm / +-70 deg on the reference preset: Newton ends on a spurious closure outside the
    limits. These were max_iterations; now out_of_limits, flagged not_closed (q closes nothing)."""
    hexa = hexapod("reference")
    poses = box_poses(hexa.home_pose, 300, seed=2, translation=0.2, angle_deg=70)
    for i in (6, 95, 136, 176):
        sol = hexa.inverse(poses[i], check=False)
        assert sol.status == "out_of_limits" and sol.flags == ("not_closed",) and not sol.closed
        assert "no closed configuration found within the limits" in sol.message and " is outside " in sol.message
        assert not posed(sol)  # the tracker takes no pose from it
        with pytest.raises(hm.WorkspaceError, match="^out_of_limits: no closed configuration"):
            hexa.inverse(poses[i])
    batch = hexa.inverse_batch(poses[[6, 95, 136, 176]])
    assert list(batch.status) == ["out_of_limits"] * 4 and batch.flags == (("not_closed",),) * 4


def test_readings_without_an_assembly_are_named_with_the_residual():
    """Random readings within the stroke on the 3-6 preset for which the resultant polynomial has
    no real root: these were max_iterations (a step budget), now not_found or out_of_limits from
    Newton alone, no_assembly with the resultant (forward's answer on a 3-6 hexapod)."""
    hexa = hm.Hexapod.from_preset("3-6")
    hexa.engine.finder.exact = None  # Newton alone
    exact = ThreeSixFK(hexa.geometry)
    rng = np.random.default_rng(0)
    seen = set()
    rows = []
    for _ in range(40):
        readings = rng.uniform(hexa.stroke[:, 0], hexa.stroke[:, 1])
        try:
            if exact.solve_all(readings):
                continue
        except WorkspaceError:  # two legs that cannot meet: no assembly either
            pass
        rows.append(readings)
        assert hexapod("3-6").forward(readings, check=False).status == "no_assembly"
        sol = hexa.forward(readings, check=False)
        seen.add(sol.status)
        assert sol.status in ("not_found", "out_of_limits") and not sol.closed
        assert "no closed configuration found" in sol.message and "residual" in sol.message
    assert seen == {"not_found", "out_of_limits"}
    batch = hexa.forward_batch(np.array(rows))
    assert set(batch.status) <= {"not_found", "out_of_limits"}
    with pytest.raises(hm.ConvergenceError, match="^not_found: no closed configuration found"):
        hexa.forward(rows[[hexa.forward(r, check=False).status for r in rows].index("not_found")])


def test_a_small_step_budget_stays_max_iterations():
    hexa = hexapod("reference")
    T = box_poses(hexa.home_pose, 1, seed=3)[0]
    sol = hexa.inverse(T, max_iter=1, check=False)
    assert sol.status == "max_iterations"
