"""The ROS bridge in this process: a DDS failure is on /health and never stops HTTP; /tf_static for late joiners."""

from __future__ import annotations

import json
import sys
import time
import urllib.error
import urllib.request

import can
import numpy as np
import pytest

from hexapod_model.service import FixtureService, Simulator
from hexapod_model.service.config.ros import RosConfig
from hexapod_model.service.record.pose_record import PoseRecord

from ..conftest import hexapod
from ..service.helpers import fixture_table, service_config, sim_config
from .conftest import need_extra, run_domain

pytestmark = pytest.mark.ros


def health(address) -> tuple[int, dict]:
    host, port = address
    try:
        with urllib.request.urlopen(f"http://{host}:{port}/health", timeout=5) as r:
            return r.status, json.load(r)
    except urllib.error.HTTPError as e:
        return e.code, json.load(e)


def serve_with_bridge(config, seconds=1.5, meanwhile=None):
    """Run the service, its ROS bridge and a held simulated fixture ``right``; returns /health and the last record.

    ``meanwhile()`` is called while it runs.
    """
    from hexapod_model.ros.dds import RosBridge

    hexapods = {"right": hexapod("reference")}
    service = FixtureService(config, hexapods=hexapods)
    bridge = RosBridge(service, config.ros)
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    held = sim_config(config, [{"name": "right", "rate": 50.0, "hold": [0, 0, 0.4, 0, 0, 0]}])
    sim = Simulator(config, held, bus, hexapods=hexapods)
    try:
        service.start()
        bridge.start()
        sim.start()
        time.sleep(seconds)
        if meanwhile is not None:
            meanwhile()
        return (*health(service.address), service.record("right"))
    finally:
        sim.stop()
        bridge.stop()
        service.stop()
        bus.shutdown()


def test_a_participant_that_cannot_be_created_is_on_health_and_http_goes_on(tmp_path):
    need_extra()
    # 192.0.2.1 (TEST-NET-1) is no interface of this machine: Cyclone DDS refuses the domain
    config = service_config(tmp_path, [fixture_table("right")], ros={"interface": "192.0.2.1", "peers": ["192.0.2.1"]})
    assert config.ros == RosConfig(interface="192.0.2.1", peers=("192.0.2.1",))
    code, body, record = serve_with_bridge(config)
    assert record is not None and record.status == "ok"  # the cycle went on
    assert body["status"] == "degraded", body
    assert "cannot create the DDS participant" in body["ros"]["error"] and body["ros"]["publishing"] is False
    assert body["fixtures"]["right"]["status"] == "ok"
    assert code in (200, 503)


def test_a_working_bridge_is_healthy_and_counts_what_it_published(tmp_path):
    need_extra()
    config = service_config(tmp_path, [fixture_table("right")], ros={"domain_id": run_domain()})
    code, body, _ = serve_with_bridge(config)
    ros = body["ros"]
    assert ros["error"] is None and ros["publishing"] is True and ros["dropped"] == 0
    assert ros["published"] > 3 * 40  # pose, joint states and tf of about 75 ok sets (1.5 s at 50 Hz)
    assert body["status"] == "ok" and code == 200


def test_the_cell_placement_is_on_tf_static_for_a_late_joiner(tmp_path):
    need_extra()
    from cyclonedds.core import Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.qos import Policy
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    from hexapod_model.lie import rpy_to_matrix
    from hexapod_model.ros.messages import TFMessage
    from hexapod_model.service.config.cell import Cell

    config = service_config(
        tmp_path, [fixture_table("right")], ros={"robot_frame": "ur10e/base_link", "domain_id": run_domain()}
    )
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(0.0, 0.0, np.pi / 2)
    T[:3, 3] = [0.85, -0.3, 0.02]
    object.__setattr__(config.fixtures[0], "cell", Cell(base_in_robot=T, coupling=np.eye(4)))  # [fixtures.cell]
    got = []

    def late_reader():  # joins after the placement was written: transient local keeps it
        participant = DomainParticipant(run_domain())  # in the bridge's domain (one Domain per id and process)
        qos = Qos(
            Policy.Reliability.Reliable(duration(seconds=1)),
            Policy.Durability.TransientLocal,
            Policy.History.KeepLast(1),
        )
        reader = DataReader(participant, Topic(participant, "rt/tf_static", TFMessage, qos=qos), qos=qos)
        end = time.monotonic() + 5
        while not got and time.monotonic() < end:
            got.extend(m for m in reader.take(N=10) if isinstance(m, TFMessage))
            time.sleep(0.05)
        del reader, participant

    serve_with_bridge(config, 0.5, late_reader)
    ((msg,),) = [got]
    (t,) = msg.transforms
    assert (t.header.frame_id, t.child_frame_id) == ("ur10e/base_link", "right/base")
    assert [t.transform.translation.x, t.transform.translation.y, t.transform.translation.z] == [0.85, -0.3, 0.02]
    r = t.transform.rotation
    assert np.allclose([r.x, r.y, r.z, r.w], [0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)], atol=1e-15)


def test_without_the_ros_extra_health_says_what_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "cyclonedds.domain", None)  # as if cyclonedds were not installed
    config = service_config(tmp_path, [fixture_table("right")], ros={"domain_id": run_domain()})
    code, body, record = serve_with_bridge(config, 1.0)
    assert record is not None and record.status == "ok"
    assert body["status"] == "degraded" and body["ros"]["publishing"] is False
    assert "pip install 'hexapod_model[ros]'" in body["ros"]["error"]


def test_a_failed_write_is_on_health_until_writing_works_again(tmp_path):
    need_extra()
    from types import SimpleNamespace

    from hexapod_model.ros.dds import RosBridge
    from hexapod_model.ros.names import FixtureNames

    config = service_config(tmp_path, [fixture_table("right")], ros={})
    service = FixtureService(config, http=False, hexapods={"right": hexapod("reference")})
    bridge = RosBridge(service, config.ros)
    bridge.names = {"right": FixtureNames.of("right", "hexapod", service.hexapods["right"])}
    written = []

    class Writer:
        broken = True

        def write(self, msg):
            if self.broken:
                raise RuntimeError("DDS_RETCODE_TIMEOUT")
            written.append(msg)

    w = Writer()
    bridge._writers = SimpleNamespace(pose={"right": w}, joints={"right": w}, tf=w, diagnostics=w)  # type: ignore[assignment]
    pose = {"x": 0.0, "y": 0.0, "z": 0.4, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0}
    rec = PoseRecord("right", 1795672991.5, [0.0] * 6, pose, "ok", [], 0, "moving", False, None, None, None, None)
    bridge._publish(rec, service.hexapods["right"].q_home)
    h = bridge.health()
    assert h["error"] == "DDS write failed: DDS_RETCODE_TIMEOUT" and h["failed_writes"] == 4 and h["published"] == 0
    w.broken = False
    bridge._publish(rec._replace(t=rec.t + 0.02), service.hexapods["right"].q_home)
    h = bridge.health()
    assert h["error"] is None and h["failed_writes"] == 4 and h["published"] == 3 and len(written) == 3
