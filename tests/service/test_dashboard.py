"""The dashboard in a real browser: headless Chromium renders GET / of a service on the simulated bus.

The page's values (``data-field`` elements, the number itself in ``data-value``) are read from the
rendered DOM and checked against ``/fixtures/NAME/guidance`` of the same service.
"""

from __future__ import annotations

import time

import can
import pytest

from hexapod_model.service import FixtureService, Simulator

from ..conftest import hexapod
from .browser import fields, guidance, render_until
from .helpers import fixture_table, service_config, sim_config
from .test_http import TOKEN, token_file

HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]
POSE = dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), HOLD))
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}


@pytest.mark.chromium
def test_the_dashboard_shows_what_guidance_says(tmp_path):
    config = service_config(
        tmp_path,
        [fixture_table("left"), fixture_table("right", 1)],
        http={"host": "127.0.0.1", "port": 0, "token_file": str(token_file(tmp_path))},
    )
    # 1 um reading noise: the left plate, held at its target, lies well within the 0.1 mm tolerance
    # (with the default 10 um its conservative verdict could flip between the page's record and a later one)
    still = {"rate": 50.0, "hold": HOLD, "noise": 1e-6}
    sim = sim_config(config, [{"name": "right", **still}, {"name": "left", **still}])
    hexa = hexapod("reference")
    service = FixtureService(config, hexapods={"left": hexa, "right": hexa})
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    simulator = Simulator(config, sim, bus, hexapods={"left": hexa, "right": hexa})
    try:
        service.start()
        simulator.start()
        assert service.changeover is not None
        away = {**POSE, "z": POSE["z"] + 0.002}
        service.changeover.put_recipe(
            "bracket",
            {"targets": {"right": {"pose": away, "tolerance": TOL}, "left": {"pose": POSE, "tolerance": TOL}}},
            "test",
        )
        service.changeover.activate("bracket", "test")
        deadline = time.monotonic() + 30.0  # both held plates locked: the state no longer changes
        while not all(getattr(service.record(n), "stored", False) for n in ("left", "right")):
            assert time.monotonic() < deadline, [service.record(n) for n in ("left", "right")]
            time.sleep(0.05)
        host, port = service.address
        # (a dump taken before the service's first event shows no recipe and no fixture: browser.py)
        dom = render_until(f"http://{host}:{port}/#token={TOKEN}", tmp_path / "profile", lambda d: "data-updated=" in d)
        want = {name: guidance(service.address, name) for name in ("left", "right")}
    finally:
        simulator.stop()
        service.stop()
        bus.shutdown()
    shown = fields(dom)
    assert shown[(None, "active_recipe")][0] == "bracket"
    for name, g in want.items():
        assert g["status"] == "ok" and shown[(name, "status")][0] == "ok"
        assert shown[(name, "state")][0] == g["state"]
        # the target is fixed: shown to the bit
        for leg in g["legs"]:
            assert float(shown[(name, f"legs.{leg['leg']}.target_mm")][1]) == leg["target_mm"]
        assert float(shown[(name, "target.z_mm")][1]) == pytest.approx(g["target"]["pose"]["z"] * 1e3, abs=1e-9)
        assert float(shown[(name, "tolerance.translation_mm")][1]) == 0.1
        # what moves with the reading noise: the page's record and this one differ a little
        dev = float(shown[(name, "deviation.translation_mm")][1])
        assert dev == pytest.approx(g["deviation"]["translation_mm"], abs=0.15)
        for leg in g["legs"]:
            change = float(shown[(name, f"legs.{leg['leg']}.change_mm")][1])
            assert change == pytest.approx(leg["change_mm"], abs=0.15)
            text = shown[(name, f"legs.{leg['leg']}.change_mm")][0]
            assert text == f"{abs(change):.3f}"
    assert float(shown[("right", "deviation.translation_mm")][1]) == pytest.approx(2.0, abs=0.15)
    assert shown[("right", "in_tolerance")][0] == "not in tolerance"
    assert want["left"]["in_tolerance"] and shown[("left", "in_tolerance")][0] == "in tolerance"
    assert (("left", "acknowledge") in shown) and ("right", "flags") in shown
