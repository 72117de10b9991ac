"""The dashboard's clearance in a real browser: a plate held in collision is shown red, with the pair.

The service solves with thick legs (docs/geometries/thick_legs.toml); the simulated plate, of the
same kinematics with the reference preset's thin legs, is held at a yaw twist where the thick
legs 4 and 5 overlap: the service's pose is in collision, its target is not.
"""

from __future__ import annotations

import re
import time
from pathlib import Path

import can
import pytest

import hexapod_model as hm
from hexapod_model.service import FixtureService, Simulator

from ..conftest import hexapod
from .browser import fields, guidance, render_until
from .helpers import fixture_table, service_config, sim_config
from .test_http import TOKEN, token_file

ROOT = Path(__file__).resolve().parents[2]
THICK = ROOT / "docs" / "geometries" / "thick_legs.toml"
TWIST = [0.02, 0.0, 0.4, 0.0, 0.0, 75.0]  # thick legs 4 and 5 overlap, 1 mm deeper than any other pair
FREE = {"x": 0.0, "y": 0.0, "z": 0.4, "roll": 0.0, "pitch": 0.0, "yaw": 40.0}
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}


@pytest.mark.chromium
def test_the_dashboard_shows_the_clearance_and_highlights_a_collision(tmp_path):
    config = service_config(
        tmp_path,
        [fixture_table("right")],
        http={"host": "127.0.0.1", "port": 0, "token_file": str(token_file(tmp_path))},
    )
    sim = sim_config(config, [{"name": "right", "rate": 50.0, "hold": TWIST}])  # checked against thin legs
    thick = hm.Hexapod.load(THICK)
    service = FixtureService(config, hexapods={"right": thick})
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    simulator = Simulator(config, sim, bus, hexapods={"right": hexapod("reference")})
    try:
        service.start()
        simulator.start()
        assert service.changeover is not None
        service.changeover.set_target("right", {"pose": FREE, "tolerance": TOL}, "test")
        deadline = time.monotonic() + 30.0
        while guidance(service.address, "right")["clearance"] is None:
            assert time.monotonic() < deadline, service.record("right")
            time.sleep(0.05)
        host, port = service.address
        want: dict = {}

        def ready(dom: str) -> bool:  # a page dumped while a starved simulator left the legs silent shows no pose
            want.update(guidance(service.address, "right"))
            shown = fields(dom).get(("right", "clearance.collision"), ["", ""])[1]
            return bool(shown) and want["clearance"] is not None

        dom = render_until(f"http://{host}:{port}/#token={TOKEN}", tmp_path / "profile", ready)
        shown = fields(dom)
    finally:
        simulator.stop()
        service.stop()
        bus.shutdown()
    now, target = want["clearance"], want["target_clearance"]
    assert now["collision"] is True and target["collision"] is False
    assert shown[("right", "clearance.collision")][1] == "true"
    assert shown[("right", "target_clearance.collision")][1] == "false"
    assert shown[("right", "clearance.pair")][1] == ",".join(now["pair"])
    # the pose moves with the reading noise (~0.01 mm): the page's record and this one differ a little
    assert float(shown[("right", "clearance.distance_mm")][1]) == pytest.approx(now["distance_mm"], abs=0.05)
    assert float(shown[("right", "target_clearance.distance_mm")][1]) == target["distance_mm"]  # fixed: to the bit
    tags = {m.group(1): m.group(0) for m in re.finditer(r'<span [^>]*data-field="([a-z_]+\.collision)"[^>]*>', dom)}
    assert 'class="part collision"' in tags["clearance.collision"]
    assert 'class="part"' in tags["target_clearance.collision"]
