"""The compiled readings-path follower (kinematics/follow.py) gives what the Python one gives."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.sensitivity import SensitivityEvaluator
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics import certificate as assembly

from ..conftest import PRESET_NAMES, assert_same_message, limits_only

EPS = float(np.finfo(float).eps)
AMBIGUOUS = {"intersecting", "spherical", "3-6", "guideway"}  # presets whose sample below holds ambiguous rows


def readings(hexa: hm.Hexapod) -> np.ndarray:
    """Readings of seeded box poses (+-50 mm, +-25 deg) and beyond (x2.2, x2.8, x3.5) that IK reaches."""
    poses = np.concatenate(
        [
            box_poses(hexa.home_pose, 250, seed=60 + k, translation=0.05 * s, angle_deg=25 * s)
            for k, s in enumerate((1.0, 2.2, 2.8, 3.5))
        ]
    )
    inv = hexa.inverse_batch(poses)
    return inv.lengths[inv.converged]


def solve_all(hexa: hm.Hexapod, rows: np.ndarray) -> tuple[list[hm.Solution], int]:
    """Each row cold from home and warm from the previous row's solution; and how many were followed."""
    followed = []
    follower = assembly._follow_compiled

    def spy(*args):
        followed.append(1)
        return follower(*args)

    out, guess = [], None
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(assembly, "_follow_compiled", spy)
        for x in rows:
            out.append(hexa.forward(x, check=False))
            sol = hexa.forward(x, guess, check=False, prove=False)  # the followers' answers, not the step's proof
            out.append(sol)
            guess = sol if sol.converged else guess
    return out, len(followed)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_compiled_follower_matches_python_follower(name, monkeypatch):
    hexa = limits_only(name)  # readings far out, beyond the cones too: the followers' paths
    rows = readings(hexa)
    compiled, followed = solve_all(hexa, rows)
    monkeypatch.setattr(assembly, "_follow_compiled", assembly._follow)  # the Python follower
    python, again = solve_all(hexa, rows)
    assert followed == again and followed > 50  # rows whose path takes several substeps
    # two code paths agree to 1e-12 (m, rad), or near a singularity to the rounding a solve's condition number
    # amplifies (the forward error bound kappa * eps: the far rows hold kappas thousands of times home's)
    sensitivity = SensitivityEvaluator(hexa, hexa.base_radius)
    statuses = set()
    for a, b in zip(python, compiled):
        assert (a.status, a.flags, a.det_sign, a.iterations) == (b.status, b.flags, b.det_sign, b.iterations)
        if not a.closed and a.status != "no_assembly":  # the 20th iterate of a diverging Newton: rounding grows
            assert_same_message(a.message, b.message, numbers=False)
            continue
        assert_same_message(a.message, b.message)
        atol = max(1e-12, 4 * EPS * sensitivity.evaluate(a.q).condition_number)
        np.testing.assert_allclose(b.pose, a.pose, rtol=0, atol=atol)
        assert len(a.candidates) == len(b.candidates)
        for ca, cb in zip(a.candidates, b.candidates):
            np.testing.assert_allclose(cb, ca, rtol=0, atol=1e-12)
        statuses.add(a.status)
    assert "converged" in statuses
    assert name not in AMBIGUOUS or "ambiguous_assembly" in statuses
