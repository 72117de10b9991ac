"""Guidance: deviation in the target frame, per-leg changes by inverse kinematics, in_tolerance, lock naming."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.analysis.jacobian import leg_jacobian_local
from hexapod_model.service import FixtureCycle, geometry_hash
from hexapod_model.service.record.pose import pose_record
from hexapod_model.service.record.pose_record import PoseRecord
from hexapod_model.service.targets.guidance import MARGIN_SIGMAS, deviation, guidance
from hexapod_model.service.targets.target import target_from_json

from ..conftest import hexapod
from .helpers import drive, fixture_table, record_pose, service_config, sim_config

HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]
POSE = dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), HOLD))
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}


def shifted(target_pose: np.ndarray, along_mm: np.ndarray) -> np.ndarray:
    """``target_pose`` moved by ``along_mm`` (mm) along the target frame's own axes."""
    T = target_pose.copy()
    T[:3, 3] += T[:3, :3] @ (np.asarray(along_mm) * 1e-3)
    return T


def record_at(T, readings, status="ok", sigma=(0.02, 0.005)):
    flags = [] if status == "ok" else ["jump"]
    sig = {"translation_mm": sigma[0], "rotation_deg": sigma[1]}
    return PoseRecord(
        "right", 1.0, list(readings), pose_record(T), status, flags, 1, "moving", False, sig, 1.0, None, None, T
    )


def test_deviation_is_in_the_targets_frame_and_leg_changes_are_the_inverse_kinematics_differences():
    hexa = hexapod("reference")
    target = target_from_json({"pose": POSE, "tolerance": TOL}, "right", hexa, "anna", 1.0)
    current = shifted(target.pose, [1.2, 0.0, -1.6])  # 2 mm away in the target frame
    readings = hexa.inverse(current).lengths
    g = guidance(record_at(current, readings), target)
    d = g["deviation"]
    assert d["translation_mm"] == pytest.approx(2.0, abs=1e-9)
    assert (d["x_mm"], d["y_mm"], d["z_mm"]) == pytest.approx((1.2, 0.0, -1.6), abs=1e-9)
    assert d["rotation_deg"] == pytest.approx(0.0, abs=1e-9)
    expected = (hexa.inverse(target.pose).lengths - readings) * 1e3
    assert [leg["leg"] for leg in g["legs"]] == [1, 2, 3, 4, 5, 6]
    assert np.allclose([leg["change_mm"] for leg in g["legs"]], expected, atol=1e-6)  # 1 nm
    assert not g["in_tolerance"] and g["target"]["set_by"] == "anna"


def test_for_a_small_error_the_leg_changes_are_the_leg_jacobian_times_the_pose_error():
    """docs/changeover.md: change = J_local(current) xi, xi = log6(T_current^-1 T_target) (platform frame)."""
    hexa = hexapod("reference")
    target = target_from_json({"pose": POSE, "tolerance": TOL}, "right", hexa, "anna", 1.0)
    current = shifted(target.pose, [0.02, -0.01, 0.015])
    current[:3, :3] = current[:3, :3] @ pin.exp3(np.radians([0.01, -0.02, 0.005]))
    sol = hexa.inverse(current)
    J, _ = leg_jacobian_local(hexa, sol.q)
    xi = pin.log6(pin.SE3(current).inverse() * pin.SE3(target.pose)).vector
    changes = [leg["change_mm"] for leg in guidance(record_at(current, sol.lengths), target)["legs"]]
    assert np.allclose(changes, J @ xi * 1e3, atol=1e-4)  # 0.1 um of second-order terms at ~30 um changes


def test_rotation_deviation_per_axis_is_the_rotation_vector_in_the_target_frame():
    T = np.eye(4)
    C = np.eye(4)
    a = math.radians(0.3)
    C[:3, :3] = [[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]]
    d = deviation(C, T)
    assert d["rx_deg"] == pytest.approx(0.3) and d["rotation_deg"] == pytest.approx(0.3) and d["ry_deg"] == 0.0


@pytest.mark.parametrize(
    "offset_mm, status, sigma, expected",
    [
        (0.0, "ok", (0.02, 0.005), True),
        (0.05, "ok", (0.02, 0.005), True),  # 0.05 + 2 x 0.02 = 0.09 <= 0.1
        (0.07, "ok", (0.02, 0.005), False),  # 0.07 + 0.04 > 0.1: not certainly within
        (0.0, "ok", (0.06, 0.005), False),  # sigma alone too large for the tolerance
        (0.0, "flagged", (0.02, 0.005), False),
        (0.0, "ok", (0.02, 0.03), False),  # 2 x 0.03 deg > 0.05 deg
    ],
)
def test_in_tolerance_only_for_an_ok_pose_within_tolerance_by_its_sigma(offset_mm, status, sigma, expected):
    assert MARGIN_SIGMAS == 2.0
    hexa = hexapod("reference")
    target = target_from_json({"pose": POSE, "tolerance": TOL}, "right", hexa, "anna", 1.0)
    current = shifted(target.pose, [offset_mm, 0.0, 0.0])
    rec = record_at(current, hexa.inverse(current).lengths, status, sigma)
    assert guidance(rec, target)["in_tolerance"] is expected


def test_a_record_without_a_pose_gives_legs_but_no_deviation():
    hexa = hexapod("reference")
    target = target_from_json({"pose": POSE, "tolerance": TOL}, "right", hexa, "anna", 1.0)
    rec = record_at(np.eye(4), [None] * 6, "silent_leg")
    rec = rec._replace(pose=None, sigma=None, transform=None)
    g = guidance(rec, target)
    assert g["deviation"] is None and not g["in_tolerance"] and g["legs"][0]["change_mm"] is None
    assert g["legs"][0]["target_mm"] == pytest.approx(target.readings[0] * 1e3)
    assert guidance(rec, None)["legs"] == [] and record_pose(rec) is None


def test_a_lock_within_the_target_names_it_and_one_outside_does_not(tmp_path):
    service = service_config(tmp_path, [fixture_table("right", 1)])
    sim = sim_config(service, [{"name": "right", "rate": 100.0, "hold": HOLD}])
    hexa = hexapod("reference")
    near = target_from_json({"pose": POSE, "tolerance": TOL}, "right", hexa, "anna", 1.0)
    far = target_from_json({"pose": {**POSE, "z": 0.412}, "tolerance": TOL}, "right", hexa, "anna", 1.0)
    for target, met in ((replace(near, id=4, recipe="bracket"), True), (replace(far, id=5), False)):
        cycle = FixtureCycle(service.fixture("right"), hexa, geometry_hash(hexa), None, 1.0e9)
        cycle.target = target
        events: list = []
        original = cycle.lock_stored
        cycle.lock_stored = lambda n, e, f=original, seen=events: (seen.append(e), f(n, e))  # type: ignore[method-assign]
        drive(service, sim, 1.6, cycle=cycle)
        assert events, "no lock"
        assert (events[0].target_id, events[0].recipe) == ((4, "bracket") if met else (None, None))
