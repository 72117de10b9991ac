"""The changeover plan a service plays, as a ROS 2 ``trajectory_msgs/JointTrajectory`` over DDS.

With ``[ros]`` on, ``hexapod serve ... --plan plan.json`` publishes the plan once on
``/hexapod/changeover/trajectory`` (:data:`~hexapod_model.ros.trajectory.TOPIC`; reliable,
transient local, keep last 1, so a controller that joins later gets it): the message
:func:`~hexapod_model.ros.trajectory.trajectory_message` writes to the MCAP file, here as Cyclone
DDS IDL structs under ROS 2's DDS names (``builtin_interfaces/Duration``,
``trajectory_msgs/{JointTrajectoryPoint, JointTrajectory}``; the header is
:class:`~hexapod_model.ros.messages.Header`).
"""

# no `from __future__ import annotations`: cyclonedds resolves the annotations at run time
from dataclasses import dataclass
from typing import TYPE_CHECKING

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float64, int32, uint32

from ..planning.model import Plan
from .messages import Header, Time
from .trajectory import FRAME

if TYPE_CHECKING:  # type checkers see the lists the fields hold
    from builtins import list as sequence
else:
    from cyclonedds.idl.types import sequence

#: the ROS 2 name of the published type (its type hash and schema)
ROS_NAME = "trajectory_msgs/msg/JointTrajectory"


@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    """A span of time: ``sec`` (s) and ``nanosec`` (ns, below 1e9)."""

    sec: int32
    nanosec: uint32


@dataclass
class JointTrajectoryPoint(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectoryPoint_"):
    """One point: rad, rad/s, rad/s^2 per joint (``effort`` empty) and its time from the start."""

    positions: sequence[float64]
    velocities: sequence[float64]
    accelerations: sequence[float64]
    effort: sequence[float64]
    time_from_start: Duration


@dataclass
class JointTrajectory(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectory_"):
    """The arm's whole joint trajectory."""

    header: Header
    joint_names: sequence[str]
    points: sequence[JointTrajectoryPoint]


def _duration(t: float) -> Duration:
    ns = round(t * 1e9)
    return Duration(ns // 1_000_000_000, ns % 1_000_000_000)


def trajectory(plan: Plan, stamp: float) -> JointTrajectory:
    """The plan's ``JointTrajectory`` stamped ``stamp`` (Unix s), frame ``base_link``, as the MCAP file holds it."""
    sec = int(stamp)
    points = [
        JointTrajectoryPoint(
            [float(v) for v in plan.q[k]],
            [float(v) for v in plan.qd[k]],
            [float(v) for v in plan.qdd[k]],
            [],
            _duration(float(plan.t[k] - plan.t[0])),
        )
        for k in range(len(plan.t))
    ]
    return JointTrajectory(Header(Time(sec, int((stamp - sec) * 1e9)), FRAME), list(plan.joint_names), points)
