"""The Krawczyk proof of a warm step (:mod:`hexapod_model.kinematics.newton.krawczyk`).

The interval primitives against mpmath's interval arithmetic (a plain Python reference at 120
bits), the rounding allowance, the enclosures against point evaluations, the proof's soundness
on seeded warm steps of every preset, and refusals where a second root lies close by.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pytest

from hexapod_model.kinematics.newton.enclosure import enclose
from hexapod_model.kinematics.newton.intervals import (
    REL,
    motion,
    placement,
    product,
    times_motion,
    times_motion_inline,
    times_point,
    times_point_inline,
)
from hexapod_model.kinematics.newton.proof import StepProver
from hexapod_model.lie import rpy_to_matrix

from ..conftest import limits_only as hexapod  # the cones would rule out the fold poses these cases are about

iv = pytest.importorskip("mpmath").iv
DATA = Path(__file__).parents[1] / "data"


@functools.cache
def _prover(name: str) -> StepProver:
    prover = StepProver.of(hexapod(name).closed_loop)
    assert prover is not None
    return prover


def _iv(m: float, r: float):
    return iv.mpf([m, m]) + iv.mpf([-r, r])


def _inside(ref, m: float, r: float) -> bool:
    """Whether the mpmath interval ``ref`` lies within ``m +- r``."""
    lo, hi = _iv(m, r).a, _iv(m, r).b
    return bool(ref.a >= lo and ref.b <= hi)


def test_the_primitives_enclose_the_exact_values_of_an_mpmath_reference():
    iv.prec = 120
    rng = np.random.default_rng(3)
    for _ in range(20):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        S = np.concatenate([np.zeros(3), axis])
        xm, xr = rng.uniform(-3, 3), 10.0 ** rng.uniform(-9, -1)
        Mm, Mr = np.empty((3, 4)), np.empty((3, 4))
        motion(S, xm, xr, Mm, Mr)
        x = _iv(xm, xr)
        c, s = iv.cos(x), iv.sin(x)
        for a in range(3):
            for b in range(3):
                aa = iv.mpf(axis[a]) * iv.mpf(axis[b])
                K = [[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]][a][b]
                exact = c * ((1 if a == b else 0) - aa) + s * iv.mpf(K) + aa
                assert _inside(exact, Mm[a, b], Mr[a, b]), (a, b)
        Am, Ar = rng.normal(size=(3, 4)), 10.0 ** rng.uniform(-12, -3, (3, 4))
        Cm, Cr = np.empty((3, 4)), np.empty((3, 4))
        product(Am, Ar, Mm, Mr, Cm, Cr)
        for a in range(3):
            for b in range(4):
                exact = sum(_iv(Am[a, k], Ar[a, k]) * _iv(Mm[k, b], Mr[k, b]) for k in range(3))
                if b == 3:
                    exact += _iv(Am[a, 3], Ar[a, 3])
                assert _inside(exact, Cm[a, b], Cr[a, b]), (a, b)


@pytest.mark.parametrize("compiled", [True, False])
def test_the_products_by_columns_enclose_the_exact_values_of_an_mpmath_reference(compiled):
    # times_motion and times_point skip the exact zeros and ones of axis motions and identity rotations,
    # on placements held as tuples; the general ones go through product
    iv.prec = 120
    rng = np.random.default_rng(4)
    # the calls compiled, or the inlined functions' own code run as Python (what they call compiled)
    tm, tp = (times_motion, times_point) if compiled else (times_motion_inline.py_func, times_point_inline.py_func)
    scratch = np.empty((6, 3, 4))

    def arrays(C: tuple) -> tuple[np.ndarray, np.ndarray]:  # the (midpoints, radii) 12-tuples as 3 x 4 arrays
        return np.array(C[0]).reshape(3, 4), np.array(C[1]).reshape(3, 4)

    for trial in range(24):
        Am, Ar = rng.normal(size=(3, 4)), 10.0 ** rng.uniform(-12, -3, (3, 4))
        j, sign, rotation = trial % 3, rng.choice([-1.0, 1.0]), trial % 2 == 0
        S = np.zeros(6)
        S[j + (3 if rotation else 0)] = sign
        if trial % 8 == 7:  # any other direction: the general product
            S[3 if rotation else 0 : 6 if rotation else 3] = rng.normal(size=3)
            S /= np.linalg.norm(S)
        xm, xr = rng.uniform(-3, 3), 10.0 ** rng.uniform(-9, -1)
        A = placement(Am), placement(Ar)
        Cm, Cr = arrays(tm(*A, S, xm, xr, scratch))
        x = _iv(xm, xr)
        if rotation:
            w = S[3:]
            c, s = iv.cos(x), iv.sin(x)
            K = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
            M = [
                [c * ((1 if a == b else 0) - w[a] * w[b]) + s * K[a][b] + w[a] * w[b] for b in range(3)]
                for a in range(3)
            ]
            t = [0, 0, 0]
        else:
            M = [[iv.mpf(1 if a == b else 0) for b in range(3)] for a in range(3)]
            t = [x * S[a] for a in range(3)]
        for a in range(3):
            for b in range(4):
                col = [M[k][b] for k in range(3)] if b < 3 else t
                exact = sum(_iv(Am[a, k], Ar[a, k]) * col[k] for k in range(3))
                if b == 3:
                    exact += _iv(Am[a, 3], Ar[a, 3])
                assert _inside(exact, Cm[a, b], Cr[a, b]), (trial, a, b)
        P = np.eye(4)
        P[:3, 3] = rng.normal(size=3)
        if trial % 3 == 0:
            P[:3, :3] = rpy_to_matrix(*rng.uniform(-1, 1, 3))
        Cm, Cr = arrays(tp(*A, P, scratch))
        for a in range(3):
            for b in range(4):
                exact = sum(_iv(Am[a, k], Ar[a, k]) * iv.mpf(P[k, b]) for k in range(3))
                if b == 3:
                    exact += _iv(Am[a, 3], Ar[a, 3])
                assert _inside(exact, Cm[a, b], Cr[a, b]), (trial, a, b)


def test_a_rounding_allowance_is_added_to_every_radius():
    A = np.array([[0.1, 0.2, 0.3, 0.4], [0.5, 0.6, 0.7, 0.8], [0.9, 1.1, 1.3, 1.7]])
    Cm, Cr = np.empty((3, 4)), np.empty((3, 4))
    product(A, np.zeros((3, 4)), A, np.zeros((3, 4)), Cm, Cr)  # point intervals: exact radius 0
    assert np.all(Cr >= REL * np.abs(Cm))
    Mm, Mr = np.empty((3, 4)), np.empty((3, 4))
    motion(np.array([0.0, 0, 0, 0, 0, 1]), 0.3, 0.0, Mm, Mr)  # an exact angle: cos and sin still round
    assert Mr[0, 0] >= REL and Mr[0, 1] >= REL


@pytest.mark.parametrize("name", ["reference", "3-6"])
def test_the_enclosures_hold_point_evaluations_inside_the_box(name):
    prover = _prover(name)
    hexa = hexapod(name)
    q = hexa.inverse(hexa.home_pose @ _moved(np.random.default_rng(1)), check=False).q
    T0 = prover.platform(q)
    x, held = prover.unknowns(q, T0), q[prover.held_q]
    nf = x.size
    rho, hr = np.full(nf, 1e-3), np.full(6, 1e-4)
    Fm, Fr, Jm, Jr = np.empty(nf), np.empty(nf), np.empty((nf, nf)), np.empty((nf, nf))
    enclose(*prover.tables, T0, x, rho, held, hr, True, Fm, Fr, Jm, Jr)
    rng = np.random.default_rng(2)
    fm, fr, jm, jr = np.empty(nf), np.empty(nf), np.empty((nf, nf)), np.empty((nf, nf))
    for _ in range(30):
        y = x + rho * rng.choice([-1.0, 1.0], nf) * rng.uniform(0.5, 1.0, nf)
        enclose(*prover.tables, T0, y, 0 * rho, held + hr * rng.uniform(-1, 1, 6), 0 * hr, True, fm, fr, jm, jr)
        assert np.all(np.abs(fm - Fm) <= Fr) and np.all(np.abs(jm - Jm) <= Jr)


def _moved(rng) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = rng.uniform(-0.03, 0.03, 3)
    T[:3, :3] = rpy_to_matrix(*np.radians(rng.uniform(-10, 10, 3)))
    return T


@pytest.mark.parametrize("name", ["reference", "3-6", "guideway"])
def test_the_residuals_enclosure_at_a_point_holds_pinocchios_closure_residual(name):
    """An independent reference: Pinocchio's frames at a configuration off the closure.

    The residual ``F`` (tip minus anchor, m; for 6-D closures ``vex`` of the skew part of
    ``R_tip R_anchor^T``, rad) enclosed at the configuration's own unknowns holds Pinocchio's
    value within Pinocchio's rounding (1e-14 m or rad).
    """
    import pinocchio as pin

    prover, hexa = _prover(name), hexapod(name)
    clm = hexa.closed_loop
    rows = prover.tables[4]
    rng = np.random.default_rng(8)
    data = clm.model.createData()
    for _ in range(5):
        q = hexa.inverse(hexa.home_pose @ _moved(rng), check=False).q.copy()
        legs = [k for k in range(clm.model.nq) if not clm.platform_q <= k < clm.platform_q + 7]
        q[legs] += rng.normal(0.0, 3e-3, len(legs))  # off the closure: a residual of millimetres
        T0 = prover.platform(q)
        x = prover.unknowns(q, T0)
        nf = x.size
        Fm, Fr, Jm, Jr = np.empty(nf), np.empty(nf), np.empty((nf, nf)), np.empty((nf, nf))
        enclose(*prover.tables, T0, x, np.zeros(nf), q[prover.held_q], np.zeros(6), False, Fm, Fr, Jm, Jr)
        pin.framesForwardKinematics(clm.model, data, q)
        for i, leg in enumerate(clm.legs):
            tip, anchor = data.oMf[leg.tip_frame], data.oMf[leg.anchor_frame]
            F = list(tip.translation - anchor.translation)
            if rows == 6:
                E = tip.rotation @ anchor.rotation.T
                F += [0.5 * (E[(a + 2) % 3, (a + 1) % 3] - E[(a + 1) % 3, (a + 2) % 3]) for a in range(3)]
            got = slice(i * rows, (i + 1) * rows)
            assert np.all(np.abs(Fm[got] - F) <= Fr[got] + 1e-14), (i, Fm[got], F)
        assert np.max(np.abs(Fm)) > 1e-4  # the configuration is off the closure


@pytest.mark.parametrize("name", ["reference", "intersecting", "spherical", "3-6", "guideway"])
def test_a_proven_warm_step_holds_the_generating_pose_within_its_bounds(name):
    hexa, prover = hexapod(name), _prover(name)
    rng = np.random.default_rng(11)
    proven = 0
    for _ in range(6):
        T = hexa.home_pose @ _moved(rng)
        start = hexa.inverse(T, check=False)
        step = np.eye(4)
        step[:3, 3] = rng.normal(size=3) * 1e-4
        truth = hexa.inverse(T @ step, check=False)
        if not (start.converged and truth.converged):
            continue
        sol = hexa.forward(truth.lengths, guess=start, check=False)
        proof = prover.prove(start.q, sol.q)
        if not proof.proven:
            continue
        proven += 1
        assert proof.position_m < 1e-6 and proof.rotation_rad < 1e-6
        d = np.linalg.norm(sol.pose[:3, 3] - truth.pose[:3, 3])
        E = sol.pose[:3, :3].T @ truth.pose[:3, :3]
        angle = np.arcsin(min(1.0, 0.5 * np.linalg.norm([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])))
        assert d <= proof.position_m + 1e-12 and angle <= proof.rotation_rad + 1e-12
    assert proven >= 4


def test_a_double_root_at_a_fold_is_not_proven():
    hexa, prover = hexapod("3-6"), _prover("3-6")
    case = json.loads((DATA / "three_six_near_fold.json").read_text())["cases"][0]
    fold = hexa.inverse(np.array(case["fold_pose"]), check=False)
    assert fold.closed
    assert not prover.prove(fold.q, fold.q).proven  # the Jacobian is singular there: no unique root
    home = hexapod("3-6").q_home
    assert prover.prove(home, home).proven  # the same zero-length path at a regular pose is


def test_a_warm_step_to_another_assembly_is_not_proven():
    hexa, prover = hexapod("3-6"), _prover("3-6")
    case = json.loads((DATA / "three_six_warm_wrong.json").read_text())
    guess = hexa.inverse(np.array(case["guess_pose"]), check=False)
    wrong = hexa.inverse(np.array(case["returned_pose"]), check=False)
    truth = hexa.inverse(np.array(case["true_pose"]), check=False)
    assert wrong.closed and truth.closed
    assert not prover.prove(guess.q, wrong.q).proven


def _ends(prover: StepProver, q0: np.ndarray, q1: np.ndarray) -> tuple:
    T0 = prover.platform(q1)
    return T0, prover.unknowns(q0, T0), prover.unknowns(q1, T0), q0[prover.held_q].copy(), q1[prover.held_q].copy()


def test_the_whole_path_test_and_the_subdividing_one_bound_the_same_end():
    """One test of the whole step about the result, and the path halved: both hold the generating pose."""
    from hexapod_model.kinematics.newton.krawczyk import prove_path, prove_whole

    hexa, prover = hexapod("reference"), _prover("reference")
    start = hexa.inverse(hexa.home_pose @ _moved(np.random.default_rng(5)))
    step = np.eye(4)
    step[:3, 3] = [4e-4, -2e-4, 2e-4]
    truth = hexa.inverse(start.pose @ step)
    sol = hexa.forward(truth.lengths, guess=start)
    T0, x0, x1, l0, l1 = _ends(prover, start.q, sol.q)
    work = prover.work()[0]
    whole = prove_whole(prover.tables, T0, x0, x1, l0, l1, True, work)
    whole = (whole[0], whole[1], whole[2].copy(), whole[3])
    path = prove_path(prover.tables, T0, x0, x1, l0, l1, True, work)
    assert whole[0] and whole[1] == 1 and whole[3] == 1
    assert path[0] and path[1] >= 1 and path[3] >= 1  # the path's own tests and sub-intervals
    exact = prover.unknowns(truth.q, T0)
    for _, _, radius, _ in (whole, path):
        assert np.all(np.abs(exact - x1) <= radius + 1e-12)


def _whole(prover: StepProver, work: tuple, q0: np.ndarray, q1: np.ndarray, truth: np.ndarray) -> None:
    """``prove_whole`` of the step ``q0`` -> ``q1`` on ``work``: proven, its bound holding the generating ``truth``."""
    from hexapod_model.kinematics.newton.krawczyk import prove_whole

    T0, x0, x1, l0, l1 = _ends(prover, q0, q1)
    proven, tests, radius, parts = prove_whole(prover.tables, T0, x0, x1, l0, l1, True, work)
    assert proven and tests == 1 and parts == 1
    assert np.all(np.abs(prover.unknowns(truth, T0) - x1) <= radius + 1e-12)


def test_the_whole_path_test_reuses_its_preconditioner_and_never_a_stale_or_broken_one():
    """Step after step the per-leg preconditioner is built once and then reused (its blocks kept
    bit for bit); at a distant pose it is built afresh; one a failed setup left partly written is
    never used: the step's blocks are those a fresh work builds."""
    from hexapod_model.kinematics.newton.krawczyk import HELD, held_setup

    hexa, prover = hexapod("reference"), _prover("reference")
    rng = np.random.default_rng(11)
    step = np.eye(4)
    step[:3, 3] = [2e-5, -1e-5, 1e-5]  # a 1 kHz sample's motion
    work = prover.work()[0]
    L = work[5][0]  # the legs' left factors
    assert work[0][HELD][0] == 0.0
    prev, held = hexa.inverse(hexa.home_pose @ _moved(rng)), None
    for _ in range(5):
        truth = hexa.inverse(prev.pose @ step)
        sol = hexa.forward(truth.lengths, guess=prev, prove=False)
        _whole(prover, work, prev.q, sol.q, truth.q)
        assert work[0][HELD][0] == 1.0
        if held is not None:
            assert np.array_equal(L, held)  # reused
        held, prev = L.copy(), sol

    far = hexa.inverse(hexa.home_pose @ _moved(rng) @ _moved(rng))  # another pose: the held one not tried there
    truth = hexa.inverse(far.pose @ step)
    sol = hexa.forward(truth.lengths, guess=far, prove=False)
    _whole(prover, work, far.q, sol.q, truth.q)
    assert not np.array_equal(L, held)  # rebuilt

    Jm = work[1]
    assert not held_setup(np.zeros_like(Jm), prover.tables[4], work, np.zeros(prover.nf))  # singular: partly written
    assert work[0][HELD][0] == 0.0
    _whole(prover, work, far.q, sol.q, truth.q)
    fresh = StepProver.of(hexa.closed_loop)
    assert fresh is not None
    fresh_work = fresh.work()[0]
    _whole(fresh, fresh_work, far.q, sol.q, truth.q)
    assert np.array_equal(L, fresh_work[5][0])


def test_a_step_whose_leg_is_ill_conditioned_is_proven_only_subdivided():
    """A turned pose (48 deg of yaw) where a leg's joints couple strongly: one test of the whole
    0.8 mm step fails; the halved path proves it, and the proof's bounds hold the pose."""
    hexa, prover = hexapod("reference"), _prover("reference")
    T = np.eye(4)
    T[:3, 3] = [0.05802425, 0.07538191, 0.43002195]
    T[:3, :3] = rpy_to_matrix(0.02637685, 0.13464285, 0.83210861)
    start = hexa.inverse(T)
    dl = np.array([0.00509281, -0.02605381, 0.03389148, 0.01265576, -0.00728817, -0.05404263]) / 64
    sol = hexa.forward(start.lengths + dl, guess=start, check=False)
    one = prover.prove(start.q, sol.q, subdivide=False)
    halved = prover.prove(start.q, sol.q)
    assert not one.proven and one.tests == 1
    assert halved.proven and halved.tests > 2 and halved.subdivisions > 1
    assert sol.converged and sol.proof is not None and sol.proof.proven


def _calls(module: str, callee: str) -> list:
    """The calls of ``callee`` (by name) in the source of ``hexapod_model.kinematics.newton.<module>`` (AST nodes)."""
    import ast
    import importlib
    import inspect

    source = inspect.getsource(importlib.import_module(f"hexapod_model.kinematics.newton.{module}"))
    return [
        node
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == callee
    ]


def test_the_proof_calls_its_enclosure_with_a_plain_boolean():
    """One compiled enclosure for both kinds of call (with and without the Jacobian), not one per constant.

    numba compiles a function once per literal argument: a constant ``True`` or ``False`` passed
    as ``jacobian`` compiled the enclosure twice, about 10 s of the proof's first compilation.
    """
    import ast

    from numba import njit, types

    from hexapod_model.kinematics.newton.enclosure import JACOBIAN

    calls = _calls("krawczyk", "enclose_into")
    assert len(calls) >= 5
    for call in calls:
        jacobian = call.args[10]
        assert not isinstance(jacobian, ast.Constant), ast.unparse(call)
        assert ast.unparse(jacobian) in ("JACOBIAN[0]", "JACOBIAN[1]"), ast.unparse(call)

    @njit
    def typed(flag):
        return flag

    @njit
    def both():
        return typed(JACOBIAN[0]), typed(JACOBIAN[1])

    assert both() == (False, True)
    assert typed.signatures == [(types.boolean,)]  # one specialisation, not Literal[bool](False) and (True)


@pytest.mark.parametrize(
    ("module", "callee", "index"), [("enclosure", "_weights", 2), ("krawczyk_blocks", "_invert", 1)]
)
def test_the_proof_passes_its_compiled_helpers_no_constant_they_would_compile_once_more_for(module, callee, index):
    """The enclosure's transpose flag of its rotation weights and the preconditioner's inverse's size, at run time.

    A constant argument types as a literal (``Literal[bool](True)``, ``Literal[int](6)``): numba
    compiles the callee once more for each, beside its ``boolean`` or ``int64`` specialisation.
    """
    import ast

    calls = _calls(module, callee)
    assert len(calls) >= 2
    for call in calls:
        assert not isinstance(call.args[index], ast.Constant), ast.unparse(call)
