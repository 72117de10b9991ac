"""The ROS 2 message types the service publishes, as Cyclone DDS IDL structs (ROS 2's DDS names).

ROS 2 maps a message ``pkg/msg/Name`` to the DDS type ``pkg::msg::dds_::Name_`` whose members
are the ``.msg`` fields in their order (``rosidl_generator_dds_idl``); the CDR bytes of these
structs are then those of every ROS 2 middleware. ``byte`` fields are IDL ``octet``; ``string``
is unbounded; ``float64[]`` a sequence. Only the types :mod:`hexapod_model.ros.convert` fills
are defined: ``builtin_interfaces/Time``, ``std_msgs/Header``, ``geometry_msgs/{Point,
Quaternion, Pose, PoseStamped, Vector3, Transform, TransformStamped}``, ``tf2_msgs/TFMessage``,
``sensor_msgs/JointState`` and ``diagnostic_msgs/{KeyValue, DiagnosticStatus, DiagnosticArray}``.
"""

# no `from __future__ import annotations`: cyclonedds resolves the annotations at run time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import byte, float64, int32, uint32

if TYPE_CHECKING:  # type checkers see the lists the fields hold
    from builtins import list as sequence
else:
    from cyclonedds.idl.types import sequence


def _dds(ros_name: str) -> str:
    """``pkg/msg/Name`` -> ``pkg::msg::dds_::Name_``."""
    pkg, kind, name = ros_name.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


@dataclass
class Time(IdlStruct, typename=_dds("builtin_interfaces/msg/Time")):
    """Seconds and nanoseconds since the Unix epoch."""

    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename=_dds("std_msgs/msg/Header")):
    """Stamp and frame of a message."""

    stamp: Time
    frame_id: str


@dataclass
class Point(IdlStruct, typename=_dds("geometry_msgs/msg/Point")):
    """A position (m)."""

    x: float64
    y: float64
    z: float64


@dataclass
class Vector3(IdlStruct, typename=_dds("geometry_msgs/msg/Vector3")):
    """A translation (m)."""

    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename=_dds("geometry_msgs/msg/Quaternion")):
    """An orientation, ``x, y, z, w``."""

    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Pose(IdlStruct, typename=_dds("geometry_msgs/msg/Pose")):
    """Position and orientation."""

    position: Point
    orientation: Quaternion


@dataclass
class PoseStamped(IdlStruct, typename=_dds("geometry_msgs/msg/PoseStamped")):
    """A pose in the header's frame."""

    header: Header
    pose: Pose


@dataclass
class Transform(IdlStruct, typename=_dds("geometry_msgs/msg/Transform")):
    """Translation (m) and rotation of a child frame in its parent."""

    translation: Vector3
    rotation: Quaternion


@dataclass
class TransformStamped(IdlStruct, typename=_dds("geometry_msgs/msg/TransformStamped")):
    """``header.frame_id`` -> ``child_frame_id``."""

    header: Header
    child_frame_id: str
    transform: Transform


@dataclass
class TFMessage(IdlStruct, typename=_dds("tf2_msgs/msg/TFMessage")):
    """The ``/tf`` and ``/tf_static`` message."""

    transforms: sequence[TransformStamped]


@dataclass
class JointState(IdlStruct, typename=_dds("sensor_msgs/msg/JointState")):
    """Joint positions (m or rad) by URDF joint name; velocity and effort left empty."""

    header: Header
    name: sequence[str]
    position: sequence[float64]
    velocity: sequence[float64] = field(default_factory=list)
    effort: sequence[float64] = field(default_factory=list)


@dataclass
class KeyValue(IdlStruct, typename=_dds("diagnostic_msgs/msg/KeyValue")):
    """One diagnostic value."""

    key: str
    value: str


@dataclass
class DiagnosticStatus(IdlStruct, typename=_dds("diagnostic_msgs/msg/DiagnosticStatus")):
    """One component's level (``OK`` 0, ``WARN`` 1, ``ERROR`` 2, ``STALE`` 3), message and values."""

    level: byte
    name: str
    message: str
    hardware_id: str
    values: sequence[KeyValue]


@dataclass
class DiagnosticArray(IdlStruct, typename=_dds("diagnostic_msgs/msg/DiagnosticArray")):
    """The ``/diagnostics`` message."""

    header: Header
    status: sequence[DiagnosticStatus]


#: ROS 2 name of each message type (``pkg/msg/Name``), for type hashes and bag schemas
ROS_NAMES: dict[type, str] = {
    PoseStamped: "geometry_msgs/msg/PoseStamped",
    JointState: "sensor_msgs/msg/JointState",
    TFMessage: "tf2_msgs/msg/TFMessage",
    DiagnosticArray: "diagnostic_msgs/msg/DiagnosticArray",
}
