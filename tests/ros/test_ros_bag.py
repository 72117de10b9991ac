"""`hexapod fixture history --mcap`: the store as a ROS 2 bag, read back by mcap + mcap-ros2-support and rosbags."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest

from hexapod_model.cli import main
from hexapod_model.service import LockEvent, Store
from hexapod_model.service.record.pose_record import PoseRecord
from hexapod_model.service.store.fixture_store import sample_row

from .conftest import need_extra

pytestmark = pytest.mark.ros
POSE = ("x", "y", "z", "qx", "qy", "qz", "qw")
T0 = 1795672990.25
CONFIG = """
[bus]
interface = "virtual"
channel = "bag-test"
[store]
path = "store.sqlite"
[ros]
namespace = "cell"
[[fixtures]]
name = "left"
hexapod = "reference"
can_ids = [0x181, 0x182, 0x183, 0x184, 0x185, 0x186]
[[fixtures]]
name = "right"
hexapod = "reference"
can_ids = [0x191, 0x192, 0x193, 0x194, 0x195, 0x196]
"""


def rec(fixture, t, status, pose=True, flags=()):
    q = np.array([0.1, -0.2, 0.3, 0.0])
    q[3] = np.sqrt(1 - q @ q)
    values = [0.01 * (t - T0), -0.02, 0.41, *q]
    readings: list[float | None] = [0.001 * k + (t - T0) for k in range(6)]
    values_of = dict(zip(POSE, values)) if pose else None
    return PoseRecord(fixture, t, readings, values_of, status, list(flags), 0, "moving", None, None, None, None, None)


RECORDS = [
    rec("left", T0, "ok"),
    rec("right", T0 + 0.01, "ok", flags=["drift"]),
    rec("left", T0 + 0.02, "flagged", flags=["jump"]),
    rec("left", T0 + 0.03, "encoder_error", pose=False, flags=["encoder_error:leg3"]),
    rec("right", T0 + 0.04, "ok"),
]
LOCK = LockEvent(
    "right",
    T0 + 0.05,
    np.array([0.01, -0.02, 0.41]),
    np.array([0.0, 0.0, 0.6, 0.8]),
    np.full(6, 1e-3),
    "ok",
    "h",
    np.zeros(43),
)


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "fixture.toml"
    path.write_text(CONFIG)
    with Store(tmp_path / "store.sqlite") as store:
        store.add_samples([sample_row(r) for r in RECORDS])
        store.add_lock(LOCK)
    return path


def read_back(path):
    if importlib.util.find_spec("mcap_ros2") is None:
        pytest.skip("mcap-ros2-support not installed (the reader of this test): pip install mcap-ros2-support")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == "ros2"
        return [(c.topic, s.name, m.log_time, msg) for s, c, m, msg in reader.iter_decoded_messages()]


def test_history_as_a_ros2_bag_reads_back_with_another_implementation(config, capsys):
    need_extra()
    out = config.parent / "history.mcap"
    assert main(["fixture", "history", str(config), "--mcap", str(out)]) == 0
    assert "wrote 15 messages" in capsys.readouterr().err  # 3 ok x (pose, joints, tf) + 5 diagnostics + 1 lock
    msgs = read_back(out)
    times = [m[2] for m in msgs]
    assert times == sorted(times)
    by_topic: dict[str, list] = {}
    for topic, schema, t_ns, msg in msgs:
        by_topic.setdefault(topic, []).append((schema, t_ns, msg))
    assert sorted(by_topic) == [
        "/cell/left/joint_states",
        "/cell/left/pose",
        "/cell/right/joint_states",
        "/cell/right/lock_pose",
        "/cell/right/pose",
        "/diagnostics",
        "/tf",
    ]
    ok = [r for r in RECORDS if r.status == "ok"]
    poses = by_topic["/cell/left/pose"] + by_topic["/cell/right/pose"]
    assert len(poses) == len(ok)  # not the flagged nor the failed record
    for schema, t_ns, m in poses:
        assert schema == "geometry_msgs/msg/PoseStamped"
        r = next(r for r in ok if abs(r.t * 1e9 - t_ns) < 1e3)
        assert m.header.frame_id == f"{r.fixture}/base"
        assert m.header.stamp.sec * 10**9 + m.header.stamp.nanosec == t_ns
        p = m.pose
        got = [p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y, p.orientation.z]
        assert got + [p.orientation.w] == [r.pose[k] for k in POSE]
    (js,) = [m for _, _, m in by_topic["/cell/left/joint_states"]]
    assert js.name == [f"leg{k}_prismatic" for k in range(1, 7)] and list(js.position) == RECORDS[0].readings
    tfs = [m.transforms[0] for _, _, m in by_topic["/tf"]]
    assert [(t.header.frame_id, t.child_frame_id) for t in tfs] == [
        ("left/base", "left/platform"),
        ("right/base", "right/platform"),
        ("right/base", "right/platform"),
    ]
    levels = [(m.status[0].name, m.status[0].level) for _, _, m in by_topic["/diagnostics"]]
    assert levels == [
        ("hexapod: left", 0),
        ("hexapod: right", 1),
        ("hexapod: left", 1),
        ("hexapod: left", 2),
        ("hexapod: right", 0),
    ]
    ((_, t_ns, lock),) = by_topic["/cell/right/lock_pose"]
    assert abs(t_ns - LOCK.t * 1e9) < 1e3 and lock.pose.orientation.z == 0.6 and lock.pose.position.z == 0.41

    # rosbags reads the single file as a ROS 2 bag too: the same messages
    from rosbags.highlevel import AnyReader

    with AnyReader([out]) as reader:
        again = [(c.topic, c.msgtype, t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()]
    assert sorted((m[0], m[1], m[2]) for m in again) == sorted((m[0], m[1], m[2]) for m in msgs)
    pose = next(m[3] for m in again if m[0] == "/cell/right/pose")
    assert pose.pose.position.x == by_topic["/cell/right/pose"][0][2].pose.position.x


def test_one_fixture_since_a_time(config):
    need_extra()
    out = config.parent / "right.mcap"
    assert (
        main(["fixture", "history", str(config), "--mcap", str(out), "--fixture", "right", "--since", str(T0 + 0.02)])
        == 0
    )
    topics = [m[0] for m in read_back(out)]
    assert topics == ["/cell/right/pose", "/cell/right/joint_states", "/tf", "/diagnostics", "/cell/right/lock_pose"]


def test_mcap_output_may_not_overwrite_the_config(config, capsys):
    need_extra()
    assert main(["fixture", "history", str(config), "--mcap", str(config)]) != 0
    assert "fixture.toml" in capsys.readouterr().err


def test_mcap_with_csv_options_or_without_the_extra_is_one_clear_line(config, capsys, monkeypatch):
    out = str(config.parent / "x.mcap")
    assert main(["fixture", "history", str(config), "--mcap", out, "--samples"]) != 0
    assert "--mcap writes the sample log and the lock events" in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "mcap", None)  # as if not installed
    assert main(["fixture", "history", str(config), "--mcap", out]) != 0
    err = capsys.readouterr().err
    assert "pip install 'hexapod_model[ros]'" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
