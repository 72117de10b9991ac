"""Shi, She and Duan (2016): geometric 3-6 direct kinematics (eqs. 1-11) and rotation angles (eqs. 12-15)."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.jacobian import kinematic_evaluation
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics.three_six import ACCEPT, MAX_ASSEMBLIES, ThreeSixFK
from hexapod_model.lie import (
    EULER_ORDERS,
    axis_rotation,
    euler_solutions,
    euler_to_matrix,
    matrix_to_euler,
    matrix_to_rpy,
    matrix_to_ypr,
    rpy_to_matrix,
    ypr_to_matrix,
)


@pytest.fixture(scope="module")
def hexa():
    return hm.Hexapod.from_preset("3-6", check_body=False)  # the resultant against the limits alone


@pytest.fixture(scope="module")
def fk(hexa):
    return ThreeSixFK(hexa.geometry)


def _readings_match(fk, sol, lengths):
    L = fk.home_lengths + lengths
    for k in range(3):
        for j in (2 * k, 2 * k + 1):
            assert np.linalg.norm(sol.points[k] - fk.base[j]) == pytest.approx(L[j], abs=1e-12)


def test_home_readings_give_home_and_its_mirror(hexa, fk):
    sols = fk.solve_all(np.zeros(6))
    assert len(sols) >= 2 and len(sols) % 2 == 0
    np.testing.assert_allclose(sols[0].pose, hexa.home_pose, atol=1e-12)
    mirrored = [s for s in sols if np.allclose(s.pose[:3, 3], hexa.home_pose[:3, 3] * [1, 1, -1], atol=1e-9)]
    assert mirrored, "the reflection through the base plane is always an assembly"
    for s in sols:
        _readings_match(fk, s, np.zeros(6))
        R = s.pose[:3, :3]
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
        assert s.residual < 1e-12


def test_cross_check_against_newton_solver(hexa, fk):
    n = 0
    for T in box_poses(hexa.home_pose, 12, seed=5, translation=0.03, angle_deg=15):
        ik = hexa.inverse(T, check=False)
        if not ik.converged:
            continue
        n += 1
        geo = fk.solve(ik.lengths, reference=hexa.home_pose)
        newton = hexa.forward(ik.lengths)
        assert np.abs(geo.pose - newton.pose).max() < 1e-9
        assert np.abs(geo.pose - T).max() < 1e-9
        _readings_match(fk, geo, ik.lengths)
    assert n >= 8


def test_assemblies_above_the_base_are_solutions_of_the_urdf_model(hexa, fk):
    """Each assembly with the platform above the base is reproduced by the URDF model's inverse
    kinematics (below-base mirrors need legs through the base plate, which the Cardan joints forbid)."""
    T = box_poses(hexa.home_pose, 1, seed=2, translation=0.02, angle_deg=10)[0]
    lengths = hexa.inverse(T).lengths
    checked = 0
    for s in fk.solve_all(lengths):
        if s.pose[2, 3] <= 0:
            continue
        ik = hexa.inverse(s.pose, check=False)
        if ik.status in ("converged", "out_of_limits") and np.all(np.abs(ik.lengths) < 0.18):
            np.testing.assert_allclose(ik.lengths, lengths, atol=1e-9)
            checked += 1
    assert checked >= 2


def test_reference_selects_the_assembly(hexa, fk):
    lengths = np.zeros(6)
    below = hexa.home_pose.copy()
    below[2, 3] *= -1
    assert fk.solve(lengths, reference=below).pose[2, 3] == pytest.approx(-hexa.home_pose[2, 3])
    assert fk.solve(lengths).pose[2, 3] == pytest.approx(hexa.home_pose[2, 3])


def test_errors(hexa, fk):
    with pytest.raises(hm.GeometryError):
        ThreeSixFK(hm.get_preset("spherical"))
    with pytest.raises(hm.WorkspaceError):
        fk.solve([-0.18, 0.17, 0, 0, 0, 0])  # the two legs of pair 0 cannot meet
    with pytest.raises(hm.InputError):
        fk.solve([0.0] * 5)


ISSUE_READINGS = [
    -0.002877279397885346,
    0.005232292617211892,
    -0.00532425994014854,
    -0.05518961782271656,
    0.025369871239453057,
    -0.045294087439625264,
]


def test_issue_readings_give_every_assembly_and_the_nearest_is_newtons(hexa, fk):
    """The angle scan found 6 assemblies, none within 26 mm of Newton's pose, and chose one
    26.7 mm / 24 deg off without an error."""
    lengths = np.array(ISSUE_READINGS)
    newton = hexa.forward(lengths, check=False)
    assert newton.residual < 1e-12
    sols = fk.solve_all(lengths)
    assert len(sols) == 8 <= MAX_ASSEMBLIES
    assert min(np.abs(s.pose - newton.pose).max() for s in sols) < 1e-9
    assert np.abs(fk.solve(lengths).pose - newton.pose).max() < 1e-9
    for s in sols:
        _readings_match(fk, s, lengths)
        assert s.residual <= ACCEPT


def _scan_roots(fk, lengths, n=20_000):
    """Independent check: intervals of psi_0 where one of the four branches of |A_1 - A_2|^2 - D_12^2
    (psi_1, psi_2 from the two other distances) changes sign, on an n-step grid."""
    C, d = fk.circles(lengths)
    psi0 = np.linspace(-np.pi, np.pi, n + 1)
    A0 = C[0] + d[0] * (np.cos(psi0)[:, None] * fk.e[0] + np.sin(psi0)[:, None] * fk.f[0])
    branches = {}
    for k in (1, 2):
        w = A0 - C[k]
        a, b = 2 * d[k] * w @ fk.e[k], 2 * d[k] * w @ fk.f[k]
        c = (w * w).sum(1) + d[k] ** 2 - fk.D2[0, k]
        with np.errstate(invalid="ignore"):
            spread = np.arccos(c / np.hypot(a, b))
        branches[k] = [np.arctan2(b, a) + s * spread for s in (1, -1)]
    found = []
    for p1 in branches[1]:
        for p2 in branches[2]:
            A1 = C[1] + d[1] * (np.cos(p1)[:, None] * fk.e[1] + np.sin(p1)[:, None] * fk.f[1])
            A2 = C[2] + d[2] * (np.cos(p2)[:, None] * fk.e[2] + np.sin(p2)[:, None] * fk.f[2])
            g = ((A1 - A2) ** 2).sum(1) - fk.D2[1, 2]
            change = np.flatnonzero(g[:-1] * g[1:] <= 0)  # NaN (no real psi_1/psi_2) never counts
            found += [(psi0[i], psi0[i + 1]) for i in change]
    return found


def test_no_assembly_is_missed_against_a_20000_step_scan(hexa, fk):
    counts = []
    for T in box_poses(hexa.home_pose, 60, seed=11, translation=0.1, angle_deg=40):
        ik = hexa.inverse(T, check=False)
        if not ik.converged:
            continue
        sols = fk.solve_all(ik.lengths)
        psi0 = np.array([s.psi[0] for s in sols])
        for lo, hi in _scan_roots(fk, ik.lengths):
            assert np.any((psi0 >= lo - 1e-9) & (psi0 <= hi + 1e-9)), "a sign change without an assembly"
        assert min(np.abs(s.pose - T).max() for s in sols) < 1e-9  # the truth is always there
        assert len(sols) % 2 == 0  # mirror pairs about the (planar) base
        counts.append(len(sols))
    assert len(counts) > 40 and max(counts) <= MAX_ASSEMBLIES


def test_readings_near_a_fold_keep_the_true_assembly(hexa, fk):
    """Poses whose leg Jacobian is 30 times worse conditioned than at home: another assembly is
    close, and both must be found."""
    home = kinematic_evaluation(hexa, hexa.q_home).condition_number
    near = 0
    for T in box_poses(hexa.home_pose, 1500, seed=2, translation=0.1, angle_deg=40):
        ik = hexa.inverse(T, check=False)
        if not ik.converged or kinematic_evaluation(hexa, ik.q).condition_number < 30 * home:
            continue
        near += 1
        sols = fk.solve_all(ik.lengths)
        assert min(np.abs(s.pose - T).max() for s in sols) < 1e-9
        assert all(s.residual <= ACCEPT for s in sols)
    assert near >= 20


def test_nearest_assembly_within_a_distance_or_an_error(hexa, fk):
    lengths = np.array(ISSUE_READINGS)
    newton = hexa.forward(lengths, check=False)
    assert np.abs(fk.solve(lengths, reference=newton.pose, max_distance=1e-6).pose - newton.pose).max() < 1e-9
    far = newton.pose.copy()
    far[:3, 3] += [0.0, 0.03, 0.0]  # 30 mm from Newton's assembly, farther still from the others
    with pytest.raises(hm.WorkspaceError, match="nearest of 8 assemblies is 0.03"):
        fk.solve(lengths, reference=far, max_distance=0.01)


# ----- angles (Shi, She and Duan (2016) eqs. 12-15) -----
@pytest.mark.parametrize("order", EULER_ORDERS)
def test_euler_round_trip(order):
    rng = np.random.default_rng(len(order) + ord(order[0]))
    a = rng.uniform(-np.pi, np.pi, (200, 3))
    a[:, 1] = rng.uniform(-np.pi / 2 + 1e-6, np.pi / 2 - 1e-6, 200)
    R = euler_to_matrix(order, a)
    np.testing.assert_allclose(
        R,
        axis_rotation(order[0], a[:, 0]) @ axis_rotation(order[1], a[:, 1]) @ axis_rotation(order[2], a[:, 2]),
        atol=1e-15,
    )
    np.testing.assert_allclose(matrix_to_euler(order, R), a, atol=1e-9)
    both = euler_solutions(order, R)
    for k in range(2):
        np.testing.assert_allclose(euler_to_matrix(order, both[:, k]), R, atol=1e-12)
    assert np.all(np.abs(both[:, 1, 1]) >= np.pi / 2 - 1e-12)  # the second triple has |t2| >= 90 deg


@pytest.mark.parametrize("order", EULER_ORDERS)
@pytest.mark.parametrize("middle", [np.pi / 2, -np.pi / 2])
def test_euler_gimbal_lock_reconstructs_the_matrix(order, middle):
    R = euler_to_matrix(order, [0.4, middle, -1.1])
    a = matrix_to_euler(order, R)
    assert a[2] == 0.0 and a[1] == pytest.approx(middle)
    np.testing.assert_allclose(euler_to_matrix(order, a), R, atol=1e-12)


def test_orders_are_distinct_and_ypr_is_the_rpy_convention():
    a = np.array([0.3, -0.5, 0.7])
    mats = [euler_to_matrix(o, a) for o in EULER_ORDERS]
    assert all(not np.allclose(mats[i], mats[j]) for i in range(6) for j in range(i + 1, 6))
    np.testing.assert_allclose(ypr_to_matrix(0.7, -0.5, 0.3), rpy_to_matrix(0.3, -0.5, 0.7), atol=1e-15)
    np.testing.assert_allclose(matrix_to_ypr(rpy_to_matrix(0.3, -0.5, 0.7)), [0.7, -0.5, 0.3], atol=1e-12)
    np.testing.assert_allclose(matrix_to_rpy(euler_to_matrix("zyx", [0.7, -0.5, 0.3])), [0.3, -0.5, 0.7], atol=1e-12)
    # Shi, She and Duan (2016) eq. 14 (a11 = cos yaw, ...) holds for a single-axis rotation, e.g. its case study
    R = ypr_to_matrix(0.25, 0.0, 0.0)
    assert R[0, 0] == pytest.approx(np.cos(0.25)) and R[1, 1] == pytest.approx(np.cos(0.25))
    assert R[2, 2] == pytest.approx(1.0, abs=1e-15)  # to rounding (scipy composes the rotation)
    with pytest.raises(ValueError):
        euler_to_matrix("xxy", a)
