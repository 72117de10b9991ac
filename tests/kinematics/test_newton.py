"""The compiled Newton iteration (fast path) against the general path, and what falls back to it."""

from __future__ import annotations

import functools

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.model import ClosedLoopModel
from hexapod_model.description.urdf import geometry_to_urdf
from hexapod_model.kinematics.certificate import Outcome
from hexapod_model.kinematics.newton.compiled import CompiledSolver, solver_for
from hexapod_model.kinematics.newton.solver import NewtonSolver

from ..conftest import PATH_TOL, PRESET_NAMES, assert_same_message, assert_same_solution, hexapod

_ROLL = """  <joint name="leg1_roll" type="revolute">
    <origin xyz="0 0 0" rpy="0 0 0" />
    <parent link="leg1_base_cross" />
    <child link="leg1_roll_link" />
    <axis xyz="0 0 1" />
    <limit lower="-3" upper="3" effort="1000" velocity="1" />
  </joint>
  <link name="leg1_roll_link" />
"""


@functools.cache
def idle_roll_hexapod() -> hm.Hexapod:
    """The spherical preset with a fourth joint in leg 1: a roll about the leg axis, through the ball joint.

    The roll moves no closure point, so poses and readings are the spherical preset's; the leg
    has 4 joints for 3 closure rows (not the compiled path's layout).
    """
    text = geometry_to_urdf(hm.get_preset("spherical"))
    head = '  <joint name="leg1_prismatic" type="prismatic">\n    <origin xyz="0 0 0" rpy="0 0 0" />\n'
    assert text.count(head + '    <parent link="leg1_base_cross" />') == 1
    text = text.replace(
        head + '    <parent link="leg1_base_cross" />', _ROLL + head + '    <parent link="leg1_roll_link" />'
    )
    return hm.Hexapod(ClosedLoopModel(text, "<idle roll>"))


def solvers(hexa: hm.Hexapod, held: tuple[int, ...]) -> tuple[NewtonSolver, NewtonSolver]:
    """The solver the hexapod uses for ``held`` and the general one."""
    return solver_for(hexa.closed_loop, held), NewtonSolver(hexa.closed_loop, held)


def assert_same_run(fast: tuple, general: tuple) -> None:
    """Same status, message and iterations; configurations and Jacobians to rounding."""
    q, status, iterations, residual, jacobian, message = fast
    assert (status, iterations) == (general[1], general[2])
    assert_same_message(message, general[5], numbers=status != "max_iterations")
    np.testing.assert_allclose(q, general[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(jacobian, general[4], rtol=0, atol=1e-11)
    if status == "converged":
        assert residual <= 1e-12 and general[3] <= 1e-12
    else:
        np.testing.assert_allclose(residual, general[3], rtol=1e-6)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_compiled_path_equals_the_general_path(name):
    # far beyond the seed 000 box: converged, out-of-limits and flipped or unconverged starts
    hexa = hexapod(name)
    clm = hexa.closed_loop
    fk_fast, fk_general = solvers(hexa, hexa.engine.held_forward)
    ik_fast, ik_general = solvers(hexa, hexa.engine.held_inverse)
    assert isinstance(fk_fast, CompiledSolver) and isinstance(ik_fast, CompiledSolver)
    assert (fk_fast.home_sign, fk_fast.home_kappa) == pytest.approx((fk_general.home_sign, fk_general.home_kappa))
    statuses = set()
    for T in box_poses(hexa.home_pose, 150, seed=31, translation=0.1, angle_deg=45):
        q = hexa.q_home
        hexa.engine.set_pose(q, T)
        ik = ik_fast.run(q, 1e-12, 20)
        assert_same_run(ik, ik_general.run(q, 1e-12, 20))
        q = hexa.q_home
        q[clm.prismatic_q] = np.clip(ik[0][clm.prismatic_q], hexa.stroke[:, 0], hexa.stroke[:, 1])
        for max_iter in (20, 2):
            fk = fk_fast.run(q, 1e-12, max_iter)
            assert_same_run(fk, fk_general.run(q, 1e-12, max_iter))
            statuses.add(fk[1])
    assert {"converged", "max_iterations"} <= statuses


def test_singular_status_and_message_are_the_general_paths():
    clm = ClosedLoopModel(hm.geometry_to_urdf(vertical_legs()))  # refused by Hexapod: singular at home
    held = tuple(leg.prismatic for leg in clm.legs)
    fast, general = solver_for(clm, held), NewtonSolver(clm, held)
    assert isinstance(fast, CompiledSolver)
    q = clm.q_home.copy()
    q[clm.prismatic_q] = 0.01
    result = fast.run(q, 1e-12, 20)
    assert result[1] == "singular" and "pivot ratio" in result[5]
    assert_same_run(result, general.run(q, 1e-12, 20))
    result = fast.run(clm.q_home, 1e-12, 20)
    assert result[1] == "singular" and "no step taken" in result[5]
    assert_same_run(result, general.run(clm.q_home, 1e-12, 20))


def vertical_legs() -> hm.HexapodGeometry:
    """All six legs vertical: the platform can rotate about z and slide sideways freely."""
    import dataclasses

    legs = tuple(
        hm.LegGeometry(
            base_anchor=(0.2 * np.cos(a), 0.2 * np.sin(a), 0.0),
            platform_anchor=(0.2 * np.cos(a), 0.2 * np.sin(a), 0.0),
            stroke=(-0.1, 0.1),
        )
        for a in np.linspace(0, 2 * np.pi, 6, endpoint=False)
    )
    return dataclasses.replace(hm.get_preset("spherical"), name="vertical", legs=legs)


def test_hybrid_held_sets():
    # one joint held per leg, the platform free: the Schur structure, so the compiled path
    hexa = hexapod("reference")
    truth = hexa.inverse(box_poses(hexa.home_pose, 1, seed=33)[0])
    one_per_leg = tuple(sorted([*hexa.engine.held_forward[:5], hexa.model.getJointId("leg6_cardan_base_1")]))
    fast, general = solvers(hexa, one_per_leg)
    assert isinstance(fast, CompiledSolver)
    start = hexa.q_home
    for j in one_per_leg:
        iq = hexa.model.joints[j].idx_q
        start[iq] = truth.q[iq]
    result = fast.run(start, 1e-12, 20)
    assert result[1] == "converged"
    assert_same_run(result, general.run(start, 1e-12, 20))
    np.testing.assert_allclose(hexa.pose_of(result[0]), truth.pose, rtol=0, atol=1e-9)
    # two joints held in leg 5, none in leg 6; every joint free: the general path
    two_in_leg5 = tuple(sorted([*hexa.engine.held_forward[:5], hexa.model.getJointId("leg5_cardan_base_1")]))
    assert not isinstance(solver_for(hexa.closed_loop, two_in_leg5), CompiledSolver)
    assert not isinstance(solver_for(hexa.closed_loop, ()), CompiledSolver)


def test_legs_of_different_joint_counts_solve_through_the_general_path():
    hexa, plain = idle_roll_hexapod(), hexapod("spherical")
    assert not isinstance(hexa.engine.solver(hexa.engine.held_forward), CompiledSolver)
    assert not isinstance(hexa.engine.solver(hexa.engine.held_inverse), CompiledSolver)
    for T in box_poses(plain.home_pose, 20, seed=32):
        back = hexa.inverse(T)
        np.testing.assert_allclose(back.lengths, plain.inverse(T).lengths, rtol=0, atol=1e-10)
        sol = hexa.forward(back.lengths)
        np.testing.assert_allclose(sol.pose, T, rtol=0, atol=1e-9)


def assert_same_iterate(fast: NewtonSolver, general: NewtonSolver, args: tuple, nq: int) -> str:
    """Same outcome and certificate from :meth:`iterate` on both solvers; returns the status."""
    a, b = fast.iterate(*args), general.iterate(*args)
    assert (a[0], a[1]) == (b[0], b[1])
    assert_same_message(a[3], b[3], numbers=a[0] != "max_iterations")
    assert (fast.certified, fast.det_sign, fast.sign) == (general.certified, general.det_sign, general.sign)
    np.testing.assert_allclose(fast.q_aug[:nq], general.q_aug[:nq], rtol=0, atol=1e-12)
    np.testing.assert_allclose([fast.theta, fast.kappa], [general.theta, general.kappa], rtol=1e-6, atol=1e-12)
    return a[0]


@pytest.mark.parametrize("name", ["reference", "3-6"])
def test_certified_iterations_equal_the_general_path(name):
    hexa = hexapod(name)
    clm = hexa.closed_loop
    fast, general = solvers(hexa, hexa.engine.held_forward)
    statuses = set()
    for T in box_poses(hexa.home_pose, 60, seed=34, translation=0.1, angle_deg=40):
        q = hexa.q_home
        q[clm.prismatic_q] = np.clip(hexa.inverse(T, check=False).q[clm.prismatic_q], *hexa.stroke.T)
        for sign in (fast.home_sign, -fast.home_sign, 0.0):
            statuses.add(assert_same_iterate(fast, general, (q, 1e-12, 20, sign, None, 0.0, True), clm.nq))
        # a homotopy step from a start that does not close: r - scale * offset
        offset, _ = general.evaluate(q)
        start = hexa.q_home
        start[clm.prismatic_q] = 0.5 * q[clm.prismatic_q]
        assert_same_iterate(fast, general, (start, 1e-4, 20, fast.home_sign, offset, 0.5, True), clm.nq)
    assert {"converged", "uncertified"} <= statuses


def test_forward_solutions_equal_the_general_path():
    # the assembly certificate (substeps, candidates) over the compiled iterations
    fast, general = hexapod("3-6"), hm.Hexapod.from_preset("3-6")
    held = general.engine.held_forward
    general.engine.local.solvers = {held: NewtonSolver(general.closed_loop, held)}
    poses = box_poses(fast.home_pose, 80, seed=35, translation=0.1, angle_deg=40)
    statuses = set()
    for T in poses:
        readings = np.clip(fast.inverse(T, check=False).lengths, *fast.stroke.T)
        a, b = fast.forward(readings, check=False), general.forward(readings, check=False)
        assert (a.status, a.iterations, a.flags, a.det_sign) == (b.status, b.iterations, b.flags, b.det_sign)
        assert_same_message(a.message, b.message, numbers=a.status != "max_iterations")
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
        assert len(a.candidates) == len(b.candidates)
        statuses.add(a.status)
    assert "converged" in statuses and len(statuses) > 1


def _fields(sol: hm.Solution) -> tuple:
    """Everything a Solution holds, arrays as bytes (bitwise: two runs of one code path)."""
    arrays = (sol.pose, sol.q, sol.lengths, sol.jacobian, *sol.candidates)
    return (sol.status, sol.iterations, sol.residual, sol.message, sol.flags, sol.det_sign) + tuple(
        a.tobytes() for a in arrays
    )


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_one_call_forward_equals_the_python_path(name):
    # Hexapod.forward tries CompiledSolver.certified_forward (one compiled call) first; the
    # Python path (assembly.solve_forward, then _solution) must give the same Solution, to rounding
    hexa = hexapod(name)
    solver = hexa.engine.solver(hexa.engine.held_forward)
    assert solver.one_call is not None
    rng = np.random.default_rng(37)
    seen, flags, previous = set(), set(), None

    def check(readings: np.ndarray, guess: hm.Solution | None) -> hm.Solution:
        sign = solver.home_sign if guess is None else guess.det_sign
        joints = hexa.joints_of(readings)
        attempt = solver.certified_forward(hexa.engine.start(guess), joints, 1e-10, 50, sign)
        one_call = len(attempt) == 6  # converged certified: (q, pose, jacobian, iterations, residual, bad)
        start = hexa.engine.start(guess)
        slow = hexa.engine.finish(solver, start.copy(), 1e-10, 50, False, (joints, sign, guess is not None))
        review = hexa.engine.finder.exact is not None  # a 3-6 hexapod's every assembly (forward does it)
        slow = hexa.engine.judged(slow, readings, joints, guess, start, 1e-10, 50, False, review)  # and the proof
        q_aug, state = solver.q_aug.copy(), (solver.sign, solver.det_sign, solver.certified)
        kappa = solver.kappa
        fast = hexa.forward(readings, guess, tol=1e-10, max_iter=50, check=False)
        assert_same_solution(fast, slow)
        assert (solver.sign, solver.det_sign, solver.certified) == state
        if slow.status != "max_iterations":
            np.testing.assert_allclose(solver.q_aug, q_aug, rtol=0, atol=PATH_TOL)
            np.testing.assert_allclose(solver.kappa, kappa, rtol=1e-9)
        seen.add((fast.status, one_call))
        flags.update((f, one_call) for f in fast.flags)
        return fast

    for T in box_poses(hexa.home_pose, 40, seed=36, translation=0.1, angle_deg=40):
        readings = np.clip(hexa.inverse(T, check=False).lengths, *hexa.stroke.T)
        check(readings, None)
        sol = check(readings, previous)
        if np.all(np.isfinite(sol.q)):  # 1 ms later at 1 kHz, from this result (even out of limits)
            check(np.clip(readings + rng.normal(0.0, 1e-5, 6), *hexa.stroke.T), sol)
        previous = sol if sol.converged else previous
    assert {("converged", True), ("converged", False)} <= seen  # both paths taken
    if name in ("reference", "intersecting"):
        assert ("out_of_limits", True) in seen  # the joint-limit check of the compiled call
    if name == "3-6":
        assert ("near_singular", True) in flags


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_one_call_inverse_equals_the_python_path(name):
    # Hexapod.inverse solves, checks limits and builds the pose in one call (CompiledSolver.run_checked);
    # NewtonSolver.run then _solution must give the same Solution and solver state, to rounding
    hexa = hexapod(name)
    solver = hexa.engine.solver(hexa.engine.held_inverse)
    assert solver.one_call is not None
    statuses = set()
    for T in box_poses(hexa.home_pose, 60, seed=38, translation=0.15, angle_deg=50):
        for max_iter in (50, 1):
            q0 = hexa.engine.start(None)
            hexa.engine.set_pose(q0, T)
            slow = hexa.engine.solution(Outcome(*solver.run(q0, 1e-10, max_iter)), False, max_iter=max_iter)
            q_aug, theta, state = solver.q_aug.copy(), solver.theta, (solver.det_sign, solver.certified)
            fast = hexa.inverse(T, tol=1e-10, max_iter=max_iter, check=False)
            assert_same_solution(fast, slow)
            assert (solver.det_sign, solver.certified) == state
            if slow.status != "max_iterations" or max_iter == 1:
                np.testing.assert_allclose(solver.q_aug, q_aug, rtol=0, atol=PATH_TOL)
                np.testing.assert_allclose(solver.theta, theta, rtol=1e-9, atol=1e-15)
            statuses.add(fast.status)
    assert {"converged", "max_iterations", "out_of_limits"} <= statuses


def test_one_call_solves_take_strided_inputs_without_a_new_compiled_signature():
    # a column of a table (strided) or a hand-made Solution's view: the same answers, through the
    # one compiled signature (another would compile for a minute on a first run)
    from hexapod_model.kinematics.newton.iteration import solve_blocks, solve_schur

    hexa = hexapod("reference")
    good = hexa.forward(np.full(6, 0.01))
    hexa.inverse(good.pose)  # both entries compiled (or loaded) with contiguous arrays
    table = np.zeros((6, 3))
    table[:, 1] = np.full(6, 0.012)
    wide = np.zeros((hexa.nq, 2))
    wide[:, 0] = good.q
    guess = hm.Solution(good.pose, wide[:, 0], good.lengths, "converged", 0, 0.0, det_sign=good.det_sign)
    signatures = len(solve_schur.signatures), len(solve_blocks.signatures)
    assert not table[:, 1].flags.c_contiguous and not guess.q.flags.c_contiguous
    a = hexa.forward(table[:, 1], guess)
    b = hexa.forward(np.full(6, 0.012), good)
    assert _fields(a) == _fields(b)
    assert hexa.inverse(b.pose, guess).q.tobytes() == hexa.inverse(b.pose, good).q.tobytes()
    assert (len(solve_schur.signatures), len(solve_blocks.signatures)) == signatures
