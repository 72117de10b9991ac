"""Newton solver: Jacobian vs finite differences, round trips, statuses and errors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses, trajectory_poses
from hexapod_model.description.model import ClosedLoopModel
from hexapod_model.kinematics.body_check import BODY_STATUSES
from hexapod_model.kinematics.newton.solver import NewtonSolver
from hexapod_model.lie import pose_distance, rotation_angle

from ..conftest import PRESET_NAMES, hexapod


def random_configuration(hexa: hm.Hexapod, rng) -> np.ndarray:
    """A random, generally *not* closed configuration near home."""
    m = hexa.closed_loop
    q = hexa.q_home
    legs = np.array([m.model.joints[j].idx_q for leg in m.legs for j in leg.joints])
    q[legs] = rng.uniform(-0.4, 0.4, legs.size)
    i = m.platform_q
    q[i : i + 7] = pin.SE3ToXYZQUAT(pin.exp6(rng.uniform(-0.2, 0.2, 6)))
    return q


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_jacobian_matches_finite_differences(name):
    hexa = hexapod(name)
    solver = NewtonSolver(hexa.closed_loop, ())  # every joint free: the full closure Jacobian
    rng = np.random.default_rng(1)
    h = 1e-6
    for _ in range(5):
        q = random_configuration(hexa, rng)
        r0, G = solver.evaluate(q)
        assert np.linalg.norm(r0) > 1e-3  # really off the constraint manifold
        fd = np.empty_like(G)
        for k in range(hexa.closed_loop.nv):
            dv = np.zeros(hexa.closed_loop.nv)
            dv[k] = h
            rp, _ = solver.evaluate(pin.integrate(hexa.model, q, dv))
            rm, _ = solver.evaluate(pin.integrate(hexa.model, q, -dv))
            fd[:, k] = (rp - rm) / (2 * h)
        np.testing.assert_allclose(G, fd, atol=1e-7, rtol=0)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_round_trip_pose_lengths_pose_on_1000_box_poses(name):
    hexa = hexapod(name)
    poses = box_poses(hexa.home_pose, 1000, seed=7)
    plain = hexa.engine.solver(hexa.engine.held_forward)
    worst_p = worst_r = worst_l = 0.0
    steps = []
    for T in poses:
        back = hexa.inverse(T, check=False)  # the whole box is inside the stroke and joint limits of every preset
        assert back.status == "converged" or back.status in BODY_STATUSES and name in ("3-6", "guideway")
        if back.status != "converged":  # 3-6: a corner beyond the 45 deg cones; guideway: two struts cross
            continue
        sol = hexa.forward(back.lengths, check=False)  # cold start from home, certified
        if sol.status == "ambiguous_assembly":  # 3-6: another assembly within the limits about as near home
            assert name == "3-6" and any(pose_distance(P, T, 0.2) < 1e-9 for P in sol.candidates)
            continue
        assert sol.converged
        worst_p = max(worst_p, np.linalg.norm(sol.pose[:3, 3] - T[:3, 3]))
        worst_r = max(worst_r, rotation_angle(sol.pose[:3, :3], T[:3, :3]))
        worst_l = max(worst_l, np.abs(hexa.inverse(sol.pose, guess=sol).lengths - back.lengths).max())
        q0 = hexa.q_home
        q0[hexa.closed_loop.prismatic_q] = back.lengths
        assert plain.run(q0, 1e-12, 20)[2] <= 8  # the plain Newton solve
        steps.append(sol.iterations)  # with the substeps the certificate needs (kinematics/certificate.py)
    assert worst_p < 1e-9 and worst_r < 1e-9 and worst_l < 1e-9
    assert max(steps) <= 16 and np.mean(steps) <= 6


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_solutions_close_the_loops_per_pinocchio_constraints(name):
    hexa = hexapod(name)
    T = box_poses(hexa.home_pose, 1, seed=3)[0]
    sol = hexa.inverse(T)
    # the independent reference: Pinocchio's own constraint models (log6 / point distance)
    assert hexa.closure_residual(sol.q).max() < 1e-9
    assert sol.residual <= 1e-10


def test_warm_start_along_trajectory_converges_in_two_steps():
    hexa = hexapod("reference")
    _, poses = trajectory_poses("A", hexa.home_pose, 0.25 / 50, rate_hz=1000)
    sol = inv = None
    for T in poses[::40]:
        inv = hexa.inverse(T, guess=inv)
        sol = hexa.forward(inv.lengths, guess=sol)
        assert np.abs(sol.pose - T).max() < 1e-9
    sol2 = hexa.forward(inv.lengths, guess=sol)
    assert sol2.iterations == 0  # already there


def test_hybrid_solve_holds_named_joints():
    hexa = hexapod("reference")
    T = box_poses(hexa.home_pose, 1, seed=11)[0]
    truth = hexa.inverse(T)
    names = list(hexa.prismatic_names[:5]) + ["leg6_cardan_base_1"]
    iq = [hexa.model.joints[hexa.model.getJointId(n)].idx_q for n in names]
    sol = hexa.solve(dict(zip(names, truth.q[iq])), guess=hexa.q_home)
    np.testing.assert_allclose(sol.pose, T, atol=1e-9)
    np.testing.assert_allclose(sol.lengths, truth.lengths, atol=1e-9)
    # holding the platform is the inverse problem
    inv = hexa.solve({"platform_joint": T})
    np.testing.assert_allclose(inv.lengths, truth.lengths, atol=1e-9)
    with pytest.raises(hm.InputError, match="not a joint"):
        hexa.solve({"leg9_prismatic": 0.0})
    with pytest.raises(hm.LimitError, match=r"leg1_cardan_base_1 = 3 rad is outside"):
        hexa.solve({"leg1_cardan_base_1": 3.0})


@pytest.mark.parametrize(
    "bad, error, pattern",
    [
        ([0.0] * 5, hm.InputError, "expected 6 values, got 5"),
        ([0.0, np.nan, 0, 0, 0, 0], hm.InputError, "finite"),
        ([0.0, 0, np.inf, 0, 0, 0], hm.InputError, "finite"),
        ([0.0, 0, 0, 0.5, 0, 0], hm.LimitError, r"stroke limit: leg4_prismatic = 0.5 m is outside \[-0.16, 0.2\] m"),
        ("abc", hm.InputError, "expected 6"),
    ],
)
def test_bad_readings_raise_clear_errors(bad, error, pattern):
    with pytest.raises(error, match=pattern):
        hexapod("reference").forward(bad)


def test_bad_poses_raise_clear_errors():
    hexa = hexapod("reference")
    T = hexa.home_pose.copy()
    T[0, 0] = 2.0
    with pytest.raises(hm.InputError, match="not a rigid transform"):
        hexa.inverse(T)
    T = hexa.home_pose.copy()
    T[1, 3] = np.nan
    with pytest.raises(hm.InputError, match="finite"):
        hexa.inverse(T)
    with pytest.raises(hm.InputError, match="4x4"):
        hexa.inverse(np.eye(3))


def test_pose_outside_workspace():
    hexa = hexapod("reference")
    T = hexa.home_pose.copy()
    T[2, 3] += 0.3  # 30 cm up: beyond the stroke
    with pytest.raises(hm.WorkspaceError, match=r"stroke limit: leg\d_prismatic = .* m is outside"):
        hexa.inverse(T)
    sol = hexa.inverse(T, check=False)
    assert sol.status == "out_of_limits" and not sol.converged
    assert issubclass(hm.WorkspaceError, hm.HexapodError)


def test_non_convergence_is_never_presented_as_converged():
    hexa = hexapod("reference")
    lengths = hexa.inverse(box_poses(hexa.home_pose, 1, seed=5)[0]).lengths
    with pytest.raises(hm.ConvergenceError, match="no convergence"):
        hexa.forward(lengths, max_iter=1)
    sol = hexa.forward(lengths, max_iter=1, check=False)
    assert sol.status == "max_iterations" and not sol.converged and sol.residual > 1e-10


def test_singular_layout_is_reported():
    # all six legs vertical: the platform can rotate about z and slide sideways freely
    legs = tuple(
        hm.LegGeometry(
            base_anchor=(0.2 * np.cos(a), 0.2 * np.sin(a), 0.0),
            platform_anchor=(0.2 * np.cos(a), 0.2 * np.sin(a), 0.0),
            stroke=(-0.1, 0.1),
        )
        for a in np.linspace(0, 2 * np.pi, 6, endpoint=False)
    )
    g = dataclasses.replace(hm.get_preset("spherical"), name="vertical", legs=legs)
    with pytest.raises(hm.GeometryError, match=r"home condition number' = \S+e\+\d+: .* exceeds the limit 1e\+06"):
        hm.Hexapod.from_geometry(g)  # refused on load: no solve on it is ever reported as good
    # the solver itself, on the same model: singular after a step, and at home where no step is taken
    clm = ClosedLoopModel(hm.geometry_to_urdf(g))
    solver = NewtonSolver(clm, tuple(leg.prismatic for leg in clm.legs))
    q = clm.q_home.copy()
    q[clm.prismatic_q] = 0.01
    assert solver.run(q, 1e-12, 20)[1] == "singular"
    _, status, iterations, residual, jac, message = solver.run(clm.q_home, 1e-12, 20)
    assert (status, iterations) == ("singular", 0) and residual <= 1e-12, message
    assert "no step taken" in message and np.linalg.cond(jac) > 1e12


def test_solution_reports_everything():
    sol = hexapod("reference").forward([0.01, -0.01, 0.02, 0.0, 0.0, 0.01])
    assert sol.pose.shape == (4, 4) and sol.q.shape == (43,) and sol.lengths.shape == (6,)
    assert sol.status in hm.STATUSES and sol.converged and sol.iterations >= 1
    assert sol.residual <= 1e-10 and 1 < sol.condition_number < 1e4
    np.testing.assert_allclose(sol.lengths, [0.01, -0.01, 0.02, 0.0, 0.0, 0.01])


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_structured_steps_equal_the_dense_step(name):
    # the Schur (direct kinematics) and block-diagonal (inverse kinematics) paths must solve
    # exactly the same linear system as a dense solve of the reduced Jacobian
    hexa = hexapod(name)
    rng = np.random.default_rng(4)
    for held, attr in ((hexa.engine.held_forward, "held_pos"), (hexa.engine.held_inverse, "block_cols")):
        solver = NewtonSolver(hexa.closed_loop, held)
        assert getattr(solver, attr) is not None
        q = random_configuration(hexa, rng)
        r, G = solver.evaluate(q)
        assert solver._solve_step() > 1e-6
        np.testing.assert_allclose(solver.x, np.linalg.solve(G, r), rtol=1e-9, atol=1e-12)


def test_cold_starts_far_from_home_converge_or_say_why():
    # beyond the Bem et al. (2026) box (+-80 mm, +-35 deg): without the step limit, Newton from home
    # overshot to a 180-degree flipped closure on some of these
    hexa = hexapod("reference")
    statuses = set()
    for T in box_poses(hexa.home_pose, 400, seed=3, translation=0.08, angle_deg=35):
        sol = hexa.inverse(T, check=False)
        statuses.add(sol.status)
        if sol.converged:
            np.testing.assert_allclose(sol.pose, T, atol=1e-9)
            assert np.abs(hexa.forward(sol.lengths).pose - T).max() < 1e-9
    assert statuses <= {"converged", "out_of_limits", *BODY_STATUSES} and "converged" in statuses


def test_pinocchio_habits():
    """RobotWrapper names, pin.SE3 in and out."""
    hexa = hexapod("reference")
    assert isinstance(hexa.model, pin.Model) and isinstance(hexa.data, pin.Data)
    assert hexa.nq == hexa.model.nq and np.array_equal(hexa.q0, pin.neutral(hexa.model))
    assert len(hexa.constraint_models) == 6
    sol = hexa.forward([0.01, 0.0, -0.01, 0.0, 0.01, 0.0])
    assert isinstance(sol.placement, pin.SE3) and np.allclose(sol.placement.homogeneous, sol.pose)
    back = hexa.inverse(sol.placement)
    np.testing.assert_allclose(back.lengths, sol.lengths, atol=1e-10)
    hybrid = hexa.solve({"platform_joint": sol.placement})
    np.testing.assert_allclose(hybrid.lengths, sol.lengths, atol=1e-10)
