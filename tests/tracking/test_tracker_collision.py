"""A tracked path through a collision: the samples whose clearance is below min_clearance are flagged ``collision``.

The thick-legs geometry (docs/geometries/thick_legs.toml) twists about its vertical axis from a
free pose into one where legs 2 and 3 overlap and back; which samples are in collision is
decided here by :meth:`~hexapod_model.Hexapod.clearance` of the true configuration, not by the
tracker.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import hexapod_model as hm
from hexapod_model.lie import xyz_rpy_to_pose
from hexapod_model.tracking.tracker import Tracker

ROOT = Path(__file__).resolve().parents[2]
THICK = ROOT / "docs" / "geometries" / "thick_legs.toml"


def test_a_path_through_a_collision_is_flagged_on_the_samples_in_collision():
    hexa = hm.Hexapod.load(THICK)
    yaws = np.concatenate([np.arange(56.0, 74.0, 1.5), np.arange(74.0, 55.0, -1.5)])  # deg, in and out
    truth = [hexa.inverse(xyz_rpy_to_pose([0.0, 0.0, 0.4, 0.0, 0.0, y]), check=False) for y in yaws]
    colliding = [hexa.clearance(s.q).collision for s in truth]
    assert any(colliding) and not all(colliding) and not colliding[0] and not colliding[-1]
    tracker = Tracker(hexa, "eq22", initial=truth[0])
    for sol, hit in zip(truth, colliding):
        r = tracker.step(sol.lengths)
        assert r.status == "ok", (r.status, r.flags)
        assert r.solution is not None
        assert np.allclose(r.solution.pose, sol.pose, atol=1e-9)  # the path itself, not another assembly
        assert ("collision" in r.flags) == hit, (float(np.degrees(np.arctan2(sol.pose[1, 0], sol.pose[0, 0]))), r.flags)
