"""Rotation conversions against Pinocchio's own (``pin.rpy``, ``SE3ToXYZQUAT``, ``log3``)."""

from __future__ import annotations

from contextlib import nullcontext

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.exceptions import InputError
from hexapod_model.kinematics.rotations import (
    EULER_ORDERS,
    euler_to_matrix,
    matrix_to_euler,
    matrix_to_quaternion,
    matrix_to_rpy,
    quaternion_to_matrix,
    rotation_angle,
    rpy_to_matrix,
)


def random_rotations(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array([pin.exp3(rng.normal(size=3) * rng.uniform(0.0, 3.0)) for _ in range(n)])


def test_rpy_matches_pinocchio():
    rng = np.random.default_rng(1)
    rpy = rng.uniform([-np.pi, -np.pi / 2 + 1e-3, -np.pi], [np.pi, np.pi / 2 - 1e-3, np.pi], (200, 3))
    R = rpy_to_matrix(*rpy.T)
    for k in range(len(rpy)):
        np.testing.assert_allclose(R[k], pin.rpy.rpyToMatrix(*rpy[k]), atol=1e-14)
        np.testing.assert_allclose(matrix_to_rpy(R[k]), pin.rpy.matrixToRpy(R[k]), atol=1e-12)
    np.testing.assert_allclose(matrix_to_rpy(R), rpy, atol=1e-12)


def test_quaternions_match_pinocchio_xyzquat():
    R = random_rotations(200)
    q = matrix_to_quaternion(R)
    assert q.shape == (200, 4) and np.all(q[:, 3] >= 0)
    for k in range(len(R)):
        ref = pin.SE3ToXYZQUAT(pin.SE3(R[k], np.zeros(3)))[3:]
        ref = -ref if ref[3] < 0 else ref
        np.testing.assert_allclose(q[k], ref, atol=1e-14)
    np.testing.assert_allclose(quaternion_to_matrix(q), R, atol=1e-14)


def test_vectorised_over_leading_axes():
    R = random_rotations(12).reshape(3, 4, 3, 3)
    assert matrix_to_quaternion(R).shape == (3, 4, 4) and matrix_to_rpy(R).shape == (3, 4, 3)
    np.testing.assert_allclose(rpy_to_matrix(*np.moveaxis(matrix_to_rpy(R), -1, 0)), R, atol=1e-13)
    assert rpy_to_matrix(0.1, 0.2, 0.3).shape == (3, 3)


def test_rotation_angle_matches_log3():
    Ra, Rb = random_rotations(100, 2), random_rotations(100, 3)
    ours = rotation_angle(Ra, Rb)
    ref = [np.linalg.norm(pin.log3(a.T @ b)) for a, b in zip(Ra, Rb)]
    np.testing.assert_allclose(ours, ref, atol=1e-12)
    assert rotation_angle(np.eye(3), pin.exp3(np.array([1e-9, 0, 0]))) == pytest.approx(1e-9, rel=1e-6)


@pytest.mark.parametrize("order", EULER_ORDERS)
def test_euler_orders_are_the_product_of_axis_rotations(order):
    rng = np.random.default_rng(4)
    a = rng.uniform([-3, -1.5, -3], [3, 1.5, 3], (50, 3))
    axis = {"x": np.array([1.0, 0, 0]), "y": np.array([0, 1.0, 0]), "z": np.array([0, 0, 1.0])}
    R = euler_to_matrix(order, a)
    for k in range(len(a)):
        f = [pin.exp3(axis[c] * a[k, i]) for i, c in enumerate(order)]
        ref = f[0] @ f[1] @ f[2]
        np.testing.assert_allclose(R[k], ref, atol=1e-14)
    np.testing.assert_allclose(matrix_to_euler(order, R), a, atol=1e-11)


def test_unknown_order_is_an_input_error():
    with pytest.raises(InputError, match="rotation order"):
        matrix_to_euler("xxz", np.eye(3))


def test_quaternions_without_a_rotation_give_nan():
    R = quaternion_to_matrix([[0, 0, 0, 0], [np.nan, 0, 0, 1], [0, 0, 0, 1]])
    assert np.isnan(R[:2]).all() and np.array_equal(R[2], np.eye(3))


def edge_rotations() -> np.ndarray:
    """Half turns (qw = 0), gimbal lock (pitch = +-90 deg) and its neighbourhood, near identity."""
    axes = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, -1, 1]], dtype=float)
    out = [pin.exp3(np.pi * a / np.linalg.norm(a)) for a in axes]
    for pitch in (np.pi / 2, -np.pi / 2, np.pi / 2 - 1e-9, -np.pi / 2 + 1e-7, np.pi / 2 - 1e-4):
        out += [pin.rpy.rpyToMatrix(0.3, pitch, -1.2), pin.rpy.rpyToMatrix(-2.9, pitch, 0.0)]
    out += [pin.exp3(np.array([1e-12, -2e-12, 0.0])), np.eye(3)]
    return np.array(out)


def test_closed_forms_agree_with_scipy_and_round_trip_at_the_edges():
    from scipy.spatial.transform import Rotation

    R = np.concatenate([random_rotations(300, 5), edge_rotations()])
    q = matrix_to_quaternion(R)
    np.testing.assert_allclose(q, Rotation.from_matrix(R).as_quat(canonical=True), rtol=0, atol=1e-15)
    np.testing.assert_allclose(quaternion_to_matrix(q), R, rtol=0, atol=1e-15)
    rpy = matrix_to_rpy(R)
    np.testing.assert_allclose(rpy_to_matrix(*rpy.T), R, rtol=0, atol=1e-15)
    assert np.all(np.abs(rpy[:, 1]) <= np.pi / 2)
    regular = np.hypot(R[:, 0, 0], R[:, 1, 0]) > 1e-3
    with pytest.warns(UserWarning) if not regular.all() else nullcontext():  # scipy warns at gimbal lock
        ref = Rotation.from_matrix(R).as_euler("xyz")
    wrapped = np.angle(np.exp(1j * (rpy[regular] - ref[regular])))  # -pi and pi are the same angle
    np.testing.assert_allclose(wrapped, 0.0, rtol=0, atol=1e-12)


def test_xyz_rpy_to_pose_is_the_pose_fk_writes():
    from hexapod_model.kinematics.rotations import matrix_to_rpy, xyz_rpy_to_pose

    T = xyz_rpy_to_pose([0.01, -0.02, 0.41, 12.0, -8.0, 20.0])
    assert T.shape == (4, 4) and T[3].tolist() == [0.0, 0.0, 0.0, 1.0]
    assert T[:3, 3].tolist() == [0.01, -0.02, 0.41]
    np.testing.assert_allclose(np.degrees(matrix_to_rpy(T[:3, :3])), [12.0, -8.0, 20.0], atol=1e-12)
