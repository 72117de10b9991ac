"""`hexapod serve` with [ros] on the simulated bus, heard by a real ROS 2 node (rclpy, Fast DDS) in another process.

Every pose the node receives must be the service's record of the same ``t`` (JSON lines, the text
HTTP serves) and ``ok``; the simulated error-bit fault of fixture ``left`` (sim.toml: leg 3 at 6 s
for 0.2 s) must give ERROR diagnostics and no pose. ``/tf`` is read with a Cyclone DDS reader in
this process (no tf2_msgs wheel), decoded by rosbags.
"""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from .conftest import need_rclpy, run_domain

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.netns]
REPO = Path(__file__).resolve().parents[2]
LISTENER = Path(__file__).with_name("rclpy_listener.py")
SIM_SECONDS = 9.0  # the fault is at 6.0-6.2 s
TOL = 1e-12  # m (and quaternion units): the same floats carried by two paths


def key(t: float) -> tuple[int, int]:
    from hexapod_model.ros.convert import stamp

    s = stamp(t)
    return s.sec, s.nanosec


def wait_for(path: Path, pattern: str, proc: subprocess.Popen, seconds: float) -> re.Match:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        found = re.search(pattern, path.read_text())
        if found:
            return found
        if proc.poll() is not None:
            raise AssertionError(f"the service exited: {path.read_text()[-2000:]}")
        time.sleep(0.2)
    raise AssertionError(f"no {pattern!r} within {seconds} s: {path.read_text()[-2000:]}")


@pytest.fixture
def config(tmp_path):
    text = (REPO / "docs/examples/fixture.toml").read_text().replace("port = 8765", "port = 0")
    ns = f"hexapod_test_{os.getpid()}"
    (tmp_path / "fixture.toml").write_text(text + f'\n[ros]\nnamespace = "{ns}"\ndomain_id = {run_domain()}\n')
    (tmp_path / "sim.toml").write_text((REPO / "docs/examples/sim.toml").read_text())
    return tmp_path, ns


def tf_reader():
    """A Cyclone DDS reader of rt/tf in this process (the service's discovery settings)."""
    from cyclonedds.domain import Domain, DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from hexapod_model.ros.dds import cyclone_xml
    from hexapod_model.ros.messages import TFMessage
    from hexapod_model.service.config.ros import RosConfig

    domain = Domain(run_domain(), cyclone_xml(RosConfig()))
    participant = DomainParticipant(run_domain())
    return domain, participant, DataReader(participant, Topic(participant, "rt/tf", TFMessage))


def test_rclpy_node_receives_the_served_poses_joint_states_and_diagnostics(config):
    need_rclpy()
    from rosbags.typesys import Stores, get_typestore

    from hexapod_model import Hexapod

    folder, ns = config
    env = {**os.environ, "PYTHONPATH": str(REPO), "ROS_DOMAIN_ID": str(run_domain())}
    env.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)
    stock = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(folder), "ROS_DOMAIN_ID": str(run_domain())}
    stop, heard = folder / "stop", folder / "heard.jsonl"
    listener = subprocess.Popen(  # a stock node: no discovery setting in its environment
        [sys.executable, str(LISTENER), ns, "left,right", "600", str(heard), str(stop)],
        env=stock,
        stdout=subprocess.PIPE,
        text=True,
    )
    err = folder / "serve.log"
    with open(folder / "records.jsonl", "w") as out, open(err, "w") as log:
        service = subprocess.Popen(
            [sys.executable, "-m", "hexapod_model.cli", "serve", "fixture.toml", "--simulate", "sim.toml", "--jsonl"],
            cwd=folder,
            env=env,
            stdout=out,
            stderr=log,
        )
    domain = participant = reader = None
    http: list[dict] = []
    transforms = []
    try:
        assert listener.stdout is not None and listener.stdout.readline().strip() == "listening"
        port = int(wait_for(err, r"serving http://127\.0\.0\.1:(\d+)", service, 600).group(1))
        wait_for(err, "publishing ROS 2 topics", service, 600)  # after the kernels compiled (a minute when cold)
        domain, participant, reader = tf_reader()
        end = time.monotonic() + SIM_SECONDS  # the simulator started with the publisher
        while time.monotonic() < end and service.poll() is None:  # the HTTP records meanwhile
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/fixtures/right/pose", timeout=2) as r:
                    http.append(json.loads(r.read()))
            except OSError:
                pass
            transforms += [tr for m in reader.take(N=100) for tr in getattr(m, "transforms", ())]  # not InvalidSample
            time.sleep(0.05)
        service.send_signal(signal.SIGTERM)  # hexapod serve stops cleanly
        assert service.wait(60) == 0, err.read_text()[-2000:]
    finally:
        stop.touch()
        listener.wait(60)
        if service.poll() is None:
            service.terminate()
            service.wait(30)
        del reader, participant, domain
    records = [json.loads(line) for line in (folder / "records.jsonl").read_text().splitlines()]
    by_key = {(r["fixture"], key(r["t"])): r for r in records}
    heard_lines = [json.loads(line) for line in heard.read_text().splitlines()]
    kinds = {k: [x for x in heard_lines if x["kind"] == k] for k in ("pose", "joints", "diagnostics", "hashes")}

    # poses: each is the ok record of its t, in <fixture>/base
    poses = kinds["pose"]
    assert {p["fixture"] for p in poses} == {"left", "right"}
    assert sum(p["fixture"] == "right" for p in poses) > 100  # 50 Hz for several seconds
    for p in poses:
        rec = by_key[(p["fixture"], (p["sec"], p["nanosec"]))]
        assert rec["status"] == "ok", rec
        assert p["frame"] == f"{p['fixture']}/base"
        want = [rec["pose"][k] for k in ("x", "y", "z", "qx", "qy", "qz", "qw")]
        assert max(abs(a - b) for a, b in zip(p["pose"], want)) <= TOL
    # the HTTP records of fixture right: the ok ones the node heard are equal
    heard_right = {(p["sec"], p["nanosec"]): p["pose"] for p in poses if p["fixture"] == "right"}
    matched = [r for r in http if r["status"] == "ok" and key(r["t"]) in heard_right]
    assert len(matched) > 10, (len(http), len(heard_right))
    for r in matched:
        want = [r["pose"][k] for k in ("x", "y", "z", "qx", "qy", "qz", "qw")]
        assert max(abs(a - b) for a, b in zip(heard_right[key(r["t"])], want)) <= TOL

    # no pose, joint state or transform for a record that is not ok; the fault did happen
    faulty = [r for r in records if r["fixture"] == "left" and r["status"] == "encoder_error"]
    assert faulty and all("encoder_error:leg3" in r["flags"] for r in faulty)
    not_ok = {(r["fixture"], key(r["t"])) for r in records if r["status"] != "ok"}
    for x in poses + kinds["joints"]:
        assert (x["fixture"], (x["sec"], x["nanosec"])) not in not_ok

    # joint states: the URDF's one-dof joints; the prismatic ones are the readings
    hexa = Hexapod.from_preset("reference", compiled=False)
    one_dof = [n for n in hexa.joint_names if n != "platform_joint"]
    joints = kinds["joints"]
    assert {j["fixture"] for j in joints} == {"left", "right"}
    for j in joints:
        rec = by_key[(j["fixture"], (j["sec"], j["nanosec"]))]
        assert rec["status"] == "ok" and j["name"] == one_dof
        legs = [j["position"][j["name"].index(n)] for n in hexa.prismatic_names]
        assert max(abs(a - b) for a, b in zip(legs, rec["readings"])) <= TOL
        assert all(math.isfinite(v) for v in j["position"])
    # the passive joints are the pose's: the inverse kinematics of the record's pose gives them (1e-7 rad or m)
    from hexapod_model.lie import quaternion_to_matrix

    for j in joints[:: max(1, len(joints) // 6)]:
        p = by_key[(j["fixture"], (j["sec"], j["nanosec"]))]["pose"]
        T = np.eye(4)
        T[:3, :3] = quaternion_to_matrix(np.array([p["qx"], p["qy"], p["qz"], p["qw"]]))
        T[:3, 3] = [p["x"], p["y"], p["z"]]
        q = hexa.inverse(T).q
        want = [q[hexa.model.joints[hexa.model.getJointId(n)].idx_q] for n in j["name"]]
        assert np.max(np.abs(np.array(j["position"]) - want)) < 1e-7

    # diagnostics: the level follows the record's status
    statuses = [s for d in kinds["diagnostics"] for s in d["status"]]
    expected = {"ok": {0, 1}, "flagged": {1}, "drift": {1}, "no_data": {3}}
    for s in statuses:
        assert s["level"] in expected.get(s["values"]["status"], {2}), s
    assert any(s["name"] == "hexapod: left" and s["values"]["status"] == "encoder_error" for s in statuses)
    assert any(s["name"] == "hexapod: right" and s["level"] == 0 for s in statuses)

    # the type hash the node saw in the writer's USER_DATA is its own type's
    (hashes,) = kinds["hashes"]
    assert hashes["type"] == "geometry_msgs/msg/PoseStamped"
    assert hashes["publisher"] == hashes["own"]
    assert hashes["own"] == get_typestore(Stores.ROS2_JAZZY).hash_rihs01("geometry_msgs/msg/PoseStamped")

    # /tf: base -> platform of ok records only
    assert transforms
    for tr in transforms:
        fixture = tr.child_frame_id.split("/")[0]
        assert tr.header.frame_id == f"{fixture}/base" and tr.child_frame_id == f"{fixture}/platform"
        rec = by_key[(fixture, (tr.header.stamp.sec, tr.header.stamp.nanosec))]
        assert rec["status"] == "ok"
        assert abs(tr.transform.translation.z - rec["pose"]["z"]) <= TOL
