"""The changeover over HTTP: targets and recipes with the token, guidance from the simulated bus, a restart."""

from __future__ import annotations

import http.client
import json
import time

import can
import numpy as np
import pytest

from hexapod_model.service import FixtureService, Simulator

from ..conftest import hexapod
from .helpers import fixture_table, record_pose, service_config, sim_config
from .test_http import TOKEN, token_file

HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]
POSE = dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), HOLD))
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}
AUTH = {"Authorization": f"Bearer {TOKEN}", "X-Operator": "anna"}


def call(address, method, path, body=None, headers=None):
    c = http.client.HTTPConnection(*address, timeout=10)
    data = None if body is None else json.dumps(body)
    c.request(method, path, body=data, headers={"Content-Type": "application/json", **(headers or {})})
    r = c.getresponse()
    text = r.read()
    c.close()
    return r.status, json.loads(text) if r.getheader("content-type", "").startswith("application/json") else text


def until(address, fixture, check, seconds=10.0):
    """Poll the guidance until ``check(guidance)``; returns it (the last one when the time ran out)."""
    end = time.monotonic() + seconds
    while True:
        code, g = call(address, "GET", f"/fixtures/{fixture}/guidance", headers=AUTH)
        assert code == 200, g
        if check(g) or time.monotonic() > end:
            return g
        time.sleep(0.1)


class Running:
    """The service and simulated encoders on a virtual bus of this process."""

    def __init__(self, config, sim):
        hexa = hexapod("reference")
        self.service = FixtureService(config, hexapods={"right": hexa, "left": hexa})
        self.bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
        self.service.start()
        self.sim = Simulator(config, sim, self.bus, hexapods={"right": hexa, "left": hexa})
        self.sim.start()

    @property
    def address(self):
        return self.service.address

    def stop(self):
        self.sim.stop()
        self.service.stop()
        self.bus.shutdown()


@pytest.fixture
def setup(tmp_path):
    config = service_config(
        tmp_path,
        [fixture_table("left"), fixture_table("right", 1, home_counts=100_000)],
        http={"host": "127.0.0.1", "port": 0, "token_file": str(token_file(tmp_path))},
    )
    sim = sim_config(
        config, [{"name": "right", "rate": 50.0, "hold": HOLD}, {"name": "left", "rate": 50.0, "hold": HOLD}]
    )
    return config, sim


def test_targets_guidance_recipes_and_a_restart_over_http(setup):
    config, sim = setup
    hexa = hexapod("reference")
    run = Running(config, sim)
    try:
        a = run.address
        # writes need the token; bad bodies name their field
        assert call(a, "PUT", "/fixtures/right/target", {"pose": POSE, "tolerance": TOL})[0] == 401
        bad = {"Authorization": "Bearer wrong-token-0123456789"}
        assert call(a, "PUT", "/fixtures/right/target", {"pose": POSE, "tolerance": TOL}, bad)[0] == 401
        assert call(a, "DELETE", "/fixtures/right/target")[0] == 401
        assert call(a, "PUT", "/recipes/r1", {"targets": {}})[0] == 401
        assert call(a, "POST", "/recipes/r1/activate")[0] == 401
        code, body = call(a, "PUT", "/fixtures/right/target", {"pose": {**POSE, "z": "x"}, "tolerance": TOL}, AUTH)
        assert code == 422 and body["field"] == "pose.z" and "\n" not in body["error"]
        code, body = call(a, "PUT", "/fixtures/right/target", {"pose": {**POSE, "z": 0.6}, "tolerance": TOL}, AUTH)
        assert code == 422 and "stroke limit" in body["error"] and "leg" in body["error"]
        assert call(a, "PUT", "/fixtures/nope/target", {"pose": POSE, "tolerance": TOL}, AUTH)[0] == 404

        # a target at the simulated hold pose: in tolerance within 10 s
        code, body = call(a, "PUT", "/fixtures/right/target", {"pose": POSE, "tolerance": TOL}, AUTH)
        assert code == 200 and body["target"]["set_by"].startswith("anna (127.0.0.1:")
        g = until(a, "right", lambda g: g["in_tolerance"])
        assert g["in_tolerance"] and g["status"] == "ok" and g["deviation"]["translation_mm"] < 0.1

        # 2 mm away: ~2 mm, and per-leg changes equal to the inverse kinematics' differences
        away = {**POSE, "z": POSE["z"] + 0.002}
        code, body = call(a, "PUT", "/fixtures/right/target", {"pose": away, "tolerance": TOL}, AUTH)
        target_id = body["target"]["id"]
        g = until(a, "right", lambda g: g["target"]["id"] == target_id and g["status"] == "ok")
        assert g["deviation"]["translation_mm"] == pytest.approx(2.0, abs=0.1) and not g["in_tolerance"]
        ik_target = hexa.inverse(record_pose({"pose": {**body["target"]["pose"]}})).lengths
        ik_here = hexa.inverse(record_pose(g)).lengths
        changes = np.array([leg["change_mm"] for leg in g["legs"]])
        assert np.abs(changes - (ik_target - ik_here) * 1e3).max() < 1e-3  # 1 um
        assert np.allclose([leg["target_mm"] for leg in g["legs"]], ik_target * 1e3, atol=1e-6)

        # recipes
        recipe = {"targets": {"left": {"pose": POSE, "tolerance": TOL}, "right": {"pose": away, "tolerance": TOL}}}
        assert call(a, "PUT", "/recipes/bracket", recipe, AUTH)[0] == 200
        code, body = call(a, "PUT", "/recipes/other", {"targets": {"middle": recipe["targets"]["left"]}}, AUTH)
        assert code == 422 and body["field"] == "targets.middle"
        assert call(a, "POST", "/recipes/nothing/activate", None, AUTH)[0] == 404
        code, body = call(a, "POST", "/recipes/bracket/activate", None, AUTH)
        assert code == 200 and body["active"] == "bracket" and body["targets"]["left"]["recipe"] == "bracket"
        code, body = call(a, "GET", "/recipes", headers=AUTH)
        assert code == 200 and body["active"]["name"] == "bracket" and set(body["recipes"]) == {"bracket"}
        g = until(a, "left", lambda g: g["in_tolerance"])
        assert g["in_tolerance"] and g["active_recipe"] == "bracket" and g["target"]["recipe"] == "bracket"
        kept = call(a, "GET", "/fixtures/right/target", headers=AUTH)[1]["target"]
    finally:
        run.stop()

    run = Running(config, sim)  # the targets and the active recipe survive a restart
    try:
        a = run.address
        again = call(a, "GET", "/fixtures/right/target", headers=AUTH)[1]["target"]
        assert {k: again[k] for k in ("id", "set_by", "set_at", "recipe", "tolerance")} == {
            k: kept[k] for k in ("id", "set_by", "set_at", "recipe", "tolerance")
        }
        assert again["pose"] == pytest.approx(kept["pose"], abs=1e-12)  # kept as a quaternion
        assert call(a, "GET", "/recipes", headers=AUTH)[1]["active"]["name"] == "bracket"
        code, body = call(a, "DELETE", "/fixtures/right/target", None, AUTH)
        assert code == 200 and body == {"cleared": True}
        assert call(a, "GET", "/fixtures/right/guidance", headers=AUTH)[1]["target"] is None
        # the dashboard's page needs no token (its script sends it); its event stream does
        code, page = call(a, "GET", "/")
        assert code == 200 and b"/dashboard/dashboard.js" in page
        assert call(a, "GET", "/dashboard/dashboard.js")[0] == 200
        assert call(a, "GET", "/events")[0] == 401
        c = http.client.HTTPConnection(*a, timeout=5)
        c.request("GET", "/events", headers=AUTH)
        r = c.getresponse()
        assert r.status == 200 and r.getheader("content-type").startswith("text/event-stream")
        seen = b""
        while b"data: " not in seen or not seen.endswith(b"\n\n"):
            seen += r.read1(65536)
        event = json.loads(seen.split(b"data: ", 1)[1].split(b"\n\n")[0])
        assert [f["fixture"] for f in event["fixtures"]] == ["left", "right"] and event["active_recipe"] == "bracket"
        c.close()
    finally:
        run.stop()
