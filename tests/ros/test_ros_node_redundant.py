"""`hexapod serve` with an inclinometer fixture and [ros] on, heard by a real ROS 2 node (rclpy, Fast DDS).

The simulated plate is held; leg 3 reads 0.3 mm long from 3 s on. The node must hear poses of
``ok`` records only, the six legs' joint states, and on ``/diagnostics`` the consistency test:
passed before the offset, failed after it, naming leg 3, at level ERROR.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from .conftest import need_rclpy, run_domain
from .test_ros_node import LISTENER, REPO, key, wait_for

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.netns]
SIM_SECONDS = 5.0  # the offset from 3.0 s: the node has matched the writers by then
FIXTURE = """
[bus]
interface = "virtual"
channel = "redundant"
[store]
path = "fixture.sqlite"
[http]
host = "127.0.0.1"
port = 0
[[fixtures]]
name = "tilt"
hexapod = "reference_tilt"
can_ids = [0x181, 0x182, 0x183, 0x184, 0x185, 0x186]
noise = 1e-6
lock_time = 30.0  # not locked when the offset comes: a locked fixture's moved leg is leg_moved, no solve
[fixtures.encoder]
metres_per_count = 1e-7
[fixtures.inclinometer]
can_id = 0x1A0
"""
SIM = """
seed = 1
[[fixtures]]
name = "tilt"
rate = 50.0
noise = 1e-6
hold = [0.005, -0.01, 0.4, 2.0, -1.0, 5.0]
[[fixtures.faults]]
kind = "step"
leg = 3
size = 3e-4
start = 3.0
"""


def test_rclpy_node_hears_the_consistency_test_of_a_redundant_fixture(tmp_path):
    need_rclpy()
    ns = f"hexapod_test_{os.getpid()}"
    (tmp_path / "fixture.toml").write_text(FIXTURE + f'[ros]\nnamespace = "{ns}"\ndomain_id = {run_domain()}\n')
    (tmp_path / "sim.toml").write_text(SIM)
    env = {**os.environ, "PYTHONPATH": str(REPO), "ROS_DOMAIN_ID": str(run_domain())}
    env.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)
    stock = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(tmp_path), "ROS_DOMAIN_ID": str(run_domain())}
    stop, heard, err = tmp_path / "stop", tmp_path / "heard.jsonl", tmp_path / "serve.log"
    listener = subprocess.Popen(
        [sys.executable, str(LISTENER), ns, "tilt", "600", str(heard), str(stop)],
        env=stock,
        stdout=subprocess.PIPE,
        text=True,
    )
    with open(tmp_path / "records.jsonl", "w") as out, open(err, "w") as log:
        service = subprocess.Popen(
            [sys.executable, "-m", "hexapod_model.cli", "serve", "fixture.toml", "--simulate", "sim.toml", "--jsonl"],
            cwd=tmp_path,
            env=env,
            stdout=out,
            stderr=log,
        )
    try:
        assert listener.stdout is not None and listener.stdout.readline().strip() == "listening"
        wait_for(err, "publishing ROS 2 topics", service, 600)  # after the kernels compiled (a minute when cold)
        time.sleep(SIM_SECONDS + 1.0)  # the simulator started with the publisher
        service.send_signal(signal.SIGTERM)
        assert service.wait(60) == 0, err.read_text()[-2000:]
    finally:
        stop.touch()
        listener.wait(60)
        if service.poll() is None:
            service.terminate()
            service.wait(30)
    records = [json.loads(line) for line in (tmp_path / "records.jsonl").read_text().splitlines()]
    by_key = {key(r["t"]): r for r in records}
    heard_lines = [json.loads(line) for line in heard.read_text().splitlines()]
    poses = [x for x in heard_lines if x["kind"] == "pose"]
    joints = [x for x in heard_lines if x["kind"] == "joints"]
    assert len(poses) > 10 and len(joints) == len(poses)
    for x in poses + joints:
        assert by_key[(x["sec"], x["nanosec"])]["status"] == "ok"  # never the estimate of a set failing the test
    assert all(len(j["name"]) == len(j["position"]) == 36 for j in joints)
    assert any("isolated:leg3" in r["flags"] and r["pose"] is not None for r in records)  # an estimate was there
    statuses = [s for d in heard_lines if d["kind"] == "diagnostics" for s in d["status"]]
    assert all(s["name"] == "hexapod: tilt" for s in statuses)
    values = [(s["level"], s["values"]) for s in statuses]
    assert any(level == 0 and v["consistency"] == "passed" for level, v in values)
    failed = [(level, v) for level, v in values if v["consistency"] == "failed"]
    assert failed and all(level == 2 for level, _ in failed)
    assert any(v["consistency_isolated"] == "leg3" for _, v in failed)
    assert {v["consistency_readings"] for _, v in values} == {
        json.dumps(["leg1", "leg2", "leg3", "leg4", "leg5", "leg6", "tilt_x", "tilt_y"])
    }
