"""A stock ROS 2 node (rclpy, Fast DDS, no discovery setting) on this machine hears the service's DDS.

The node starts after the service's participant (as when a node is launched beside a running
``hexapod serve``) with a clean environment: only ``PATH``, ``HOME`` and a ``ROS_DOMAIN_ID`` of
this test run, so ``ROS_AUTOMATIC_DISCOVERY_RANGE`` has its default (``SUBNET``). The writer is
configured by :func:`~hexapod_model.ros.dds.cyclone_xml` of the default ``[ros]`` table: the
loopback interface, no multicast.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from .conftest import need_rclpy, run_domain

pytestmark = [pytest.mark.ros, pytest.mark.netns]
LISTENER = Path(__file__).with_name("rclpy_listener.py")
ECHO = Path(__file__).resolve().parents[2] / "docs/examples/ros2_echo.py"
LISTEN_SECONDS = 8.0  # the node listens this long (the service announces itself each second)


def pose_writer(domain_id: int, topic: str):
    """A Cyclone DDS participant and PoseStamped writer as the service creates them (default ``[ros]``)."""
    from cyclonedds.domain import Domain, DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    from hexapod_model.ros.dds import cyclone_xml, type_hashes
    from hexapod_model.ros.messages import PoseStamped
    from hexapod_model.service.config.ros import RosConfig

    domain = Domain(domain_id, cyclone_xml(RosConfig(domain_id=domain_id)))
    participant = DomainParticipant(domain_id, qos=Qos(Policy.Userdata(b"enclave=/;")))
    qos = Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100)),
        Policy.Durability.Volatile,
        Policy.History.KeepLast(10),
        Policy.DataRepresentation(use_cdrv0_representation=True),
        Policy.Userdata(f"typehash={type_hashes()[PoseStamped]};".encode()),
    )
    writer = DataWriter(participant, Topic(participant, "rt" + topic, PoseStamped, qos=qos), qos=qos)
    return domain, participant, writer


@contextlib.contextmanager
def serving_poses(topic: str):
    """The service's participant writing a PoseStamped on ``topic`` every 50 ms while the block runs."""
    from hexapod_model.ros.messages import Header, Point, Pose, PoseStamped, Quaternion, Time

    dds = list(pose_writer(run_domain(), topic))  # domain, participant, writer: deleted at the end
    done = threading.Event()

    def write() -> None:
        k = 0
        while not done.is_set():
            pose = Pose(Point(0.0, 0.0, 0.5), Quaternion(0.0, 0.0, 0.0, 1.0))
            dds[2].write(PoseStamped(Header(Time(k, 0), "right/base"), pose))
            k += 1
            time.sleep(0.05)

    thread = threading.Thread(target=write, daemon=True)
    thread.start()
    try:
        time.sleep(2.0)  # the service's first announcements are over before the node exists
        yield
    finally:
        done.set()
        thread.join()
        dds.clear()


def stock_env(home: Path) -> dict[str, str]:
    """A clean environment: no ROS 2 discovery setting, only this test run's domain."""
    return {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(home), "ROS_DOMAIN_ID": str(run_domain())}


def test_stock_rclpy_node_started_after_the_service_hears_its_poses(tmp_path):
    need_rclpy()
    ns = f"hexapod_discovery_{os.getpid()}"
    heard = tmp_path / "heard.jsonl"
    with serving_poses(f"/{ns}/right/pose"):
        done = subprocess.run(
            [sys.executable, str(LISTENER), ns, "right", str(LISTEN_SECONDS), str(heard), str(tmp_path / "stop")],
            env=stock_env(tmp_path),
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert done.returncode == 0, done.stderr[-2000:]
    poses = [x for x in map(json.loads, heard.read_text().splitlines()) if x["kind"] == "pose"]
    assert len(poses) > 20, f"{len(poses)} poses heard in {LISTEN_SECONDS} s"
    assert all(p["frame"] == "right/base" and p["pose"][2] == 0.5 for p in poses)


def test_the_documented_rclpy_echo_prints_the_poses(tmp_path):
    need_rclpy()
    topic = f"/hexapod_echo_{os.getpid()}/right/pose"
    with serving_poses(topic):
        done = subprocess.run(
            [sys.executable, str(ECHO), topic, "--count", "5"],
            env=stock_env(tmp_path),
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = [line.split() for line in done.stdout.splitlines()]
    assert len(lines) == 5 and all(w[1] == "right/base" and float(w[4]) == 0.5 and float(w[8]) == 1.0 for w in lines)
