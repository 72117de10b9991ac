"""The Lie maps, NumPy and compiled forms, against Pinocchio's own and against each other.

Pinocchio's ``exp3``, ``log3``, ``exp6``, ``log6``, ``Quaternion``, ``SE3ToXYZQUAT`` and ``rpy`` are
the references, on seeded random inputs that include near-zero angles (both sides of the series
thresholds) and rotations near a half turn. Tolerances are absolute, in rad or m (unit inputs).
"""

from __future__ import annotations

from contextlib import nullcontext

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.exceptions import InputError
from hexapod_model.lie import (
    EULER_ORDERS,
    axis_rotation,
    euler_to_matrix,
    exp3,
    exp6,
    log3,
    log6,
    matrix_to_euler,
    matrix_to_quaternion,
    matrix_to_rpy,
    quaternion_multiply,
    quaternion_of_matrix,
    quaternion_to_matrix,
    rotation_angle,
    rpy_to_matrix,
    rpy_to_quaternion,
)
from hexapod_model.lie import compiled as lc
from hexapod_model.lie import compiled_quaternion as lq


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
    from hexapod_model.lie import xyz_rpy_to_pose

    T = xyz_rpy_to_pose([0.01, -0.02, 0.41, 12.0, -8.0, 20.0])
    assert T.shape == (4, 4) and T[3].tolist() == [0.0, 0.0, 0.0, 1.0]
    assert T[:3, 3].tolist() == [0.01, -0.02, 0.41]
    np.testing.assert_allclose(np.degrees(matrix_to_rpy(T[:3, :3])), [12.0, -8.0, 20.0], atol=1e-12)


def test_axis_rotation_is_exp3_of_the_axis():
    angles = np.linspace(-3.0, 3.0, 7)
    for k, axis in enumerate("xyz"):
        np.testing.assert_allclose(axis_rotation(axis, angles), exp3(np.outer(angles, np.eye(3)[k])), atol=1e-15)
    with pytest.raises(InputError, match="rotation axis"):
        axis_rotation("w", 1.0)


def rotation_vectors(seed: int) -> np.ndarray:
    """Rotation vectors (rad) from 1e-12 to just under a half turn, and half turns within 1e-9 .. 1e-4 of pi."""
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(160, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    angles = np.concatenate(
        [10.0 ** rng.uniform(-12, -3, 40), rng.uniform(1e-3, 3.0, 80), np.pi - 10.0 ** rng.uniform(-9, -4, 40)]
    )
    return axes * angles[:, None]


def test_exp3_and_log3_match_pinocchio():
    w = rotation_vectors(31)
    R = exp3(w)
    for k in range(len(w)):
        np.testing.assert_allclose(R[k], pin.exp3(w[k]), rtol=0, atol=1e-15)
        np.testing.assert_allclose(
            log3(R[k]), pin.log3(R[k]), rtol=0, atol=1e-9 if np.pi - np.linalg.norm(w[k]) < 1e-6 else 1e-12
        )
    small = np.linalg.norm(w, axis=-1) < 3.0
    np.testing.assert_allclose(log3(R)[small], w[small], rtol=0, atol=1e-12)
    E = np.empty((3, 3))
    for k in range(len(w)):  # compiled twin: the standard model's rotation update
        lc.exp3(w[k, 0], w[k, 1], w[k, 2], E)
        np.testing.assert_allclose(E, R[k], rtol=0, atol=1e-15)


def test_log3_at_a_half_turn_returns_one_of_the_two_axes():
    for axis in (*np.eye(3), np.array([1.0, 1.0, 0.0]) / np.sqrt(2), np.array([0.0, -0.6, 0.8])):
        R = pin.exp3(np.pi * axis)
        w = log3(R)
        assert np.linalg.norm(w) == pytest.approx(np.pi, abs=1e-12)
        np.testing.assert_allclose(pin.exp3(w), R, rtol=0, atol=1e-14)


def twists(seed: int) -> np.ndarray:
    """(n, 6) twists: linear parts of ~1 m, angular parts from :func:`rotation_vectors`."""
    w = rotation_vectors(seed)
    v = np.random.default_rng(seed + 1).normal(size=(len(w), 3))
    return np.hstack([v, w])


def pinocchio_exp6_tolerance(xi: np.ndarray) -> float:
    """m: Pinocchio's ``(1 - cos t) / t^2`` cancels above its series threshold, ``eps |v| / t`` off."""
    return 1e-14 + 4 * np.finfo(float).eps * np.linalg.norm(xi[:3]) / np.linalg.norm(xi[3:])


def test_exp6_and_log6_match_pinocchio():
    xi = twists(32)
    T = exp6(xi)
    for k in range(len(xi)):
        M = pin.exp6(pin.Motion(xi[k]))
        np.testing.assert_allclose(T[k, :3, :3], M.rotation, rtol=0, atol=1e-15)
        np.testing.assert_allclose(T[k, :3, 3], M.translation, rtol=0, atol=pinocchio_exp6_tolerance(xi[k]))
        near_pi = np.pi - np.linalg.norm(xi[k, 3:]) < 1e-6
        np.testing.assert_allclose(log6(T[k]), pin.log6(M).vector, rtol=0, atol=1e-7 if near_pi else 1e-12)
    assert T.shape == (len(xi), 4, 4) and exp6(np.zeros(6)).tolist() == np.eye(4).tolist()


def test_compiled_exp6_and_log6_match_pinocchio_and_numpy():
    rng = np.random.default_rng(21)
    R, p, out = np.empty((3, 3)), np.empty(3), np.empty(6)
    for scale in (1e-9, 1e-6, 1e-3, 0.3, 2.0):  # both sides of the Taylor threshold
        for _ in range(50):
            v = rng.normal(0.0, scale, 6)
            lc.exp6(v, R, p)
            M = pin.exp6(pin.Motion(v))
            np.testing.assert_allclose(R, M.rotation, rtol=0, atol=1e-15)
            np.testing.assert_allclose(p, M.translation, rtol=0, atol=1e-15)
            np.testing.assert_allclose(exp6(v)[:3, :3], R, rtol=0, atol=1e-15)
            lc.log6(M.rotation, M.translation, out)
            atol = 1e-12 if scale > 1 else 1e-14  # acos is ill-conditioned towards a half turn
            np.testing.assert_allclose(out, pin.log6(M).vector, rtol=0, atol=atol)
            np.testing.assert_allclose(out, log6(M.homogeneous), rtol=0, atol=atol)


def test_compiled_free_flyer_integration_is_the_maps_composed():
    # integrate_free_flyer writes out quat_to_matrix, exp6, the product and matrix_to_quat in
    # scalars: the same operations in the same order as the maps composed, so the same numbers
    from numba import njit

    @njit
    def composed(x, v, R0, R1, Re, pe, quat):
        lc.quat_to_matrix(x[3], x[4], x[5], x[6], R0)
        lc.exp6(v, Re, pe)
        for a in range(3):
            x[a] += R0[a, 0] * pe[0] + R0[a, 1] * pe[1] + R0[a, 2] * pe[2]
            for b in range(3):
                R1[a, b] = R0[a, 0] * Re[0, b] + R0[a, 1] * Re[1, b] + R0[a, 2] * Re[2, b]
        lc.matrix_to_quat(R1, quat)
        dot = quat[0] * x[3] + quat[1] * x[4] + quat[2] * x[5] + quat[3] * x[6]
        n2 = quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]
        alpha = (-1.0 if dot < 0.0 else 1.0) * (3.0 - n2) / 2.0
        for a in range(4):
            x[3 + a] = alpha * quat[a]

    rng = np.random.default_rng(25)
    scratch = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty(3), np.empty(4)
    cases = []
    for scale in (1e-9, 1e-5, 1e-2, 0.5, 3.0):  # both sides of the Taylor threshold, every quaternion branch
        for _ in range(400):
            x = rng.normal(size=7)
            x[3:] /= np.linalg.norm(x[3:])
            cases.append((x, rng.normal(0.0, scale, 6)))
    for axis in range(3):  # half turns about each axis: R1's trace -1, its largest diagonal entry on that axis
        v = np.zeros(6)
        v[3 + axis] = np.pi
        cases.append((np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]), v))
    branches = set()
    for x, v in cases:
        want, got = x.copy(), x.copy()
        composed(want, v, *scratch)
        lc.integrate_free_flyer(got, v)
        assert want.tobytes() == got.tobytes()
        R = scratch[1]
        branches.add(-1 if np.trace(R) > 0.0 else int(np.argmax(np.diag(R))))
    assert branches == {-1, 0, 1, 2}


def test_compiled_quaternions_match_pinocchio():
    pin.seed(22)
    R, quat = np.empty((3, 3)), np.empty(4)
    for _ in range(200):
        M = pin.SE3.Random()
        x = pin.SE3ToXYZQUAT(M)
        lc.quat_to_matrix(x[3], x[4], x[5], x[6], R)
        np.testing.assert_allclose(R, M.rotation, rtol=0, atol=1e-15)
        np.testing.assert_allclose(R, quaternion_to_matrix(x[3:]), rtol=0, atol=1e-15)
        lc.matrix_to_quat(M.rotation, quat)
        assert min(np.abs(quat - x[3:]).max(), np.abs(quat + x[3:]).max()) < 1e-15
    for angle in (np.pi, np.pi - 1e-9):  # negative traces take the other branches
        for axis in np.eye(3):
            M = pin.exp3(angle * axis)
            lc.matrix_to_quat(M, quat)
            lc.quat_to_matrix(quat[0], quat[1], quat[2], quat[3], R)
            np.testing.assert_allclose(R, M, rtol=0, atol=1e-15)


def test_quaternion_of_matrix_is_eigens_bit_for_bit():
    R = np.concatenate([random_rotations(200, 6), edge_rotations()])
    for k in range(len(R)):
        ref = pin.Quaternion(R[k]).coeffs()
        ref = -ref if ref[3] < 0 else ref
        assert quaternion_of_matrix(R[k]) == ref.tolist()
    ours, vectorised = np.array([quaternion_of_matrix(r) for r in R]), matrix_to_quaternion(R)
    sign = np.where(np.sum(ours * vectorised, axis=-1) < 0, -1.0, 1.0)  # qw = 0: either sign
    np.testing.assert_allclose(ours, sign[:, None] * vectorised, rtol=0, atol=1e-15)


def test_rpy_to_quaternion_matches_pinocchio():
    rng = np.random.default_rng(33)
    for rpy in [*rng.uniform(-4.0, 4.0, (100, 3)), (0.0, 0.0, 3.0), (0.0, 0.0, -3.5)]:
        q = rpy_to_quaternion(*rpy)
        assert q[3] >= 0
        np.testing.assert_allclose(quaternion_to_matrix(q), pin.rpy.rpyToMatrix(*rpy), rtol=0, atol=1e-15)


def test_quaternion_products_match_pinocchio_and_the_compiled_twins():
    rng = np.random.default_rng(34)
    a, b = rng.normal(size=(100, 4)), rng.normal(size=(100, 4))
    a /= np.linalg.norm(a, axis=-1, keepdims=True)
    b /= np.linalg.norm(b, axis=-1, keepdims=True)
    ab = quaternion_multiply(a, b)
    out, v, rv = np.empty(4), rng.normal(size=3), np.empty(3)
    for k in range(len(a)):
        ref = pin.Quaternion(a[k]) * pin.Quaternion(b[k])  # a 4-vector is read as (x, y, z, w)
        np.testing.assert_allclose(ab[k], ref.coeffs(), rtol=0, atol=1e-15)
        lq.quat_mul(a[k], b[k], out)
        assert out.tolist() == ab[k].tolist()  # the same operations in the same order
        Ra = quaternion_to_matrix(a[k])
        lq.quat_rotate(a[k], v, rv, False)
        np.testing.assert_allclose(rv, Ra @ v, rtol=0, atol=1e-14)
        lq.quat_rotate(a[k], v, rv, True)
        np.testing.assert_allclose(rv, Ra.T @ v, rtol=0, atol=1e-14)


def test_compiled_quaternion_exp6_and_log6_match_pinocchio():
    xi = twists(35)
    p, q, out = np.empty(3), np.empty(4), np.empty(6)
    for k in range(len(xi)):
        M = pin.exp6(pin.Motion(xi[k]))
        lq.exp6_quat(xi[k], p, q)
        np.testing.assert_allclose(p, M.translation, rtol=0, atol=pinocchio_exp6_tolerance(xi[k]))
        np.testing.assert_allclose(p, exp6(xi[k])[:3, 3], rtol=0, atol=1e-14)
        np.testing.assert_allclose(quaternion_to_matrix(q), M.rotation, rtol=0, atol=1e-15)
        lq.log6_quat(M.translation, pin.SE3ToXYZQUAT(M)[3:], out)
        near_pi = np.pi - np.linalg.norm(xi[k, 3:]) < 1e-6
        np.testing.assert_allclose(out, pin.log6(M).vector, rtol=0, atol=1e-7 if near_pi else 1e-12)
        if not near_pi:
            np.testing.assert_allclose(out, xi[k], rtol=0, atol=1e-12)


def test_log3_matches_scipys_rotation_vectors():
    """The calibration's rotation vectors, once scipy's ``as_rotvec``: the same to 1e-12 rad short of a half turn."""
    from scipy.spatial.transform import Rotation

    w = rotation_vectors(36)
    R = exp3(w)
    ref = Rotation.from_matrix(R).as_rotvec()
    short = np.pi - np.linalg.norm(w, axis=-1) > 1e-6
    np.testing.assert_allclose(log3(R)[short], ref[short], rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(log3(R), axis=-1), np.linalg.norm(ref, axis=-1), rtol=0, atol=1e-12)


def test_free_flyer_pose_conversions_match_pinocchio():
    """``pose_to_xyzquat(T, H) = XYZQUAT(H^-1 T)`` (quaternion up to sign) and back, NumPy and compiled."""
    from hexapod_model.lie.se3 import pose_to_xyzquat, xyzquat_to_pose

    pin.seed(37)
    H = pin.SE3.Random().homogeneous
    x, y, T, U = np.empty(7), np.empty(7), np.empty((4, 4)), np.empty((4, 4))
    for k in range(200):
        M = pin.SE3.Random() if k % 2 else pin.SE3(pin.exp3(np.pi * np.eye(3)[k % 3]), np.zeros(3))  # half turns too
        Tk = H @ M.homogeneous
        pose_to_xyzquat(Tk, H, x)
        lc.pose_to_xyzquat(Tk, H, y)
        ref = pin.SE3ToXYZQUAT(M)
        np.testing.assert_allclose(x[:3], ref[:3], rtol=0, atol=1e-14)
        assert min(np.abs(x[3:] - ref[3:]).max(), np.abs(x[3:] + ref[3:]).max()) < 1e-15
        np.testing.assert_allclose(y, x, rtol=0, atol=1e-15)
        xyzquat_to_pose(x, H, T)
        lc.xyzquat_to_pose(x, H, U)
        np.testing.assert_allclose(T, Tk, rtol=0, atol=1e-14)
        np.testing.assert_allclose(U, T, rtol=0, atol=1e-15)
