"""A fixture with redundant sensors on ROS 2: records of a real cycle through the bridge and into a bag.

The inclinometer fixture (``reference_tilt``) with a 0.3 mm offset on leg 3 from 0.5 s: its sets
fail the consistency test, naming leg 3 (``tests/service/test_redundant_service.py``). ROS 2 must
receive no pose from them, and the consistency test on ``/diagnostics``, live and in the bag.
"""

from __future__ import annotations

import importlib.util
import json
import time
from types import SimpleNamespace

import pytest

from hexapod_model.cli import main
from hexapod_model.service import FixtureCycle, FixtureService, Simulator, Store, geometry_hash
from hexapod_model.service.store.fixture_store import sample_row

from ..conftest import hexapod
from ..service.helpers import CollectingBus, service_config, sim_config
from .conftest import need_extra

pytestmark = pytest.mark.ros
IDS = [0x181 + k for k in range(6)]
TILT = 0x1A0
FIXTURE = {
    "name": "left",
    "hexapod": "reference_tilt",
    "can_ids": IDS,
    "noise": 1e-6,  # the geometry's encoder_sigma: the test's weights hold
    "encoder": {"metres_per_count": 1e-7},
    "inclinometer": {"can_id": TILT},
}
CONFIG = """
[bus]
interface = "virtual"
channel = "redundant-bag-test"
[store]
path = "store.sqlite"
[ros]
namespace = "cell"
[[fixtures]]
name = "left"
hexapod = "reference_tilt"
can_ids = [0x181, 0x182, 0x183, 0x184, 0x185, 0x186]
noise = 1e-6
[fixtures.encoder]
metres_per_count = 1e-7
[fixtures.inclinometer]
can_id = 0x1A0
"""


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """The records of 1.5 s of sets at 100 Hz (trajectory A), leg 3 reading 0.3 mm long from 0.5 s."""
    need_extra()
    tmp = tmp_path_factory.mktemp("redundant")
    config = service_config(tmp, [FIXTURE], ros={})
    fault = {"kind": "step", "leg": 3, "size": 3e-4, "start": 0.5}
    sim = sim_config(config, [{"name": "left", "rate": 100.0, "trajectory": "A", "noise": 1e-6, "faults": [fault]}])
    cfg, hexa = config.fixture("left"), hexapod("reference_tilt")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 1e9)
    bus = CollectingBus()
    simulator = Simulator(config, sim, bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    channel = {leg.can_id: k for k, leg in enumerate(cfg.legs)} | {TILT: len(cfg.legs)}
    out = []
    for k in range(150):
        bus.sent.clear()
        simulator.send_set(0, k / 100, stamp=1e9 + k / 100, stall_check=False)
        for msg in bus.sent:
            rec = cycle.on_frame(channel[msg.arbitration_id], msg.data, msg.timestamp)
            if rec is not None:
                out.append(rec)
    after = [r for r in out if r.t >= 1e9 + 0.5]
    assert sum("isolated:leg3" in r.flags for r in after) >= len(after) - 3  # what the service test checks
    return config, out


class Capture:
    def __init__(self):
        self.written = []

    def write(self, msg):
        self.written.append(msg)


def test_the_bridge_publishes_no_pose_of_an_inconsistent_set_and_its_test_on_diagnostics(records):
    from hexapod_model.ros.dds import RosBridge
    from hexapod_model.ros.names import FixtureNames

    config, recs = records
    hexa = hexapod("reference_tilt")
    service = FixtureService(config, http=False, hexapods={"left": hexa})
    bridge = RosBridge(service, config.ros)
    bridge.names = {"left": FixtureNames.of("left", "hexapod", hexa)}
    pose, joints, tf, diagnostics = Capture(), Capture(), Capture(), Capture()
    bridge._writers = SimpleNamespace(pose={"left": pose}, joints={"left": joints}, tf=tf, diagnostics=diagnostics)  # type: ignore[assignment]
    for rec in recs:
        bridge._publish(rec, rec.q)
    assert bridge.error is None
    ok = [r for r in recs if r.status == "ok"]
    assert len(ok) > 30 and len(pose.written) == len(ok) == len(joints.written) == len(tf.written)
    for rec, msg in zip(ok, pose.written, strict=True):
        assert msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9 == pytest.approx(rec.t, abs=1e-6)
    assert all(r.t < 1e9 + 0.5 for r in ok)  # not one pose of the sets leg 3's offset spoils
    for js in joints.written:  # every URDF joint, each with its value
        assert len(js.name) == len(js.position) == 36
    statuses = [
        {kv.key: kv.value for kv in m.status[0].values} | {"level": m.status[0].level} for m in diagnostics.written
    ]
    failed = [s for s in statuses if "inconsistent_readings" in json.loads(s["flags"])]
    assert failed and all(s["consistency"] == "failed" and s["level"] == 2 for s in failed)
    assert all(s["consistency_isolated"] == "leg3" for s in failed if "isolated:leg3" in json.loads(s["flags"]))
    assert any(s["consistency_isolated"] == "leg3" for s in failed)
    first = next(s for s in statuses if s["status"] == "ok")
    assert first["consistency"] == "passed" and first["level"] == 0
    assert json.loads(first["consistency_readings"]) == list(hexa.reading_names) and first["consistency_dof"] == "2"
    # the set's own statistic and the extra readings' values (rad), as the records carry them
    by_t = {rec.t: rec for rec in recs}
    for s in statuses:
        rec = by_t[float(s["t"])]
        if rec.consistency is not None:
            assert float(s["consistency_chi2"]) == rec.consistency["chi2"]
            assert (float(s["consistency_chi2"]) > float(s["consistency_chi2_bound"])) == (s["consistency"] == "failed")
        for name in ("tilt_x", "tilt_y"):
            value = (rec.extra_readings or {}).get(name)
            assert s[f"reading_{name}_rad"] == ("" if value is None else repr(float(value)))
    assert any(s["consistency_chi2"] for s in failed) and all(s["reading_tilt_x_rad"] for s in failed)


def test_the_bag_of_a_redundant_fixture_carries_its_test(records, tmp_path):
    if importlib.util.find_spec("mcap_ros2") is None:
        pytest.skip("mcap-ros2-support not installed (the reader of this test): pip install mcap-ros2-support")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    _, recs = records
    path = tmp_path / "fixture.toml"
    path.write_text(CONFIG)
    with Store(tmp_path / "store.sqlite") as store:
        store.add_samples([sample_row(r) for r in recs])
    out = tmp_path / "history.mcap"
    assert main(["fixture", "history", str(path), "--mcap", str(out)]) == 0
    with open(out, "rb") as fh:
        msgs = [
            (c.topic, m) for _, c, _, m in make_reader(fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages()
        ]
    ok = [r for r in recs if r.status == "ok"]
    assert len([m for topic, m in msgs if topic == "/cell/left/pose"]) == len(ok)
    joints = [m for topic, m in msgs if topic == "/cell/left/joint_states"]
    assert len(joints) == len(ok) and all(m.name == [f"leg{k}_prismatic" for k in range(1, 7)] for m in joints)
    for js, rec in zip(joints, ok, strict=True):
        assert list(js.position) == rec.readings  # the six legs' readings the record carries
    statuses = [{kv.key: kv.value for kv in m.status[0].values} for topic, m in msgs if topic == "/diagnostics"]
    assert len(statuses) == len(recs)
    assert any(s["consistency"] == "failed" for s in statuses)
    for s, rec in zip(statuses, recs, strict=True):
        assert s["status"] == rec.status
        if rec.status == "ok":
            assert s["consistency"] == "passed"
        if "inconsistent_readings" in rec.flags:
            assert s["consistency"] == "failed"
        named = [f.split(":")[1] for f in rec.flags if f.startswith("isolated:")]
        assert s["consistency_isolated"] == (named[0] if named else "")


def test_over_dds_a_redundant_fixtures_poses_are_its_ok_records_and_its_test_is_on_diagnostics(tmp_path):
    """The service, its bridge and the held inclinometer fixture simulated in real time; a DDS reader listens."""
    need_extra()
    import can
    from cyclonedds.core import Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.qos import Policy
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    from hexapod_model.ros.dds import RosBridge
    from hexapod_model.ros.messages import DiagnosticArray, PoseStamped

    from .conftest import run_domain

    config = service_config(tmp_path, [FIXTURE], ros={"domain_id": run_domain(), "diagnostics_period": 0.1})
    fault = {"kind": "step", "leg": 3, "size": 3e-4, "start": 0.8}  # before the held fixture locks (1 s)
    held = {"name": "left", "rate": 50.0, "hold": [0, 0, 0.4, 0, 0, 0], "noise": 1e-6, "faults": [fault]}
    sim = sim_config(config, [held])  # held: a set late on a busy machine is still one pose
    hexapods = {"left": hexapod("reference_tilt")}
    service = FixtureService(config, http=False, hexapods=hexapods)
    bridge = RosBridge(service, config.ros)
    records: list = []
    service.subscribe(records.append)
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    simulator = Simulator(config, sim, bus, hexapods=hexapods)
    poses, diagnostics = [], []
    try:
        service.start()
        bridge.start()
        participant = DomainParticipant(run_domain())  # the bridge's domain (one Domain per id and process)
        qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(1000))
        readers = [
            (DataReader(participant, Topic(participant, "rt/hexapod/left/pose", PoseStamped, qos=qos), qos=qos), poses),
            (
                DataReader(participant, Topic(participant, "rt/diagnostics", DiagnosticArray, qos=qos), qos=qos),
                diagnostics,
            ),
        ]
        time.sleep(0.5)  # matched before the first set
        simulator.start()
        end = time.monotonic() + 2.5
        while time.monotonic() < end:
            for reader, out in readers:
                out.extend(reader.take(N=100))
            time.sleep(0.05)
        assert bridge.error is None
    finally:
        simulator.stop()
        bridge.stop()
        service.stop()
        bus.shutdown()
    ok = {round(r.t * 1e6) for r in records if r.status == "ok"}
    assert len(poses) >= 5 and {round((p.header.stamp.sec + p.header.stamp.nanosec * 1e-9) * 1e6) for p in poses} <= ok
    values = [({kv.key: kv.value for kv in m.status[0].values}, m.status[0].level) for m in diagnostics]
    assert any(v["consistency"] == "passed" and level == 0 for v, level in values)
    failed = [(v, level) for v, level in values if "inconsistent_readings" in json.loads(v["flags"])]
    assert failed and all(v["consistency"] == "failed" and level == 2 for v, level in failed)
    assert any(v["consistency_isolated"] == "leg3" for v, _ in failed)
