"""Roll-pitch-yaw and the other Euler orders <-> rotation matrices, vectorised over leading axes.

Convention used for printing and parsing everywhere (CLI, CSV, URDF): ``roll, pitch, yaw`` with
``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rotations about the fixed x, y, z axes, in that order; the
same as Pinocchio's ``pin.rpy``). Roll-pitch-yaw are closed forms in NumPy (the ``hexapod fk`` /
``ik`` path imports no scipy); the other Euler orders wrap scipy's ``Rotation``, imported when
first needed (outside the hot paths).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..exceptions import InputError

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

EULER_ORDERS = ("xyz", "xzy", "yxz", "yzx", "zxy", "zyx")


def rpy_to_matrix(roll: ArrayLike, pitch: ArrayLike, yaw: ArrayLike) -> np.ndarray:
    """(..., 3, 3) rotation ``Rz(yaw) Ry(pitch) Rx(roll)``; angles in radians."""
    r, p, y = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (roll, pitch, yaw)))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    R = np.empty(r.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = -sp, cp * sr, cp * cr
    return R


def matrix_to_rpy(R: ArrayLike) -> np.ndarray:
    """(..., 3) ``roll, pitch, yaw`` (rad) of rotation matrices; pitch in [-pi/2, pi/2].

    ``pitch = atan2(-R20, hypot(R00, R10))``, ``yaw = atan2(R10, R00)`` (0 at gimbal lock, where
    ``hypot(R00, R10)`` vanishes), then roll from ``Rx(roll) = Ry(pitch)^T Rz(yaw)^T R``, so that
    the angles reproduce ``R`` to rounding even next to the lock.
    """
    R = np.asarray(R, dtype=float)
    c = np.hypot(R[..., 0, 0], R[..., 1, 0])
    pitch = np.arctan2(-R[..., 2, 0], c)
    yaw = np.where(c <= 1e-14, 0.0, np.arctan2(R[..., 1, 0], R[..., 0, 0]))
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    n01 = cy * R[..., 0, 1] + sy * R[..., 1, 1]  # rows of Rz(yaw)^T R
    n11 = cy * R[..., 1, 1] - sy * R[..., 0, 1]
    roll = np.arctan2(sp * n01 + cp * R[..., 2, 1], n11)
    return np.stack([roll, pitch, yaw], -1)


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
    from scipy.spatial.transform import Rotation

    seq = _check_order(order)
    a = np.asarray(angles, dtype=float)
    return Rotation.from_euler(seq, a.reshape(-1, 3)).as_matrix().reshape(a.shape[:-1] + (3, 3))


def matrix_to_euler(order: str, R: ArrayLike) -> np.ndarray:
    """(..., 3) angles ``t1, t2, t3`` (rad) of :func:`euler_to_matrix`.

    ``t2`` in [-pi/2, pi/2], ``t1``, ``t3`` in (-pi, pi]. At gimbal lock (``|t2| = pi/2``)
    ``t3 = 0`` is chosen.
    """
    from scipy.spatial.transform import Rotation

    seq = _check_order(order)
    R = np.asarray(R, dtype=float)
    return _euler(Rotation.from_matrix(R.reshape(-1, 3, 3)), seq).reshape(R.shape[:-2] + (3,))


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
