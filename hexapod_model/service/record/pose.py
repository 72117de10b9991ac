"""A record's pose values from a 4x4 pose, in plain floats (the cycle's per-record conversion).

The quaternion is :func:`hexapod_model.lie.quaternion_of_matrix`: Eigen's conversion (the
same bits as ``pin.Quaternion(R)``) on Python floats, cheaper per record than a boost-python
quaternion object.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ...lie import quaternion_of_matrix

POSE_KEYS = ("x", "y", "z", "qx", "qy", "qz", "qw", "roll", "pitch", "yaw")


def pose_record(T: np.ndarray) -> dict[str, float]:
    """The record's ``pose``: position (m), quaternion and roll-pitch-yaw (deg) of ``T``."""
    R = T[:3, :3]
    rpy = [math.degrees(a) for a in pin.rpy.matrixToRpy(R).tolist()]  # np.degrees' product, without its dispatch
    values = T[:3, 3].tolist() + quaternion_of_matrix(R) + rpy
    return dict(zip(POSE_KEYS, values))
