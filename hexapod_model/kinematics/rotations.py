"""Rotation matrix <-> angles and quaternions, vectorised over leading axes (scipy ``Rotation``).

Convention used for printing and parsing everywhere (CLI, CSV): ``roll, pitch, yaw`` with
``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rotations about the fixed x, y, z axes, in that order; the
same as Pinocchio's ``pin.rpy``). Quaternions are ``(qx, qy, qz, qw)``, as in Pinocchio's
``XYZQUAT`` and ROS. These conversions are outside the solver's hot path; the solver's own
pose <-> free-flyer conversions are compiled kernels (:mod:`hexapod_model.kinematics.kernels`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from ..exceptions import InputError

EULER_ORDERS = ("xyz", "xzy", "yxz", "yzx", "zxy", "zyx")


def _matrices(R: ArrayLike) -> tuple[Rotation, tuple[int, ...]]:
    R = np.asarray(R, dtype=float)
    return Rotation.from_matrix(R.reshape(-1, 3, 3)), R.shape[:-2]


def rpy_to_matrix(roll: ArrayLike, pitch: ArrayLike, yaw: ArrayLike) -> np.ndarray:
    """(..., 3, 3) rotation ``Rz(yaw) Ry(pitch) Rx(roll)``; angles in radians."""
    angles = np.stack(np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (roll, pitch, yaw))), -1)
    return Rotation.from_euler("xyz", angles.reshape(-1, 3)).as_matrix().reshape(angles.shape[:-1] + (3, 3))


def matrix_to_rpy(R: ArrayLike) -> np.ndarray:
    """(..., 3) ``roll, pitch, yaw`` (rad) of rotation matrices; pitch in [-pi/2, pi/2]."""
    rot, shape = _matrices(R)
    return _euler(rot, "xyz").reshape(shape + (3,))


def quaternion_to_matrix(q: ArrayLike) -> np.ndarray:
    """(..., 3, 3) rotation of quaternions ``(qx, qy, qz, qw)``.

    The quaternion is divided by its norm: callers that must not accept a non-unit
    quaternion check its norm first.
    """
    q = np.asarray(q, dtype=float)
    flat = q.reshape(-1, 4)
    with np.errstate(invalid="ignore", over="ignore"):
        bad = ~(np.isfinite(np.linalg.norm(flat, axis=1)) & np.any(flat != 0, axis=1))
    R = Rotation.from_quat(np.where(bad[:, None], [0.0, 0.0, 0.0, 1.0], flat)).as_matrix()
    R[bad] = np.nan  # zero, NaN or infinite quaternions have no rotation: NaN, rejected downstream
    return R.reshape(q.shape[:-1] + (3, 3))


def matrix_to_quaternion(R: ArrayLike) -> np.ndarray:
    """(..., 4) unit quaternions ``(qx, qy, qz, qw)`` with ``qw >= 0``."""
    rot, shape = _matrices(R)
    return rot.as_quat(canonical=True).reshape(shape + (4,))


def rotation_angle(Ra: ArrayLike, Rb: ArrayLike) -> np.ndarray:
    """Angle (rad) of ``Ra^T Rb``: the minimal rotation between two orientations (eq. 27 of Bem et al.)."""
    E = np.swapaxes(np.asarray(Ra, dtype=float), -1, -2) @ np.asarray(Rb, dtype=float)
    c = (E[..., 0, 0] + E[..., 1, 1] + E[..., 2, 2] - 1.0) / 2.0
    s = 0.5 * np.sqrt(
        (E[..., 2, 1] - E[..., 1, 2]) ** 2 + (E[..., 0, 2] - E[..., 2, 0]) ** 2 + (E[..., 1, 0] - E[..., 0, 1]) ** 2
    )
    return np.arctan2(s, c)  # accurate near 0, unlike arccos of the trace


def axis_rotation(axis: str, angle: ArrayLike) -> np.ndarray:
    """(..., 3, 3) rotation by ``angle`` (rad) about the fixed ``axis`` (``"x"``, ``"y"`` or ``"z"``)."""
    if axis not in ("x", "y", "z"):
        raise InputError("rotation axis", axis, "choose x, y or z")
    a = np.asarray(angle, dtype=float)
    return Rotation.from_euler(axis, a.reshape(-1, 1)).as_matrix().reshape(a.shape + (3, 3))


def _check_order(order: str) -> str:
    if order not in EULER_ORDERS:
        raise InputError("rotation order", order, f"choose one of {EULER_ORDERS}")
    return order.upper()  # scipy: upper case = intrinsic = the product R_a(t1) R_b(t2) R_c(t3)


def _euler(rot: Rotation, seq: str) -> np.ndarray:
    """Euler angles without scipy's gimbal-lock warning (the third angle is 0 there)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return rot.as_euler(seq)


def euler_to_matrix(order: str, angles: ArrayLike) -> np.ndarray:
    """(..., 3, 3) ``R = R_a(t1) R_b(t2) R_c(t3)`` for ``order = "abc"`` (eq. 12 of Shi, She and Duan).

    ``angles[..., 0:3]`` are ``t1, t2, t3`` in radians, in the order of the factors; e.g.
    ``euler_to_matrix("zyx", [yaw, pitch, roll])`` equals ``rpy_to_matrix(roll, pitch, yaw)``.
    """
    seq = _check_order(order)
    a = np.asarray(angles, dtype=float)
    return Rotation.from_euler(seq, a.reshape(-1, 3)).as_matrix().reshape(a.shape[:-1] + (3, 3))


def matrix_to_euler(order: str, R: ArrayLike) -> np.ndarray:
    """(..., 3) angles ``t1, t2, t3`` (rad) of :func:`euler_to_matrix`.

    ``t2`` in [-pi/2, pi/2], ``t1``, ``t3`` in (-pi, pi]. At gimbal lock (``|t2| = pi/2``)
    ``t3 = 0`` is chosen.
    """
    seq = _check_order(order)
    rot, shape = _matrices(R)
    return _euler(rot, seq).reshape(shape + (3,))


def euler_solutions(order: str, R: ArrayLike) -> np.ndarray:
    """(..., 2, 3) both angle triples of ``R`` for ``order``.

    :func:`matrix_to_euler` and ``(t1 + pi, pi - t2, t3 + pi)`` (wrapped to (-pi, pi]), the
    ambiguity Shi, She and Duan note.
    """
    a = matrix_to_euler(order, R)
    b = np.stack([a[..., 0] + np.pi, np.pi - a[..., 1], a[..., 2] + np.pi], -1)
    b = np.pi - np.mod(np.pi - b, 2 * np.pi)
    return np.stack([a, b], -2)


def ypr_to_matrix(yaw: ArrayLike, pitch: ArrayLike, roll: ArrayLike) -> np.ndarray:
    """(..., 3, 3) yaw-pitch-roll (Tait-Bryan z-y'-x''): ``Rz(yaw) Ry(pitch) Rx(roll)``, radians.

    Eq. 14 of Shi, She and Duan (``a11 = cos yaw, a22 = cos pitch, a33 = cos roll``) holds only
    for a rotation about a single axis; this is the standard definition it approximates.
    """
    return rpy_to_matrix(roll, pitch, yaw)


def matrix_to_ypr(R: ArrayLike) -> np.ndarray:
    """(..., 3) ``yaw, pitch, roll`` (rad) of :func:`ypr_to_matrix`, pitch in [-pi/2, pi/2]."""
    return matrix_to_euler("zyx", R)
