"""A target in collision over HTTP and from ``hexapod fixture``: ``422`` naming the pair; the guidance's clearance.

A service of one fixture with thick legs (docs/geometries/thick_legs.toml: a yaw twist makes
legs 2 and 3 touch); every figure of the ``422`` body is checked against
:meth:`~hexapod_model.Hexapod.clearance` of the same pose.
"""

from __future__ import annotations

import functools
import http.client
import json
from pathlib import Path

import pytest

import hexapod_model as hm
from hexapod_model.cli.main import main
from hexapod_model.service import FixtureService, Store, load_config
from hexapod_model.service.targets.target import parse_pose, recipe_from_json

from ..conftest import hexapod
from .test_http import TOKEN, token_file

ROOT = Path(__file__).resolve().parents[2]
THICK = ROOT / "docs" / "geometries" / "thick_legs.toml"
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}
FREE = {"x": 0.0, "y": 0.0, "z": 0.4, "roll": 0.0, "pitch": 0.0, "yaw": 40.0}  # thick legs 4 mm apart
TWIST = {**FREE, "yaw": 75.0}  # thick legs 2 and 3 overlap
AUTH = {"Authorization": f"Bearer {TOKEN}", "X-Operator": "anna"}


@functools.cache
def thick() -> hm.Hexapod:
    return hm.Hexapod.load(THICK)


def config_file(tmp_path: Path) -> Path:
    token_file(tmp_path)
    text = f"""
[bus]
interface = "virtual"
channel = "body-{tmp_path.name}"

[store]
path = "store.sqlite"

[http]
host = "127.0.0.1"
port = 0
token_file = "fixture.token"

[[fixtures]]
name = "right"
hexapod = "{THICK}"
can_ids = [0x181, 0x182, 0x183, 0x184, 0x185, 0x186]
"""
    path = tmp_path / "fixture.toml"
    path.write_text(text)
    return path


def call(address, method, path, body=None):
    c = http.client.HTTPConnection(*address, timeout=30)
    data = None if body is None else json.dumps(body)
    c.request(method, path, body=data, headers={"Content-Type": "application/json", **AUTH})
    r = c.getresponse()
    answer = json.loads(r.read())
    c.close()
    return r.status, answer


def assert_collision_body(answer: dict, field: str) -> None:
    truth = thick().clearance(parse_pose(TWIST))
    assert truth.collision
    assert answer["field"] == field and answer["limit"] == "collision"
    assert tuple(answer["pair"]) == truth.pair
    assert answer["clearance_mm"] == pytest.approx(truth.distance * 1e3, abs=1e-9)
    assert answer["min_clearance_mm"] == truth.min_clearance * 1e3
    assert f"in collision: {truth.pair[0]} - {truth.pair[1]} at {truth.distance * 1e3:.3f} mm" in answer["error"]


def test_a_target_or_recipe_in_collision_is_422_naming_the_pair_over_http_and_from_the_cli(tmp_path, capsys):
    cfg = config_file(tmp_path)
    config = load_config(cfg)
    # a recipe stored while the fixture had thin legs: activated with thick ones, it is refused
    store = Store(config.store.path)
    thin = {"right": hexapod("reference")}
    stored = recipe_from_json({"targets": {"right": {"pose": TWIST, "tolerance": TOL}}}, "thin", thin, "anna", 1.0)
    store.targets.put_recipe(stored)
    store.close()
    service = FixtureService(config, hexapods={"right": thick()})
    try:
        service.start()
        address = service.address
        url = f"http://{address[0]}:{address[1]}"
        code, answer = call(address, "PUT", "/fixtures/right/target", {"pose": TWIST, "tolerance": TOL})
        assert code == 422, answer
        assert_collision_body(answer, "pose")
        code, answer = call(
            address, "PUT", "/recipes/bracket", {"targets": {"right": {"pose": TWIST, "tolerance": TOL}}}
        )
        assert code == 422, answer
        assert_collision_body(answer, "targets.right.pose")
        code, answer = call(address, "POST", "/recipes/thin/activate")
        assert code == 422, answer
        assert_collision_body(answer, "targets.right.pose")
        assert call(address, "GET", "/fixtures/right/target") == (200, {"target": None})
        code, answer = call(address, "PUT", "/fixtures/right/target", {"pose": FREE, "tolerance": TOL})
        assert code == 200, answer
        code, g = call(address, "GET", "/fixtures/right/guidance")
        truth = thick().clearance(parse_pose(FREE))
        assert code == 200 and g["clearance"] is None  # no readings: no pose to measure
        assert g["target_clearance"]["collision"] is False and tuple(g["target_clearance"]["pair"]) == truth.pair
        assert g["target_clearance"]["distance_mm"] == pytest.approx(truth.distance * 1e3, abs=1e-9)
        # the command line: one line naming the pair, nothing stored
        pose = [str(TWIST[k]) for k in ("x", "y", "z", "roll", "pitch", "yaw")]
        capsys.readouterr()
        assert main(["fixture", "target", str(cfg), "right", "--pose", *pose, "--url", url]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "422" in err and f"{truth.pair[0]}" in err and "in collision" in err
        recipe = tmp_path / "twist.json"
        recipe.write_text(json.dumps({"targets": {"right": {"pose": TWIST, "tolerance": TOL}}}))
        assert main(["fixture", "recipe", str(cfg), "twist", "--set", str(recipe), "--url", url]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "targets.right.pose" in err and "in collision" in err
        code, target = call(address, "GET", "/fixtures/right/target")
        assert target["target"]["pose"]["yaw"] == pytest.approx(40.0)  # the free target stays
    finally:
        service.stop()
