"""The CDR bytes of the published messages, decoded by rosbags (an independent CDR implementation)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from hexapod_model.service.record.pose_record import PoseRecord

from .conftest import need_extra

pytestmark = pytest.mark.ros


@pytest.fixture(scope="module")
def ros():
    need_extra()
    from rosbags.typesys import Stores, get_typestore

    from hexapod_model import Hexapod
    from hexapod_model.ros import convert
    from hexapod_model.ros.names import FixtureNames

    hexa = Hexapod.from_preset("reference", compiled=False)
    return convert, FixtureNames.of("right", "cell/hexapod", hexa), hexa, get_typestore(Stores.ROS2_JAZZY)


def record(status="ok", flags=(), t=1795672991.5198855):
    return PoseRecord(
        "right",
        t,
        [0.001, -0.002, 0.0031, 0.0, 1e-6, -0.004],
        {"x": 0.01, "y": -0.02, "z": 0.41, "qx": 0.1, "qy": -0.2, "qz": 0.3, "qw": math.sqrt(0.86)},
        status,
        list(flags),
        3,
        "locked",
        True,
        {"translation_mm": 0.0249, "rotation_deg": 0.006},
        0.95,
        None,
        None,
    )


def decode(store, msg, name):
    data = msg.serialize()
    assert data[:4] == b"\x00\x01\x00\x00"  # CDR little endian: what ROS 2 middlewares write
    out = store.deserialize_cdr(data, name)
    assert store.serialize_cdr(out, name).tobytes() == data  # and rosbags writes the same bytes back
    return out


def test_pose_stamped_decodes_to_the_record(ros):
    convert, names, _, store = ros
    rec = record()
    m = decode(store, convert.pose_stamped(rec, names), "geometry_msgs/msg/PoseStamped")
    assert m.header.frame_id == "right/base"
    assert m.header.stamp.sec == 1795672991 and abs(m.header.stamp.nanosec - 519885540) <= 1
    p = rec.pose
    got = [m.pose.position.x, m.pose.position.y, m.pose.position.z]
    got += [m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w]
    assert got == [p[k] for k in ("x", "y", "z", "qx", "qy", "qz", "qw")]  # the same floats, carried


def test_transform_and_joint_state_decode(ros):
    convert, names, hexa, store = ros
    from hexapod_model.ros.messages import TFMessage

    rec = record()
    tf = decode(store, TFMessage([convert.transform(rec, names)]), "tf2_msgs/msg/TFMessage")
    (t,) = tf.transforms
    assert (t.header.frame_id, t.child_frame_id) == ("right/base", "right/platform")
    assert t.transform.translation.z == 0.41 and t.transform.rotation.w == rec.pose["qw"]
    q = hexa.q_home.copy()
    q[: hexa.nq - 7] = np.linspace(-0.3, 0.3, hexa.nq - 7)
    js = decode(store, convert.joint_state(rec, names, q), "sensor_msgs/msg/JointState")
    assert js.name == [n for n in hexa.joint_names if n != "platform_joint"]
    assert len(js.position) == 36 and list(js.position) == [
        q[hexa.model.joints[hexa.model.getJointId(n)].idx_q] for n in js.name
    ]
    legs = decode(store, convert.joint_state(rec, names, None), "sensor_msgs/msg/JointState")
    assert legs.name == list(hexa.prismatic_names) and list(legs.position) == rec.readings


@pytest.mark.parametrize(
    "status", ["flagged", "drift", "unacknowledged_fault", "not_converged", "encoder_error", "silent_leg", "no_data"]
)
def test_no_pose_transform_or_joints_from_a_record_that_is_not_ok(ros, status):
    convert, names, hexa, _ = ros
    rec = record(status, ["jump"] if status == "flagged" else [])
    assert convert.pose_stamped(rec, names) is None
    assert convert.transform(rec, names) is None
    assert convert.joint_state(rec, names, hexa.q_home) is None


@pytest.mark.parametrize(
    ("status", "flags", "store_error", "level"),
    [
        ("ok", [], None, 0),
        ("ok", ["drift"], None, 1),
        ("ok", [], "disk full", 1),
        ("flagged", ["jump"], None, 1),
        ("drift", ["drift:leg2"], None, 1),
        ("unacknowledged_fault", ["step:leg1"], None, 2),
        ("encoder_error", ["encoder_error:leg3"], None, 2),
        ("not_converged", ["max_iterations"], None, 2),
        ("no_data", [], None, 3),
    ],
)
def test_diagnostic_levels_and_values(ros, status, flags, store_error, level):
    convert, names, _, store = ros
    from hexapod_model.ros.messages import DiagnosticArray, Header

    rec = record(status, flags)
    status_msg = convert.diagnostic(rec, names, "cell/hexapod/right", store_error)
    arr = decode(
        store, DiagnosticArray(Header(convert.stamp(rec.t), ""), [status_msg]), "diagnostic_msgs/msg/DiagnosticArray"
    )
    (s,) = arr.status
    values = {kv.key: kv.value for kv in s.values}
    assert s.level == level and s.name == "hexapod: right" and s.hardware_id == "cell/hexapod/right"
    assert values["status"] == status and values["flags"] == str(flags).replace("'", '"')
    assert values["sigma_translation_mm"] == "0.0249" and values["store"] == (store_error or "ok")


def test_stamp_is_the_nearest_nanosecond_and_carries(ros):
    convert = ros[0]
    assert (convert.stamp(12.5).sec, convert.stamp(12.5).nanosec) == (12, 500_000_000)
    s = convert.stamp(1.9999999999)
    assert (s.sec, s.nanosec) == (2, 0)
    s = convert.stamp(1795672991.5198855)
    assert abs(convert.seconds(s) - 1795672991.5198855) < 1e-6


def test_placement_on_tf_static(ros):
    convert, names, _, store = ros
    from hexapod_model.lie import rpy_to_matrix
    from hexapod_model.ros.messages import TFMessage

    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(0.0, 0.0, math.pi / 2)
    T[:3, 3] = [0.5, -0.25, 0.1]
    for value in (T, [0.5, -0.25, 0.1, 0.0, 0.0, 90.0]):
        msg = decode(
            store, TFMessage([convert.placement(value, "ur10e/base_link", names, 5.0)]), "tf2_msgs/msg/TFMessage"
        )
        (t,) = msg.transforms
        assert (t.header.frame_id, t.child_frame_id) == ("ur10e/base_link", "right/base")
        r = t.transform.rotation
        assert np.allclose([r.x, r.y, r.z, r.w], [0, 0, math.sqrt(0.5), math.sqrt(0.5)], atol=1e-15)
        assert [t.transform.translation.x, t.transform.translation.y] == [0.5, -0.25]
    with pytest.raises(ValueError, match="base_in_robot"):
        convert.placement([1.0, 2.0], "robot", names, 0.0)


def test_cyclone_configuration_stays_on_this_machine_unless_peers_are_given():
    from hexapod_model.ros.dds import cyclone_xml
    from hexapod_model.service.config.ros import RosConfig

    local = cyclone_xml(RosConfig())
    assert '<NetworkInterface address="127.0.0.1"/>' in local and "<AllowMulticast>false</AllowMulticast>" in local
    assert '<Peers><Peer address="127.0.0.1"/></Peers>' in local
    assert "<SPDPInterval>1s</SPDPInterval>" in local  # a node started later finds the service within 1 s
    cell = cyclone_xml(RosConfig(interface="192.168.10.2", peers=("192.168.10.5", "192.168.10.6")))
    assert '<NetworkInterface address="192.168.10.2"/>' in cell and "<AllowMulticast>false</AllowMulticast>" in cell
    assert '<Peer address="192.168.10.5"/><Peer address="192.168.10.6"/>' in cell


@pytest.mark.parametrize("frame", ["", "a", "abc", "abcd", "right/base"])
def test_packed_bytes_equal_cyclonedds_own_serialiser(ros, frame):
    """PoseStamped, TFMessage and JointState pack their CDR themselves: the bytes cyclonedds would write."""
    from cyclonedds.idl import IdlStruct

    from hexapod_model.ros.messages import (
        Header,
        JointState,
        Point,
        Pose,
        PoseStamped,
        Quaternion,
        TFMessage,
        Time,
        Transform,
        TransformStamped,
        Vector3,
    )

    stamp = Time(1795672991, 519885540)
    msgs = [PoseStamped(Header(stamp, frame), Pose(Point(0.1, -2.0, 3e-9), Quaternion(0.1, 0.2, 0.3, 0.9)))]
    for n in range(3):
        transforms = [
            TransformStamped(
                Header(Time(k, 7 * k), frame * k),
                frame + "c" * k,
                Transform(Vector3(1.0, 2.0, 3.0), Quaternion(0.0, 0.0, 0.6, 0.8)),
            )
            for k in range(n)
        ]
        msgs.append(TFMessage(transforms))
    for names in ([], ["a"], ["ab", "cde", "leg1_prismatic"], [f"j{k}" for k in range(36)]):
        for extra in ([], [0.5, -1.0]):
            msgs.append(JointState(Header(stamp, frame), names, [0.1 * k for k in range(len(names))], extra, extra))
    for m in msgs:
        assert m.serialize() == IdlStruct.serialize(m), m
    assert type(msgs[0]).deserialize(msgs[0].serialize()) == msgs[0]


@pytest.fixture(scope="module", params=["reference7", "reference_tilt"])
def redundant(request):
    need_extra()
    from hexapod_model import Hexapod
    from hexapod_model.ros.names import FixtureNames

    hexa = Hexapod.from_preset(request.param, compiled=False)
    return request.param, hexa, FixtureNames.of("right", "cell/hexapod", hexa)


def test_a_redundant_fixtures_joint_states_are_its_urdf_joints_and_six_legs(ros, redundant):
    """The seventh leg is a distance closure between two fixed links, the inclinometer a fixed link: no joint."""
    import xml.etree.ElementTree as ET
    from pathlib import Path

    convert, _, _, store = ros
    preset, hexa, names = redundant
    urdf = ET.parse(Path(__file__).resolve().parents[2] / "urdf" / f"{preset}.urdf").getroot()
    movable = [j.get("name") for j in urdf.iter("joint") if j.get("type") not in ("fixed", "floating")]
    assert list(names.joints) == movable and len(movable) == 36
    assert names.readings == hexa.reading_names and names.redundant
    rec = record()._replace(readings=[0.001, -0.002, 0.0031, 0.0, 1e-6, -0.004])  # a record: the six legs'
    q = hexa.q_home.copy()
    q[: hexa.nq - 7] = np.linspace(-0.3, 0.3, hexa.nq - 7)
    js = decode(store, convert.joint_state(rec, names, q), "sensor_msgs/msg/JointState")
    assert js.name == movable and len(js.position) == len(js.name)
    legs = decode(store, convert.joint_state(rec, names, None), "sensor_msgs/msg/JointState")
    assert legs.name == list(hexa.prismatic_names) and list(legs.position) == rec.readings


def test_joint_states_of_a_record_with_every_reading_name_the_six_legs_only(ros, redundant):
    convert, _, _, store = ros
    _, hexa, names = redundant
    every = [1e-3 * (k + 1) for k in range(len(hexa.reading_names))]  # legs first, then leg7 or tilt_x, tilt_y
    legs = decode(
        store, convert.joint_state(record()._replace(readings=every), names, None), "sensor_msgs/msg/JointState"
    )
    assert legs.name == list(hexa.prismatic_names) and list(legs.position) == every[:6]


def diagnostic_values(convert, store, rec, names):
    from hexapod_model.ros.messages import DiagnosticArray, Header

    msg = DiagnosticArray(Header(convert.stamp(rec.t), ""), [convert.diagnostic(rec, names, "cell/hexapod/right")])
    (s,) = decode(store, msg, "diagnostic_msgs/msg/DiagnosticArray").status
    return s.level, {kv.key: kv.value for kv in s.values}


@pytest.mark.parametrize(
    ("status", "flags", "pose", "level", "verdict", "isolated", "suspects"),
    [
        ("ok", [], True, 0, "passed", "", ""),
        ("flagged", ["jump"], True, 1, "passed", "", ""),
        (
            "inconsistent_readings",
            ["inconsistent_readings", "isolated:leg3", "estimate"],
            True,
            2,
            "failed",
            "leg3",
            "",
        ),
        ("inconsistent_readings", ["inconsistent_readings", "suspects:7"], False, 2, "failed", "", "7"),
        (
            "unacknowledged_fault",
            ["inconsistent_readings", "isolated:tilt_x", "estimate"],
            True,
            2,
            "failed",
            "tilt_x",
            "",
        ),
        ("encoder_error", ["encoder_error:leg7"], False, 2, "", "", ""),
        ("no_data", [], False, 3, "", "", ""),
    ],
)
def test_a_redundant_fixtures_diagnostics_carry_its_consistency_test(
    ros, redundant, status, flags, pose, level, verdict, isolated, suspects
):
    from scipy.stats import chi2

    convert, _, _, store = ros
    _, hexa, names = redundant
    rec = record(status, flags)
    if not pose:
        rec = rec._replace(pose=None)
    got, values = diagnostic_values(convert, store, rec, names)
    dof = len(hexa.reading_names) - 6
    assert got == level and values["status"] == status
    assert values["consistency"] == verdict
    assert (values["consistency_isolated"], values["consistency_suspects"]) == (isolated, suspects)
    assert json.loads(values["consistency_readings"]) == list(hexa.reading_names)
    assert values["consistency_dof"] == str(dof) and float(values["consistency_false_alarm_rate"]) == 1e-3
    assert float(values["consistency_chi2_bound"]) == pytest.approx(chi2.ppf(1 - 1e-3, dof), rel=1e-9)
    if status != "ok":
        assert convert.pose_stamped(rec, names) is None and convert.joint_state(rec, names, hexa.q_home) is None


def test_six_legs_diagnostics_carry_no_consistency_test(ros):
    convert, names, _, store = ros
    _, values = diagnostic_values(convert, store, record(), names)
    assert not names.redundant and not [k for k in values if k.startswith("consistency")]
    assert list(values) == [
        "status",
        "flags",
        "state",
        "stored",
        "t",
        "sigma_translation_mm",
        "sigma_rotation_deg",
        "singularity_margin",
        "store",
    ]


def test_joint_states_without_a_configuration_are_joint_values_through_the_encoder_model(ros):
    """A stored sample keeps readings; a calibrated fixture's reading is not its prismatic joint value."""
    from hexapod_model import Hexapod, get_preset
    from hexapod_model.description.geometry import geometry_from_dict
    from hexapod_model.ros.names import FixtureNames

    convert, _, _, store = ros
    d = get_preset("reference").to_dict()
    for k, leg in enumerate(d["legs"]):
        leg["encoder_zero"], leg["encoder_scale"] = 1e-3 * (k - 2.5), 2e-3 * (k - 3)
    hexa = Hexapod.from_geometry(geometry_from_dict(d), compiled=False)
    names = FixtureNames.of("right", "cell/hexapod", hexa)
    rec = record()
    js = decode(store, convert.joint_state(rec, names, None), "sensor_msgs/msg/JointState")
    joints = hexa.joints_of(np.array(rec.readings))
    assert js.name == list(hexa.prismatic_names)
    assert np.max(np.abs(np.array(js.position) - joints)) <= 1e-15  # m; the readings are up to 2.5 mm off them
    q = hexa.q_home.copy()  # the same through a configuration: the URDF's prismatic joints hold joint values
    q[hexa.model.joints[hexa.model.getJointId(js.name[2])].idx_q] = joints[2]
    live = convert.joint_state(rec, names, q)
    assert live.position[live.name.index(js.name[2])] == joints[2]
