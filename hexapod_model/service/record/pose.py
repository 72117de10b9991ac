"""A record's pose values from a 4x4 pose, in plain floats (the cycle's per-record conversion).

:func:`quaternion` is Eigen's rotation-matrix-to-quaternion conversion (the one
``pin.Quaternion(R)`` runs, the same operations in the same order, so the same bits) on
Python floats: a boost-python quaternion object per record cost more than the whole
conversion.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

POSE_KEYS = ("x", "y", "z", "qx", "qy", "qz", "qw", "roll", "pitch", "yaw")


def quaternion(R: np.ndarray) -> list[float]:
    """``[qx, qy, qz, qw]`` of the rotation matrix ``R`` with ``qw >= 0``."""
    m = R.tolist()
    (a, b, c), (d, e, f), (g, h, k) = m
    t = a + (e + k)  # Eigen's trace: a + (e + k)
    if t > 0.0:
        t = math.sqrt(t + 1.0)
        w = 0.5 * t
        t = 0.5 / t
        x, y, z = (h - f) * t, (c - g) * t, (d - b) * t
    else:  # from the largest diagonal entry
        i = 1 if e > a else 0
        if k > m[i][i]:
            i = 2
        j = (i + 1) % 3
        n = (j + 1) % 3
        t = math.sqrt(m[i][i] - m[j][j] - m[n][n] + 1.0)
        v = [0.0, 0.0, 0.0]
        v[i] = 0.5 * t
        t = 0.5 / t
        w = (m[n][j] - m[j][n]) * t
        v[j] = (m[j][i] + m[i][j]) * t
        v[n] = (m[n][i] + m[i][n]) * t
        x, y, z = v
    return [-x, -y, -z, -w] if w < 0.0 else [x, y, z, w]


def pose_record(T: np.ndarray) -> dict[str, float]:
    """The record's ``pose``: position (m), quaternion and roll-pitch-yaw (deg) of ``T``."""
    R = T[:3, :3]
    rpy = [math.degrees(a) for a in pin.rpy.matrixToRpy(R).tolist()]  # np.degrees' product, without its dispatch
    values = T[:3, 3].tolist() + quaternion(R) + rpy
    return dict(zip(POSE_KEYS, values))
