"""SO(3) in NumPy, vectorised over leading axes: ``hat``, ``exp3``, ``log3``, angles between rotations.

Rotation vectors ``w`` (rad) map to rotation matrices by Rodrigues' formula
``exp3(w) = I + sin t / t [w] + (1 - cos t) / t^2 [w]^2`` (``t = |w|``), and back by
``log3``, the inverse with ``|log3(R)| <= pi`` (Pinocchio's ``exp3`` / ``log3``). The compiled
twins are in :mod:`hexapod_model.lie.compiled`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..exceptions import InputError

_NEAR_PI = 1e-3  # rad from pi: below, the axis comes from the symmetric part of R (sin t too small)


def hat(w: ArrayLike) -> np.ndarray:
    """(..., 3, 3) skew matrices ``[w]`` (``[w] v = w x v``) of (..., 3) vectors."""
    w = np.asarray(w, dtype=float)
    K = np.zeros(w.shape[:-1] + (3, 3))
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -z, y, -x
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = z, -y, x
    return K


def exp3(theta: ArrayLike) -> np.ndarray:
    """(..., 3, 3) rotation matrices ``exp([theta])`` of (..., 3) rotation vectors (rad; Rodrigues)."""
    theta = np.asarray(theta, dtype=float)
    a = np.linalg.norm(theta, axis=-1)
    small = a < 1e-8
    a_safe = np.where(small, 1.0, a)
    s = np.where(small, 1.0 - a * a / 6.0, np.sin(a) / a_safe)
    c = np.where(small, 0.5 - a * a / 24.0, (1.0 - np.cos(a)) / (a_safe * a_safe))
    K = hat(theta)
    out = s[..., None, None] * K + c[..., None, None] * (K @ K)
    out[..., 0, 0] += 1.0
    out[..., 1, 1] += 1.0
    out[..., 2, 2] += 1.0
    return out


def log3(R: ArrayLike) -> np.ndarray:
    """(..., 3) rotation vectors (rad, norm in [0, pi]) of (..., 3, 3) rotation matrices.

    The angle is ``atan2(|vex(R - R^T)| / 2, (tr R - 1) / 2)``, accurate at every angle; the
    axis is ``vex(R - R^T) / (2 sin t)`` except within 1e-3 rad of a half turn, where it is the
    largest column of ``(R + R^T) / 2 - cos t I = (1 - cos t) n n^T``, signed by the skew part.
    At a half turn exactly both ``n`` and ``-n`` are right; the one returned is either.
    """
    R = np.asarray(R, dtype=float)
    a = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    s = 0.5 * np.linalg.norm(a, axis=-1)  # sin t
    c = 0.5 * (R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2] - 1.0)  # cos t
    t = np.arctan2(s, c)
    small = t < 1e-8
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(small, 0.5 + t * t / 12.0, 0.5 * t / np.where(small, 1.0, s))  # t / (2 sin t)
    w = k[..., None] * a
    near = np.pi - t < _NEAR_PI
    if np.any(near):
        B = 0.5 * (R[near] + np.swapaxes(R[near], -1, -2)) - c[near][:, None, None] * np.eye(3)
        d = np.diagonal(B, axis1=-2, axis2=-1)
        j = np.argmax(d, axis=-1)
        col = np.take_along_axis(B, j[:, None, None], -1)[..., 0]  # (1 - cos t) n n_j
        n = col / np.linalg.norm(col, axis=-1, keepdims=True)
        sign = np.where(np.sum(n * a[near], axis=-1) < 0.0, -1.0, 1.0)
        w[near] = (sign * t[near])[:, None] * n
    return w


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
    from scipy.spatial.transform import Rotation

    if axis not in ("x", "y", "z"):
        raise InputError("rotation axis", axis, "choose x, y or z")
    a = np.asarray(angle, dtype=float)
    return Rotation.from_euler(axis, a.reshape(-1, 1)).as_matrix().reshape(a.shape + (3, 3))
