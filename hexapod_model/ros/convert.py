"""The service's records as ROS 2 messages: stamps, frames, poses, joint states, diagnostics.

* Frames: ``<fixture>/base`` (the base frame of the kinematic model) and ``<fixture>/platform``.
* A pose (``PoseStamped``, the ``/tf`` transform, the passive joints of a ``JointState``) is made
  only from an ``ok`` record: :func:`pose_stamped`, :func:`transform` and :func:`joint_state`
  return None for any other, so that a ROS consumer never receives a pose the service would not
  call good.
* Diagnostic levels: ``OK`` for an ``ok`` record without flags; ``WARN`` for an ``ok`` record with
  an advisory flag or an unhealthy store, and for a doubted pose (``flagged``, ``drift``);
  ``STALE`` before the first reading (``no_data``); ``ERROR`` for every other record (no pose:
  failed or faulty readings; readings failing a redundant fixture's consistency test,
  ``inconsistent_readings``, even with the others' estimate; or a latched fault waiting for its
  acknowledgement).
"""

from __future__ import annotations

import json
import math

import numpy as np

from ..lie import matrix_to_quaternion
from ..service.record.pose_record import PoseRecord
from .messages import (  # cyclonedds: the ros extra
    DiagnosticStatus,
    Header,
    JointState,
    KeyValue,
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    Time,
    Transform,
    TransformStamped,
    Vector3,
)
from .names import FixtureNames
from .redundancy import consistency_values

OK, WARN, ERROR, STALE = 0, 1, 2, 3  # diagnostic_msgs/DiagnosticStatus levels


def stamp(t: float) -> Time:
    """The ROS time of Unix seconds ``t``: whole seconds and the fraction in nanoseconds, rounded to nearest."""
    sec = math.floor(t)
    nanosec = round((t - sec) * 1e9)  # t - sec is exact
    if nanosec == 1_000_000_000:
        sec, nanosec = sec + 1, 0
    return Time(int(sec), int(nanosec))


def seconds(time: Time) -> float:
    """Unix seconds of a ROS time."""
    return time.sec + time.nanosec * 1e-9


def _good_pose(rec: PoseRecord) -> dict | None:
    return rec.pose if rec.status == "ok" and rec.pose is not None else None


def pose_stamped(rec: PoseRecord, names: FixtureNames) -> PoseStamped | None:
    """The platform pose (m) in ``<fixture>/base`` of an ``ok`` record, else None."""
    p = _good_pose(rec)
    if p is None:
        return None
    position, orientation = _pose(p)
    return PoseStamped(Header(stamp(rec.t), names.base), Pose(Point(*position), orientation))


def transform(rec: PoseRecord, names: FixtureNames) -> TransformStamped | None:
    """``<fixture>/base`` -> ``<fixture>/platform`` of an ``ok`` record, else None."""
    p = _good_pose(rec)
    if p is None:
        return None
    position, orientation = _pose(p)
    return TransformStamped(
        Header(stamp(rec.t), names.base), names.platform, Transform(Vector3(*position), orientation)
    )


def _pose(p: dict) -> tuple[tuple[float, float, float], Quaternion]:
    return (p["x"], p["y"], p["z"]), Quaternion(p["qx"], p["qy"], p["qz"], p["qw"])


def joint_state(rec: PoseRecord, names: FixtureNames, q: np.ndarray | None) -> JointState | None:
    """The one-dof joints of an ``ok`` record: all of them from its configuration ``q``, else None.

    Without ``q`` (a stored sample) the six prismatic joints only, from the record's readings of
    the six legs (the first six: a measuring leg or an inclinometer is no URDF joint).
    Prismatic values are joint values (m) as the URDF has them: the readings, through the URDF's
    encoder model when it has one (``(reading - zero) / gain``; the caller's ``q`` already holds
    joint values).
    """
    if _good_pose(rec) is None:
        return None
    header = Header(stamp(rec.t), "")
    if q is not None:
        return JointState(header, list(names.joints), [float(q[i]) for i in names.joint_q])
    legs = rec.readings[: len(names.prismatic)]
    readings = [float(r) for r in legs if r is not None]
    if len(readings) < len(names.prismatic):
        return None
    if names.encoder is not None:
        zero, gain = names.encoder
        readings = [(r - z) / g for r, z, g in zip(readings, zero, gain)]
    return JointState(header, list(names.prismatic), readings)


def level(rec: PoseRecord, store_error: str | None = None) -> int:
    """The diagnostic level of a record (module docstring)."""
    status = rec.status
    if status == "ok":
        return WARN if rec.flags or store_error else OK
    if status in ("flagged", "drift"):  # a pose the service doubts
        return WARN
    return STALE if status == "no_data" else ERROR


def diagnostic(
    rec: PoseRecord, names: FixtureNames, hardware_id: str, store_error: str | None = None
) -> DiagnosticStatus:
    """One fixture's ``DiagnosticStatus``: its status, flags, state, sigma, singularity margin and store health.

    A fixture with redundant sensors adds its consistency test
    (:func:`~hexapod_model.ros.redundancy.consistency_values`).
    """
    sigma = rec.sigma or {}
    values = {
        "status": rec.status,
        "flags": json.dumps(rec.flags),
        "state": rec.state,
        "stored": json.dumps(rec.stored),
        "t": repr(rec.t),
        "sigma_translation_mm": _text(sigma.get("translation_mm")),
        "sigma_rotation_deg": _text(sigma.get("rotation_deg")),
        "singularity_margin": _text(rec.singularity_margin),
        "store": "ok" if store_error is None else store_error,
        **consistency_values(rec, names),
    }
    flags = ", ".join(rec.flags)
    message = rec.status + (f" ({flags})" if flags else "") + ("" if store_error is None else "; store error")
    return DiagnosticStatus(
        level(rec, store_error),
        f"hexapod: {names.fixture}",
        message,
        hardware_id,
        [KeyValue(k, v) for k, v in values.items()],
    )


def _text(v: float | None) -> str:
    return "" if v is None else repr(float(v))


def placement(base_in_robot: object, robot_frame: str, names: FixtureNames, t: float) -> TransformStamped:
    """``robot_frame`` -> ``<fixture>/base`` of a fixture's cell placement.

    Args:
        base_in_robot: the base frame in the robot's (4x4 homogeneous, m), or six numbers
            ``x, y, z`` (m), ``roll, pitch, yaw`` (deg).
        robot_frame: the parent frame.
        names: the fixture's names.
        t: stamp (Unix seconds).
    """
    T = _homogeneous(base_in_robot)
    x, y, z, w = matrix_to_quaternion(T[:3, :3])
    return TransformStamped(
        Header(stamp(t), robot_frame),
        names.base,
        Transform(Vector3(*(float(v) for v in T[:3, 3])), Quaternion(float(x), float(y), float(z), float(w))),
    )


def _homogeneous(value: object) -> np.ndarray:
    from ..lie import xyz_rpy_to_pose

    a = np.asarray(getattr(value, "homogeneous", value), dtype=float)
    if a.shape == (4, 4):
        return a
    if a.shape == (6,):
        return xyz_rpy_to_pose(a)
    raise ValueError(f"base_in_robot: expected a 4x4 transform or x, y, z, roll, pitch, yaw, got shape {a.shape}")
