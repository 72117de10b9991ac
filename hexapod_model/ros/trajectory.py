"""A changeover plan as a ROS 2 ``trajectory_msgs/JointTrajectory`` in an MCAP file.

One message on ``/hexapod/changeover/trajectory`` (:data:`TOPIC`): the UR10's joint names and,
per point of the plan, ``positions`` (rad), ``velocities`` (rad/s), ``accelerations`` (rad/s^2)
and ``time_from_start``; the header's frame is the robot's base (``base_link``) and its stamp
the file's writing time. Serialised as CDR with ``rosbags``' ROS 2 type store (``ros`` extra),
so ``ros2 bag play`` can send it to a ``joint_trajectory_controller``.
"""

from __future__ import annotations

import io
import time
from pathlib import Path

from ..extras import require
from ..files import atomic_write_bytes
from ..planning.model import Plan

TOPIC = "/hexapod/changeover/trajectory"
TYPE = "trajectory_msgs/msg/JointTrajectory"
FRAME = "base_link"


def trajectory_message(plan: Plan, stamp: float, store):
    """The plan as a ``JointTrajectory`` of ``store`` (a ``rosbags`` type store), stamped ``stamp`` (Unix s)."""
    types = store.types
    Time, Duration = types["builtin_interfaces/msg/Time"], types["builtin_interfaces/msg/Duration"]
    Header, Point = types["std_msgs/msg/Header"], types["trajectory_msgs/msg/JointTrajectoryPoint"]
    import numpy as np

    def duration(t: float):
        ns = round(t * 1e9)
        return Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    sec = int(stamp)
    header = Header(stamp=Time(sec=sec, nanosec=int((stamp - sec) * 1e9)), frame_id=FRAME)
    points = [
        Point(
            positions=np.array(plan.q[k], dtype=np.float64),
            velocities=np.array(plan.qd[k], dtype=np.float64),
            accelerations=np.array(plan.qdd[k], dtype=np.float64),
            effort=np.zeros(0, dtype=np.float64),
            time_from_start=duration(float(plan.t[k] - plan.t[0])),
        )
        for k in range(len(plan.t))
    ]
    return types[TYPE](header=header, joint_names=list(plan.joint_names), points=points)


def write_trajectory_mcap(plan: Plan, path: str | Path, stamp: float | None = None) -> Path:
    """Write the plan's ``JointTrajectory`` on :data:`TOPIC` as a ROS 2 MCAP bag (atomically).

    Raises:
        MissingExtraError: ``mcap`` or ``rosbags`` is not installed (the ``ros`` extra).
    """
    what = "MCAP files"
    require("mcap", "ros", what)
    require("rosbags", "ros", what)
    from mcap.writer import CompressionType, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    stamp = time.time() if stamp is None else stamp
    msg = trajectory_message(plan, stamp, store)
    buffer = io.BytesIO()
    writer = Writer(buffer, compression=CompressionType.ZSTD)
    writer.start(profile="ros2", library="hexapod_model")
    schema = writer.register_schema(TYPE, "ros2msg", store.generate_msgdef(TYPE, ros_version=2)[0].encode())
    channel = writer.register_channel(TOPIC, "cdr", schema)
    ns = round(stamp * 1e9)
    writer.add_message(channel, log_time=ns, data=bytes(store.serialize_cdr(msg, TYPE)), publish_time=ns, sequence=0)
    writer.finish()
    return atomic_write_bytes(path, buffer.getvalue())
