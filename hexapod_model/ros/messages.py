"""The ROS 2 message types the service publishes, as Cyclone DDS IDL structs (ROS 2's DDS names).

ROS 2 maps a message ``pkg/msg/Name`` to the DDS type ``pkg::msg::dds_::Name_`` whose members
are the ``.msg`` fields in their order (``rosidl_generator_dds_idl``); the CDR bytes of these
structs are then those of every ROS 2 middleware. ``byte`` fields are IDL ``octet``; ``string``
is unbounded; ``float64[]`` a sequence. Only the types :mod:`hexapod_model.ros.convert` fills
are defined: ``builtin_interfaces/Time``, ``std_msgs/Header``, ``geometry_msgs/{Point,
Quaternion, Pose, PoseStamped, Vector3, Transform, TransformStamped}``, ``tf2_msgs/TFMessage``,
``sensor_msgs/JointState``, ``diagnostic_msgs/{KeyValue, DiagnosticStatus, DiagnosticArray}``
and ``std_msgs/String``.
"""

# no `from __future__ import annotations`: cyclonedds resolves the annotations at run time
import functools
import struct
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cyclonedds.idl import IdlStruct
from cyclonedds.idl._support import Endianness
from cyclonedds.idl.types import byte, float64, int32, uint32

if TYPE_CHECKING:  # type checkers see the lists the fields hold
    from builtins import list as sequence
else:
    from cyclonedds.idl.types import sequence


def _dds(ros_name: str) -> str:
    """``pkg/msg/Name`` -> ``pkg::msg::dds_::Name_``."""
    pkg, kind, name = ros_name.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


class _Fast(IdlStruct):
    """A message whose writers' bytes (little-endian plain CDR) are packed here.

    cyclonedds's own serialiser walks the type field by field in Python (about 0.3 ms for the 36
    joints of a hexapod's JointState); the published types pack their fixed layout with
    :mod:`struct` instead: the same bytes (a test compares them), several times faster.
    """

    def serialize(self, buffer=None, endianness=None, use_version_2: bool | None = None) -> bytes:
        """Little-endian plain CDR with its encapsulation header, else cyclonedds's serialiser."""
        if buffer is None and endianness in (None, Endianness.Little) and not use_version_2:
            out = bytearray(b"\x00\x01\x00\x00")
            self._cdr(out)
            return bytes(out)
        return super().serialize(buffer, endianness, use_version_2)

    def _cdr(self, out: bytearray) -> None:
        raise NotImplementedError


def _align(out: bytearray, n: int) -> None:
    out += b"\0" * (-(len(out) - 4) % n)  # offsets count from the end of the 4-byte encapsulation header


def _header(out: bytearray, header: "Header") -> None:
    _align(out, 4)
    out += struct.pack("<iI", header.stamp.sec, header.stamp.nanosec)
    out += _strings((header.frame_id,))[4:]  # one string: no count


def _doubles(out: bytearray, values, count: bool = False) -> None:
    """float64 values (a sequence's length first when ``count``), aligned to 8 as XCDR1 does."""
    if count:
        _align(out, 4)
        out += struct.pack("<I", len(values))
        if not len(values):
            return
    _align(out, 8)
    out += struct.pack(f"<{len(values)}d", *values)


@functools.lru_cache(maxsize=256)
def _strings(strings: tuple[str, ...]) -> bytes:
    """A CDR ``sequence<string>`` starting 4-aligned (count, then per string: length with its NUL, bytes)."""
    out = bytearray(struct.pack("<I", len(strings)))
    for text in strings:
        out += b"\0" * (-len(out) % 4)
        data = text.encode() + b"\0"
        out += struct.pack("<I", len(data)) + data
    return bytes(out)


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
class PoseStamped(_Fast, typename=_dds("geometry_msgs/msg/PoseStamped")):
    """A pose in the header's frame."""

    header: Header
    pose: Pose

    def _cdr(self, out: bytearray) -> None:
        _header(out, self.header)
        p, o = self.pose.position, self.pose.orientation
        _doubles(out, (p.x, p.y, p.z, o.x, o.y, o.z, o.w))


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
class TFMessage(_Fast, typename=_dds("tf2_msgs/msg/TFMessage")):
    """The ``/tf`` and ``/tf_static`` message."""

    transforms: sequence[TransformStamped]

    def _cdr(self, out: bytearray) -> None:
        out += struct.pack("<I", len(self.transforms))
        for t in self.transforms:
            _header(out, t.header)
            _align(out, 4)
            out += _strings((t.child_frame_id,))[4:]
            v, r = t.transform.translation, t.transform.rotation
            _doubles(out, (v.x, v.y, v.z, r.x, r.y, r.z, r.w))


@dataclass
class JointState(_Fast, typename=_dds("sensor_msgs/msg/JointState")):
    """Joint positions (m or rad) by URDF joint name; velocity and effort left empty."""

    header: Header
    name: sequence[str]
    position: sequence[float64]
    velocity: sequence[float64] = field(default_factory=list)
    effort: sequence[float64] = field(default_factory=list)

    def _cdr(self, out: bytearray) -> None:
        _header(out, self.header)
        for values in (self.name, self.position, self.velocity, self.effort):
            if values is self.name:
                _align(out, 4)
                out += _strings(tuple(values))
            else:
                _doubles(out, values, count=True)


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


@dataclass
class String(IdlStruct, typename=_dds("std_msgs/msg/String")):
    """A text: the changeover topics' JSON (guidance out, targets in, their results out)."""

    data: str


#: ROS 2 name of each message type (``pkg/msg/Name``), for type hashes and bag schemas
ROS_NAMES: dict[type, str] = {
    PoseStamped: "geometry_msgs/msg/PoseStamped",
    JointState: "sensor_msgs/msg/JointState",
    TFMessage: "tf2_msgs/msg/TFMessage",
    DiagnosticArray: "diagnostic_msgs/msg/DiagnosticArray",
    String: "std_msgs/msg/String",
}
