"""Targets against the machine's body: a collision, a joint beyond its cone or a pose outside the envelope is refused.

Every way a target arrives goes through :func:`~hexapod_model.service.targets.target.reachable`:
a single target, a recipe, its activation, a stored target at start-up. The refusal's figures
(the pair and the clearance, the joint and its angle, the envelope's axis) are checked against
:meth:`~hexapod_model.Hexapod.clearance`, :func:`~hexapod_model.kinematics.cones.check_cones` and
the geometry's envelope, computed here independently.
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.geometry import load_geometry
from hexapod_model.kinematics.cones import check_cones
from hexapod_model.lie import matrix_to_rpy
from hexapod_model.service import Changeover, PoseRecord, Store
from hexapod_model.service.targets.guidance import guidance
from hexapod_model.service.targets.target import TargetError, parse_pose, recipe_from_json, target_from_json

from ..conftest import hexapod

ROOT = Path(__file__).resolve().parents[2]
THICK = ROOT / "docs" / "geometries" / "thick_legs.toml"
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}
FREE = {"x": 0.0, "y": 0.0, "z": 0.4, "roll": 0.0, "pitch": 0.0, "yaw": 40.0}  # thick legs 4 mm apart
TWIST = {**FREE, "yaw": 75.0}  # thick legs 2 and 3 overlap


@functools.cache
def thick() -> hm.Hexapod:
    return hm.Hexapod.load(THICK)


def body(pose: dict) -> dict:
    return {"pose": dict(pose), "tolerance": TOL}


def assert_names_the_collision(exc: TargetError, hexa: hm.Hexapod, pose: dict, field: str) -> None:
    """The refusal names the pair, the clearance (mm) and min_clearance (mm) that the clearance query gives."""
    truth = hexa.clearance(parse_pose(pose))
    assert truth.collision  # the test's pose is in collision by the query itself
    d = exc.details
    assert exc.field == field and d["limit"] == "collision"
    assert tuple(d["pair"]) == truth.pair
    assert d["clearance_mm"] == pytest.approx(truth.distance * 1e3, abs=1e-9)
    assert d["min_clearance_mm"] == truth.min_clearance * 1e3
    message = str(exc)
    assert "\n" not in message and "in collision" in message and f"{truth.pair[0]} - {truth.pair[1]}" in message
    assert f"{truth.distance * 1e3:.3f} mm" in message and "min_clearance" in message


def test_a_target_in_collision_is_refused_naming_the_pair_and_the_clearance():
    with pytest.raises(TargetError) as info:
        target_from_json(body(TWIST), "right", thick(), "anna", 1.0)
    assert_names_the_collision(info.value, thick(), TWIST, "pose")


def test_a_free_target_carries_its_clearance():
    target = target_from_json(body(FREE), "right", thick(), "anna", 1.0)
    truth = thick().clearance(target.pose)
    assert not truth.collision and target.clearance is not None
    assert target.clearance["distance_mm"] == pytest.approx(truth.distance * 1e3, abs=1e-9)
    assert tuple(target.clearance["pair"]) == truth.pair and target.clearance["collision"] is False


def _beyond_cone(hexa: hm.Hexapod) -> np.ndarray:
    """A pose within the stroke and joint limits whose joints exceed a cone (searched in a seeded box)."""
    free = hm.Hexapod.from_preset("reference", check_body=False)
    for T in box_poses(hexa.home_pose, 400, 3, 0.1, 60.0):
        sol = free.inverse(T, check=False)
        if sol.converged and not check_cones(free.closed_loop, free.geometry, sol.q).within:
            return T
    raise AssertionError("no pose beyond a cone found")


def test_a_target_beyond_a_joint_cone_names_the_joint_and_the_angle_against_the_limit():
    hexa = hexapod("reference")
    T = _beyond_cone(hexa)
    xyz, rpy = T[:3, 3], np.degrees(matrix_to_rpy(T[:3, :3]))
    pose = dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), map(float, [*xyz, *rpy])))
    with pytest.raises(TargetError) as info:
        target_from_json(body(pose), "right", hexa, "anna", 1.0)
    d = info.value.details
    cones = check_cones(hexa.closed_loop, hexa.geometry, hexa.inverse(parse_pose(pose), check=False).q)
    beyond = np.argwhere(cones.angles > cones.limits)
    assert d["limit"] == "cone_limit" and d["angle_deg"] > d["cone_deg"]
    leg, end = d["joint"].split()
    assert [int(leg.removeprefix("leg")) - 1, ("base", "platform").index(end)] in beyond.tolist()
    k = (int(leg.removeprefix("leg")) - 1, ("base", "platform").index(end))
    assert d["angle_deg"] == pytest.approx(math.degrees(cones.angles[k]), abs=1e-9)
    assert d["cone_deg"] == pytest.approx(math.degrees(cones.limits[k]), abs=1e-9)
    assert f"{d['joint']} joint deflected" in str(info.value) and "cone half-angle" in str(info.value)


def test_a_target_outside_the_operating_envelope_names_the_axis_and_the_half_width():
    geometry = replace(load_geometry(THICK), envelope=(0.05, 0.05, 0.05, 0.3, 0.3, 0.5))  # yaw +-28.6 deg
    hexa = hm.Hexapod.from_geometry(geometry)
    inside = target_from_json(body({**FREE, "yaw": 25.0}), "right", hexa, "anna", 1.0)
    assert inside.clearance is not None
    with pytest.raises(TargetError) as info:
        target_from_json(body(FREE), "right", hexa, "anna", 1.0)  # yaw 40 deg: the stroke and cones allow it
    d = info.value.details
    assert hexa.inverse(parse_pose(FREE)).converged  # refused by the envelope alone
    assert d == {"limit": "envelope", "axis": "yaw", "offset": pytest.approx(40.0, abs=1e-9), "unit": "deg",
                 "half_width": pytest.approx(math.degrees(0.5), abs=1e-12)}  # fmt: skip
    assert "outside the operating envelope: yaw +40.000 deg" in str(info.value)


def test_a_recipe_with_a_target_in_collision_is_refused_naming_its_fixture():
    hexapods = {"left": thick(), "right": thick()}
    with pytest.raises(TargetError) as info:
        recipe_from_json({"targets": {"left": body(FREE), "right": body(TWIST)}}, "bracket", hexapods, "anna", 1.0)
    assert_names_the_collision(info.value, thick(), TWIST, "targets.right.pose")


def _record(name: str, q: np.ndarray | None = None, T: np.ndarray | None = None) -> PoseRecord:
    return PoseRecord(name, 1.0, [0.0] * 6, None, "no_data", [], 0, "moving", False, None, None, None, None, T, q)


def _changeover(store: Store, hexa: hm.Hexapod) -> Changeover:
    cycles = {name: SimpleNamespace(target=None, last=_record(name)) for name in ("left", "right")}
    return Changeover(store, {"left": hexa, "right": hexa}, cycles)  # type: ignore[arg-type]


def test_the_changeover_refuses_a_target_in_collision_and_stores_nothing(tmp_path):
    store = Store(tmp_path / "s.sqlite")
    changeover = _changeover(store, thick())
    with pytest.raises(TargetError) as info:
        changeover.set_target("right", body(TWIST), "anna")
    assert_names_the_collision(info.value, thick(), TWIST, "pose")
    assert changeover.target("right") is None and store.targets.current_targets() == {}
    with pytest.raises(TargetError, match="targets.right.pose"):
        changeover.put_recipe("bracket", {"targets": {"right": body(TWIST)}}, "anna")
    assert store.targets.recipes() == {}
    store.close()


def test_activating_a_stored_recipe_in_collision_and_a_stored_target_in_collision_are_refused(tmp_path):
    """A store written for thin legs, read with thick ones (the geometry changed): nothing in collision is used."""
    store = Store(tmp_path / "s.sqlite")
    thin = _changeover(store, hexapod("reference"))
    thin.put_recipe("bracket", {"targets": {"left": body(FREE), "right": body(TWIST)}}, "anna")
    thin.set_target("right", body(TWIST), "anna")
    changeover = _changeover(store, thick())
    assert changeover.target("right") is None and "in collision" in changeover.problems["right"]
    assert "in collision" in changeover.guidance("right")["target_problem"]
    with pytest.raises(TargetError) as info:
        changeover.activate("bracket", "bo")
    assert_names_the_collision(info.value, thick(), TWIST, "targets.right.pose")
    assert changeover.target("left") is None and store.targets.active() is None
    assert "in collision" in changeover.recipes()["recipes"]["bracket"]["problem"]
    store.close()


def test_guidance_carries_the_clearance_of_the_pose_and_of_the_target(tmp_path):
    hexa = thick()
    target = target_from_json(body(FREE), "right", hexa, "anna", 1.0)
    sol = hexa.inverse(parse_pose(TWIST), check=False)  # a measured pose in collision
    g = guidance(_record("right", sol.q, sol.pose), target, clearance={"distance_mm": -1.0})
    assert g["clearance"] == {"distance_mm": -1.0} and g["target_clearance"] == target.clearance
    assert guidance(_record("right"), None)["clearance"] is None
    store = Store(tmp_path / "s.sqlite")
    changeover = _changeover(store, hexa)
    changeover.set_target("right", body(FREE), "anna")
    changeover.cycles["right"].last = _record("right", sol.q, sol.pose)
    g = changeover.guidance("right")
    truth = hexa.clearance(sol.q)
    assert g["clearance"]["collision"] is True and tuple(g["clearance"]["pair"]) == truth.pair
    assert g["clearance"]["distance_mm"] == pytest.approx(truth.distance * 1e3, abs=1e-9)
    assert g["clearance"]["min_clearance_mm"] == truth.min_clearance * 1e3
    assert g["target_clearance"]["collision"] is False
    assert g["target_clearance"]["distance_mm"] == pytest.approx(hexa.clearance(target.pose).distance * 1e3, abs=1e-9)
    assert changeover.guidance("left")["clearance"] is None  # no pose: nothing measured
    store.close()


def test_a_model_without_collision_bodies_has_no_clearance_and_its_targets_are_set(tmp_path):
    urdf = tmp_path / "bare.urdf"
    text = hm.Hexapod.from_preset("reference").closed_loop.urdf_xml
    assert "<collision" in text
    urdf.write_text(re.sub(r"<collision\b.*?</collision>", "", text, flags=re.S))
    with pytest.raises(hm.UrdfError, match="check_body=False"):  # a body check that cannot run is said
        hm.Hexapod.load(urdf)
    hexa = hm.Hexapod.load(urdf, check_body=False)
    target = target_from_json(body(FREE), "right", hexa, "anna", 1.0)
    assert target.clearance is None


def test_a_hexapod_whose_solves_skip_the_body_check_still_has_its_targets_checked():
    unchecked = hm.Hexapod.load(THICK, check_body=False)
    assert unchecked.inverse(parse_pose(TWIST)).converged  # the solve alone accepts it
    with pytest.raises(TargetError) as info:
        target_from_json(body(TWIST), "right", unchecked, "anna", 1.0)
    assert_names_the_collision(info.value, unchecked, TWIST, "pose")
    free = hm.Hexapod.from_preset("reference", check_body=False)
    T = _beyond_cone(free)
    xyz, rpy = T[:3, 3], np.degrees(matrix_to_rpy(T[:3, :3]))
    pose = dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), map(float, [*xyz, *rpy])))
    with pytest.raises(TargetError, match="beyond a joint cone") as cone:
        target_from_json(body(pose), "right", free, "anna", 1.0)
    assert cone.value.details["limit"] == "cone_limit"
