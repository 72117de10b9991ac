"""Targets and recipes: validation (one line naming the field), workspace refusal, the store's tables and migration."""

from __future__ import annotations

import json
import math
import sqlite3
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from hexapod_model.service import Changeover, PoseRecord, Store, UnknownError
from hexapod_model.service.store.target_tables import SCHEMA_VERSION
from hexapod_model.service.targets.target import TargetError, parse_pose, recipe_from_json, target_from_json

from ..conftest import hexapod

HOLD = {"x": 0.01, "y": -0.02, "z": 0.41, "roll": 5.0, "pitch": -3.0, "yaw": 10.0}
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}


def body(**pose):
    return {"pose": {**HOLD, **pose}, "tolerance": TOL}


def test_target_pose_from_rpy_and_quaternion_agree_and_readings_are_the_inverse_kinematics():
    hexa = hexapod("reference")
    a = target_from_json(body(), "right", hexa, "anna", 1.0)
    q = a.to_json()["pose"]
    b = target_from_json(
        {"pose": {k: q[k] for k in ("x", "y", "z", "qx", "qy", "qz", "qw")}, "tolerance": TOL}, "right", hexa, "bo", 2.0
    )
    assert np.allclose(a.pose, b.pose, atol=1e-12)
    assert np.allclose(a.readings, hexa.inverse(a.pose).lengths, atol=1e-12)
    assert a.tolerance.translation == pytest.approx(1e-4) and a.tolerance.rotation == pytest.approx(math.radians(0.05))
    assert a.to_json()["pose"]["yaw"] == pytest.approx(10.0) and a.set_by == "anna"


@pytest.mark.parametrize(
    "data, field",
    [
        ({"pose": HOLD}, "tolerance"),
        ({"tolerance": TOL}, "pose"),
        ({**body(), "colour": "red"}, "colour"),
        (body(z="high"), "pose.z"),
        (body(x=float("nan")), "pose.x"),
        (body(qw=1.0), "pose"),  # both rotation forms
        ({"pose": {"x": 0, "y": 0, "z": 0.4, "qx": 0, "qy": 0, "qz": 0, "qw": 0.9}, "tolerance": TOL}, "pose.qw"),
        ({"pose": HOLD, "tolerance": {"translation_mm": 0.0, "rotation_deg": 0.1}}, "tolerance.translation_mm"),
        ({"pose": HOLD, "tolerance": {"translation_mm": 0.1}}, "tolerance.rotation_deg"),
        ([1, 2], "<body>"),
    ],
)
def test_a_bad_target_is_one_line_naming_the_field(data, field):
    with pytest.raises(TargetError) as info:
        target_from_json(data, "right", hexapod("reference"), "anna", 1.0)
    assert info.value.field == field and "\n" not in str(info.value) and repr(field) in str(info.value)


def test_a_target_outside_the_workspace_names_the_leg_and_the_limit():
    with pytest.raises(TargetError) as info:
        target_from_json(body(z=0.6), "right", hexapod("reference"), "anna", 1.0)
    message = str(info.value)
    assert info.value.field == "pose" and "outside the workspace" in message
    assert "stroke limit" in message and "leg" in message and "[-0.16, 0.2] m" in message


def test_a_recipe_names_known_fixtures_only():
    hexapods = {"left": hexapod("reference"), "right": hexapod("reference")}
    recipe = recipe_from_json({"targets": {"left": body(), "right": body(z=0.42)}}, "bracket", hexapods, "anna", 3.0)
    assert set(recipe.targets) == {"left", "right"} and recipe.targets["right"].recipe == "bracket"
    with pytest.raises(TargetError, match="targets.middle"):
        recipe_from_json({"targets": {"middle": body()}}, "bracket", hexapods, "anna", 3.0)
    with pytest.raises(TargetError, match="targets.left.pose.z"):
        recipe_from_json({"targets": {"left": body(z=None)}}, "bracket", hexapods, "anna", 3.0)


def test_parse_pose_is_rz_ry_rx_in_degrees():
    T = parse_pose({"x": 1.0, "y": 2.0, "z": 3.0, "roll": 0.0, "pitch": 0.0, "yaw": 90.0})
    assert np.allclose(T[:3, :3] @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]) and np.allclose(T[:3, 3], [1, 2, 3])


def test_targets_recipes_and_activations_are_stored_with_who_and_when(tmp_path):
    hexa = hexapod("reference")
    store = Store(tmp_path / "s.sqlite")
    t1 = target_from_json(body(), "right", hexa, "anna", 10.0)
    first = store.targets.add_target(t1)
    store.targets.add_target(target_from_json(body(z=0.42), "right", hexa, "bo", 11.0))
    recipe = recipe_from_json({"targets": {"left": body()}}, "bracket", {"left": hexa}, "cy", 12.0)
    store.targets.put_recipe(recipe)
    store.targets.activate(recipe, "dee", 13.0)
    store.close()
    again = Store(tmp_path / "s.sqlite", create=False)
    current = again.targets.current_targets()
    assert current["right"].id > first and current["right"].set_by == "bo" and current["right"].pose[2, 3] == 0.42
    assert current["left"].recipe == "bracket" and current["left"].set_by == "cy"
    assert np.allclose(current["left"].pose, t1.pose, atol=1e-12)
    assert again.targets.active() == ("bracket", "dee", 13.0)
    assert again.targets.recipes()["bracket"][1:] == ("cy", 12.0)
    assert again.targets.clear_target("right", "eve", 14.0) and not again.targets.clear_target("right", "eve", 15.0)
    assert "right" not in again.targets.current_targets()
    sql = "SELECT cleared_by, cleared_at FROM targets WHERE fixture = 'right' ORDER BY id DESC"
    row = again.db.execute(sql).fetchone()
    assert row == ("eve", 14.0)
    again.close()


V1_SCHEMA = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE lock_events (
    id INTEGER PRIMARY KEY AUTOINCREMENT, fixture TEXT NOT NULL, t REAL NOT NULL,
    x REAL NOT NULL, y REAL NOT NULL, z REAL NOT NULL, qx REAL NOT NULL, qy REAL NOT NULL, qz REAL NOT NULL,
    qw REAL NOT NULL, l1 REAL NOT NULL, l2 REAL NOT NULL, l3 REAL NOT NULL, l4 REAL NOT NULL, l5 REAL NOT NULL,
    l6 REAL NOT NULL, status TEXT NOT NULL, geometry_hash TEXT NOT NULL, q TEXT NOT NULL);
CREATE INDEX lock_events_fixture ON lock_events (fixture, id);
CREATE TABLE samples (
    id INTEGER PRIMARY KEY AUTOINCREMENT, fixture TEXT NOT NULL, t REAL NOT NULL, status TEXT NOT NULL,
    flags TEXT NOT NULL, state TEXT NOT NULL, l1 REAL, l2 REAL, l3 REAL, l4 REAL, l5 REAL, l6 REAL,
    x REAL, y REAL, z REAL, qx REAL, qy REAL, qz REAL, qw REAL);
CREATE INDEX samples_t ON samples (t);
INSERT INTO meta VALUES ('schema_version', '1');
"""


def test_a_version_1_store_is_migrated_in_place_and_keeps_its_locks(tmp_path):
    path = tmp_path / "old.sqlite"
    db = sqlite3.connect(path)
    db.executescript(V1_SCHEMA)
    q = json.dumps([0.5] * 43)
    db.execute(
        "INSERT INTO lock_events (fixture, t, x, y, z, qx, qy, qz, qw, l1, l2, l3, l4, l5, l6, status, geometry_hash,"
        " q) VALUES ('left', 5.0, 0.01, 0.0, 0.4, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 'ok', 'h', ?)",
        (q,),
    )
    db.commit()
    db.close()
    store = Store(path)
    assert SCHEMA_VERSION == 2
    assert store.db.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()[0] == "2"
    old = store.last_lock("left")
    assert old is not None and old.t == 5.0 and old.target_id is None and old.recipe is None
    assert np.array_equal(old.q, [0.5] * 43)
    new = store.add_lock(replace(old, t=6.0, id=None, target_id=7, recipe="bracket"))
    store.targets.add_target(target_from_json(body(), "left", hexapod("reference"), "anna", 1.0))
    store.close()
    again = Store(path, create=False)
    last = again.last_lock("left")
    assert last is not None and last.id == new.id and (last.target_id, last.recipe) == (7, "bracket")
    assert list(again.targets.current_targets()) == ["left"]
    again.close()


def test_a_store_of_a_newer_schema_is_refused(tmp_path):
    store = Store(tmp_path / "s.sqlite")
    store.db.execute("UPDATE meta SET value = '99' WHERE key = 'schema_version'")
    store.close()
    with pytest.raises(Exception, match="schema version 99 is newer"):
        Store(tmp_path / "s.sqlite")


def test_a_target_set_after_the_store_file_was_deleted_is_in_the_file_the_next_start_reads(tmp_path):
    store = Store(tmp_path / "s.sqlite")
    store.targets.add_target(target_from_json(body(), "right", hexapod("reference"), "anna", 1.0))
    (tmp_path / "s.sqlite").unlink()
    second = store.targets.add_target(target_from_json(body(z=0.42), "left", hexapod("reference"), "bo", 2.0))
    store.close()
    again = Store(tmp_path / "s.sqlite", create=False)
    current = again.targets.current_targets()
    assert set(current) == {"right", "left"} and current["left"].id == second
    again.close()


def test_a_stored_target_that_no_longer_solves_is_not_used_and_guidance_says_why(tmp_path):
    store = Store(tmp_path / "s.sqlite")
    good = target_from_json(body(), "right", hexapod("reference"), "anna", 1.0)
    store.targets.add_target(good)
    far = good.pose.copy()
    far[2, 3] = 0.6  # e.g. after a change to a shorter-stroke geometry: outside the workspace now
    store.targets.add_target(replace(good, fixture="left", pose=far))
    record = PoseRecord("left", 1.0, [0.0] * 6, None, "no_data", [], 0, "moving", False, None, None, None, None)
    cycles = {name: SimpleNamespace(target=None, last=record._replace(fixture=name)) for name in ("left", "right")}
    changeover = Changeover(store, {"left": hexapod("reference"), "right": hexapod("reference")}, cycles)  # type: ignore[arg-type]
    assert changeover.target("left") is None and cycles["left"].target is None
    g = changeover.guidance("left")
    assert g["target"] is None and "stroke limit" in g["target_problem"]
    assert changeover.target("right") is not None and cycles["right"].target is changeover.target("right")
    with pytest.raises(UnknownError, match="no fixture 'middle'"):
        changeover.guidance("middle")
    store.close()


def test_listing_the_recipes_solves_each_stored_recipe_once(tmp_path, monkeypatch):
    from hexapod_model.service.changeover import changeover as module

    store = Store(tmp_path / "s.sqlite")
    record = PoseRecord("right", 1.0, [0.0] * 6, None, "no_data", [], 0, "moving", False, None, None, None, None)
    changeover = Changeover(
        store, {"right": hexapod("reference")}, {"right": SimpleNamespace(target=None, last=record)}
    )  # type: ignore[dict-item]
    changeover.put_recipe("bracket", {"targets": {"right": body()}}, by="anna")
    solved: list[str] = []
    original = module.recipe_from_json
    monkeypatch.setattr(module, "recipe_from_json", lambda *a, **k: solved.append(a[1]) or original(*a, **k))
    first = changeover.recipes()
    assert changeover.recipes() == first and solved == ["bracket"]  # the second listing solves nothing
    changeover.put_recipe("bracket", {"targets": {"right": body(z=0.405)}}, by="bob")  # a new row: solved again
    again = changeover.recipes()["recipes"]["bracket"]
    assert solved[-1] == "bracket" and again["set_by"] == "bob" and again != first["recipes"]["bracket"]
    store.close()
