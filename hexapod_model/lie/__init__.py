"""Rotations and rigid motions: SO(3) and SE(3) maps, quaternions and Euler angles.

Each map has a NumPy form, vectorised over leading axes (this package's public names), and,
where a compiled kernel needs it, a numba form in :mod:`hexapod_model.lie.compiled` (rotation
matrices) or :mod:`hexapod_model.lie.compiled_quaternion` (unit quaternions). Both are tested
against Pinocchio's ``exp3``, ``log3``, ``exp6``, ``log6``, ``Quaternion`` and ``rpy``.

Conventions: angles in radians (the six-number pose of :func:`xyz_rpy_to_pose`: degrees);
quaternions ``(qx, qy, qz, qw)``; roll-pitch-yaw ``R = Rz(yaw) Ry(pitch) Rx(roll)``; twists
``(v, w)``, linear part first (m, rad); poses 4x4 homogeneous transforms.
"""

from .euler import (
    EULER_ORDERS,
    euler_solutions,
    euler_to_matrix,
    matrix_to_euler,
    matrix_to_rpy,
    matrix_to_ypr,
    rpy_to_matrix,
    ypr_to_matrix,
)
from .quaternion import (
    matrix_to_quaternion,
    quaternion_multiply,
    quaternion_of_matrix,
    quaternion_to_matrix,
    rpy_to_quaternion,
)
from .se3 import exp6, log6, pose_distance, xyz_rpy_to_pose
from .so3 import axis_rotation, exp3, hat, log3, rotation_angle

__all__ = [
    "EULER_ORDERS",
    "axis_rotation",
    "euler_solutions",
    "euler_to_matrix",
    "exp3",
    "exp6",
    "hat",
    "log3",
    "log6",
    "matrix_to_euler",
    "matrix_to_quaternion",
    "matrix_to_rpy",
    "matrix_to_ypr",
    "pose_distance",
    "quaternion_multiply",
    "quaternion_of_matrix",
    "quaternion_to_matrix",
    "rotation_angle",
    "rpy_to_matrix",
    "rpy_to_quaternion",
    "xyz_rpy_to_pose",
    "ypr_to_matrix",
]
