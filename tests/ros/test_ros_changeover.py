"""The changeover on ROS 2: a stock rclpy node sets a fixture's target by a signed message and hears the guidance.

The service runs in this process on the simulated bus with a token and a :class:`RosBridge`; the
node (another process, no discovery setting) probes until a result comes back, then sends a request
signed with a wrong token, a good one, the good one again (a replay) and one for a fixture that does
not exist, and listens to the results and to ``/<ns>/right/guidance``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import can
import pytest

from .conftest import need_rclpy, run_domain

pytestmark = [pytest.mark.ros, pytest.mark.netns]
NODE = Path(__file__).with_name("rclpy_changeover.py")
HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]
POSE = dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), HOLD))
TARGET = {"pose": {**POSE, "z": POSE["z"] + 0.002}, "tolerance": {"translation_mm": 0.1, "rotation_deg": 0.05}}


def test_a_signed_target_over_ros2_is_set_once_and_the_guidance_is_published(tmp_path):
    need_rclpy()
    from hexapod_model.ros.changeover_topics import request
    from hexapod_model.ros.dds import RosBridge
    from hexapod_model.service import FixtureService, Simulator
    from hexapod_model.service.config.ros import RosConfig

    from ..conftest import hexapod
    from ..service.helpers import fixture_table, service_config, sim_config
    from ..service.test_http import TOKEN, token_file

    config = service_config(
        tmp_path,
        [fixture_table("right", 1)],
        http={"host": "127.0.0.1", "port": 0, "token_file": str(token_file(tmp_path))},
    )
    sim = sim_config(config, [{"name": "right", "rate": 50.0, "hold": HOLD}])
    hexa = hexapod("reference")
    service = FixtureService(config, hexapods={"right": hexa})
    ns = f"hexapod_changeover_{os.getpid()}"
    bridge = RosBridge(service, RosConfig(namespace=ns, domain_id=run_domain()))
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    simulator = Simulator(config, sim, bus, hexapods={"right": hexa})
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(tmp_path), "ROS_DOMAIN_ID": str(run_domain())}
    try:
        service.start()
        bridge.start()
        simulator.start()
        assert bridge.error is None, bridge.error
        good = request("right", TARGET, "tester", TOKEN)
        forged = request("right", TARGET, "intruder", "not-the-token")
        requests = [forged, good, good, request("left", TARGET, "x", TOKEN)]
        (tmp_path / "requests.json").write_text(json.dumps(requests))
        done = subprocess.run(
            [sys.executable, str(NODE), ns, "right", str(tmp_path / "requests.json"), str(tmp_path / "out.json"), "60"],
            env=env,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == 0, done.stderr[-2000:]
        assert service.changeover is not None
        stored = service.changeover.target("right")
    finally:
        simulator.stop()
        bridge.stop()
        service.stop()
        bus.shutdown()
    out = json.loads((tmp_path / "out.json").read_text())
    results = out["results"]
    assert out["probes"] and all("malformed target request" in p["error"] for p in out["probes"]), out["probes"]
    assert [r["ok"] for r in results] == [False, True, False, False], results
    assert "wrong signature" in results[0]["error"] and "already taken" in results[2]["error"]
    assert "left" in results[3]["error"]
    assert results[1]["target"]["set_by"] == "tester (ROS 2)"
    assert stored is not None and stored.to_json() == results[1]["target"]
    assert abs(stored.pose[2, 3] - TARGET["pose"]["z"]) < 1e-12
    # the guidance heard: the fixture's, toward the target set (2 mm above the held plate, within sigma)
    g = out["guidance"][-1]
    assert g["fixture"] == "right" and g["target"] == results[1]["target"]
    assert abs(g["deviation"]["translation_mm"] - 2.0) < 0.15
    assert time.time() - g["t"] < 60.0
