"""The body check of the solves: cone_limit and collision statuses and flags, the operating envelope."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.presets import PRESETS, get_preset
from hexapod_model.exceptions import WorkspaceError
from hexapod_model.kinematics.clearance import ClearanceQuery
from hexapod_model.kinematics.cones import check_cones
from hexapod_model.kinematics.newton.solver import STATUSES
from hexapod_model.lie import pose_distance, xyz_rpy_to_pose

ROOT = Path(__file__).resolve().parents[2]
THICK = ROOT / "docs" / "geometries" / "thick_legs.toml"
TWIST = xyz_rpy_to_pose([0.0, 0.0, 0.40, 0.0, 0.0, 85.0])  # 85 deg yaw about home: legs 2 and 3 overlap


@pytest.fixture(scope="module")
def thick() -> hm.Hexapod:
    return hm.Hexapod.load(THICK, compiled=False)


def test_statuses_are_known():
    assert "collision" in STATUSES and "cone_limit" in STATUSES


def test_inverse_of_a_pose_in_collision_names_the_pair(thick):
    sol = thick.inverse(TWIST, check=False)
    assert sol.status == "collision"
    assert "leg2" in sol.message and "leg3" in sol.message
    with pytest.raises(WorkspaceError, match="collision: leg2"):
        thick.inverse(TWIST)


def test_forward_flags_a_pose_in_collision(thick):
    near = thick.inverse(xyz_rpy_to_pose([0.0, 0.0, 0.40, 0.0, 0.0, 84.0]), check=False)
    truth = thick.inverse(TWIST, check=False)
    sol = thick.forward(truth.lengths, guess=near)  # a measured pose: converged, flagged, not raised
    assert sol.status == "converged" and "collision" in sol.flags
    assert pose_distance(sol.pose, TWIST, 0.25) < 1e-9
    assert "leg2" in sol.message and "leg3" in sol.message


def test_check_body_off_leaves_the_bare_answer():
    hexa = hm.Hexapod.load(THICK, compiled=False)
    hexa.check_body = False
    assert hexa.inverse(TWIST, check=False).status == "converged"
    hexa.check_body = True
    assert hexa.inverse(TWIST, check=False).status == "collision"


def test_batches_carry_the_body_check(thick):
    near = thick.inverse(xyz_rpy_to_pose([0.0, 0.0, 0.40, 0.0, 0.0, 84.0]), check=False)
    poses = np.stack([thick.home_pose, TWIST])
    inv = thick.inverse_batch(poses)
    assert list(inv.status) == ["converged", "collision"]
    assert "leg2" in inv.messages[1] and "leg3" in inv.messages[1]
    truth = thick.inverse(TWIST, check=False)  # the row in collision has no lengths in the batch
    fwd = thick.forward_batch(np.stack([truth.lengths, truth.lengths]), guess=near, warm=True)
    assert list(fwd.status) == ["converged", "converged"]
    assert all("collision" in f for f in fwd.flags) and "leg2" in fwd.messages[1]
    home = thick.forward_batch(np.zeros((2, 6)))
    assert list(home.status) == ["converged", "converged"] and home.flags == ((), ())


def _thick_preset(name: str) -> hm.Hexapod:
    """The preset with legs thick enough to touch at home (half the smallest gap between two legs added)."""
    base = get_preset(name)
    bare = hm.Hexapod.from_geometry(base, compiled=False)
    query = ClearanceQuery(bare.closed_loop, compiled=False)
    leg = re.compile(r"leg\d_(rod|cylinder|strut)$")
    distances = query.all_pairs(bare.q_home)
    gap = min(d for d, (a, b) in zip(distances, query.pairs) if leg.match(a) and leg.match(b) and a[:4] != b[:4])
    legs = tuple(replace(leg, leg_radius=None) for leg in base.legs)
    radius = base.leg_radius + max(gap, 0.0) / 2 + 0.005
    housing = max(base.housing_radius, radius + 0.001)
    thick = replace(base, legs=legs, leg_radius=radius, housing_radius=housing)
    return hm.Hexapod.from_geometry(thick, compiled=False)


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_each_preset_with_thick_legs_is_in_collision_at_home(name):
    hexa = _thick_preset(name)
    inv = hexa.inverse(hexa.home_pose, check=False)
    assert inv.status == "collision"
    assert inv.message.count("leg") >= 2
    fwd = hexa.forward(np.zeros(len(hexa.reading_names)), check=False)  # 7 or 8 readings with redundant sensors
    assert "collision" in fwd.flags


def _beyond_cone(hexa: hm.Hexapod) -> np.ndarray:
    """A pose within the stroke and joint limits whose joints exceed a cone (searched in a seeded box)."""
    hexa.check_body = False
    try:
        for T in box_poses(hexa.home_pose, 400, 3, 0.1, 60.0):
            sol = hexa.inverse(T, check=False)
            if sol.converged and not check_cones(hexa.closed_loop, hexa.geometry, sol.q).within:
                return T
    finally:
        hexa.check_body = True
    raise AssertionError("no pose beyond a cone found")


@pytest.mark.parametrize("name", ["reference", "3-6"])
def test_a_pose_beyond_a_cone_is_cone_limit(name):
    hexa = hm.Hexapod.from_preset(name, compiled=False)
    T = _beyond_cone(hexa)
    sol = hexa.inverse(T, check=False)
    assert sol.status == "cone_limit"
    assert sol.message.startswith("leg") and "joint deflected" in sol.message
    with pytest.raises(WorkspaceError, match=r"^cone_limit: leg\d (base|platform) joint deflected"):
        hexa.inverse(T)


def _cold_counts(hexa: hm.Hexapod, n: int) -> tuple[int, int, int]:
    """(solves, ambiguous, wrong converged) of cold solves of the readings of ``n`` seeded box poses."""
    solves = ambiguous = wrong = 0
    for T in box_poses(hexa.home_pose, n, 11, 0.1, 40.0):
        truth = hexa.inverse(T, check=False)
        if not truth.converged:
            continue
        solves += 1
        sol = hexa.forward(truth.lengths, check=False)
        ambiguous += sol.status == "ambiguous_assembly"
        wrong += sol.status == "converged" and pose_distance(sol.pose, T, hexa.base_radius) > 1e-6
    return solves, ambiguous, wrong


def test_the_limits_decide_the_3_6_assembly():
    hexa = hm.Hexapod.from_preset("3-6", compiled=False)
    solves, ambiguous, wrong = _cold_counts(hexa, 60)
    assert solves >= 20
    assert wrong == 0
    assert ambiguous <= 0.25 * solves  # measured: see docs/solver.md (under 15 % at +-100 mm / +-40 deg)


def test_the_envelope_decides_between_assemblies():
    slim = {"leg_radius": 1e-4, "housing_radius": 2e-4, "plate_thickness": 1e-4}
    plates = {"base_plate_radius": 1e-3, "platform_plate_radius": 1e-3}
    # no cone, hair-thin bodies: the rival assemblies (tilted by 46-170 deg) compete
    base = replace(get_preset("3-6"), platform_cone=None, **slim, **plates)
    bare = hm.Hexapod.from_geometry(base, compiled=False)
    boxed = hm.Hexapod.from_geometry(replace(base, envelope=(0.1, 0.1, 0.1, 0.7, 0.7, 0.7)), compiled=False)
    decided = 0
    for T in box_poses(bare.home_pose, 40, 5, 0.1, 40.0):
        truth = bare.inverse(T, check=False)
        if not truth.converged:
            continue
        a, b = bare.forward(truth.lengths, check=False), boxed.forward(truth.lengths, check=False)
        if b.status == "converged":
            assert pose_distance(b.pose, T, bare.base_radius) < 1e-6
        if b.status == "ambiguous_assembly":
            assert all(boxed.engine.body.within_envelope(P) for P in b.candidates)
        decided += a.status == "ambiguous_assembly" and b.status == "converged"
    assert decided > 0


def test_the_tracker_flags_a_path_through_a_collision(thick):
    from hexapod_model.tracking.tracker import Tracker

    hexa = hm.Hexapod.load(THICK)  # compiled: the tracker's warm path
    yaws = np.linspace(30.0, 85.0, 111)
    poses = [xyz_rpy_to_pose([0.0, 0.0, 0.40, 0.0, 0.0, y]) for y in yaws]
    inside = [thick.clearance(T).collision for T in poses]
    assert not inside[0] and inside[-1]
    tracker = Tracker(hexa, "none", initial=hexa.inverse(poses[0]))
    flagged = []
    for T in poses:
        r = tracker.step(hexa.inverse(T, check=False).lengths)
        assert not r.failed
        flagged.append("collision" in r.flags)
    assert flagged == inside


def test_legs_sharing_a_base_joint_are_not_a_collision():
    """Jakobović and Jelenković's 3-3 model: two legs meet at each base and each platform point."""
    hexa = hm.Hexapod.load(ROOT / "docs" / "geometries" / "seed002_model1.toml", compiled=False)
    assert not hexa.clearance(hexa.q_home).collision
    assert hexa.inverse(hexa.home_pose, check=False).status == "converged"
