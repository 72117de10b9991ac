"""The compiled chain evaluation and free-flyer kernels against Pinocchio's own kinematics."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.kinematics.newton.chains import evaluate_chains
from hexapod_model.kinematics.newton.legs import GENERAL, IDENTITY, SHIFT, ChainTables
from hexapod_model.lie.compiled import difference_free_flyer, integrate_free_flyer

from ..conftest import PRESET_NAMES, hexapod
from .test_newton import idle_roll_hexapod


def chain_buffers(nv: int) -> tuple[np.ndarray, ...]:
    return np.zeros((6, nv)), np.zeros((12, 3, 3)), np.zeros((12, 3))


def random_q(hexa, rng: np.random.Generator) -> np.ndarray:
    """Leg joints anywhere in [-pi, pi] (beyond their limits: kinematics do not care), any platform pose."""
    q = rng.uniform(-np.pi, np.pi, hexa.nq)
    i = hexa.closed_loop.platform_q
    quat = rng.normal(size=4)
    q[i : i + 3], q[i + 3 : i + 7] = rng.normal(0.0, 0.3, 3), quat / np.linalg.norm(quat)
    return q


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_chain_evaluation_matches_pinocchio(name):
    hexa = hexapod(name)
    clm, m = hexa.closed_loop, hexa.model
    data = m.createData()
    tables = ChainTables.of(clm)
    assert tables is not None and tables.placements.shape[1] == len(clm.legs[0].joints)
    J, R, p = chain_buffers(m.nv)
    rng = np.random.default_rng(20)
    for _ in range(200):
        q = random_q(hexa, rng)
        J[:] = np.nan  # every column must be written
        evaluate_chains(
            q, tables.placements, tables.kinds, tables.motions, tables.leg_q, tables.leg_v, tables.closure, tables.home,
            tables.platform_q, tables.platform_v, J, R, p,
        )  # fmt: skip
        pin.forwardKinematics(m, data, q)
        pin.computeJointJacobians(m, data, q)
        pin.updateFramePlacements(m, data)
        np.testing.assert_allclose(J, data.J, rtol=0, atol=1e-12)
        for i, leg in enumerate(clm.legs):
            for frame, row in ((leg.tip_frame, i), (leg.anchor_frame, 6 + i)):
                np.testing.assert_allclose(R[row], data.oMf[frame].rotation, rtol=0, atol=1e-12)
                np.testing.assert_allclose(p[row], data.oMf[frame].translation, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_placement_kinds_skip_only_exact_ones_and_zeros(name):
    # the SHIFT / IDENTITY shortcuts give the numbers of the full products, bit for bit
    hexa = hexapod(name)
    tables = ChainTables.of(hexa.closed_loop)
    assert tables is not None
    if name == "reference":  # the offset Cardans: rotated, shifted and plain joint frames
        assert set(tables.kinds.ravel()) == {GENERAL, SHIFT, IDENTITY}
    general = np.full_like(tables.kinds, GENERAL)
    rng = np.random.default_rng(22)
    for _ in range(50):
        q = random_q(hexa, rng)
        out = []
        for kinds in (tables.kinds, general):
            bufs = chain_buffers(hexa.model.nv)
            evaluate_chains(
                q, tables.placements, kinds, tables.motions, tables.leg_q, tables.leg_v, tables.closure,
                tables.home, tables.platform_q, tables.platform_v, *bufs,
            )  # fmt: skip
            out.append(b"".join(np.where(b == 0.0, 0.0, b).tobytes() for b in bufs))  # -0.0 and 0.0 alike
        assert out[0] == out[1]


@pytest.mark.parametrize("name", ["reference", "spherical"])
def test_the_compiled_kernels_agree_with_their_python_source(name):
    # numba's machine code against the same source run by Python (NumPy's sin and cos may differ
    # from libm's in the last bit): the chains, the reduced Jacobian and the free-flyer step
    from hexapod_model.kinematics.newton.kernels import closure_residual, jacobian

    hexa = hexapod(name)
    clm = hexa.closed_loop
    tables = ChainTables.of(clm)
    assert tables is not None
    solver = hexa.engine.solver(hexa.engine.held_forward)
    args = (tables.placements, tables.kinds, tables.motions, tables.leg_q, tables.leg_v, tables.closure, tables.home)
    rng = np.random.default_rng(26)
    for _ in range(5):
        q = random_q(hexa, rng)
        out = []
        for chains, jac in ((evaluate_chains, jacobian), (evaluate_chains.py_func, jacobian.py_func)):
            J, R, p = chain_buffers(hexa.model.nv)
            chains(q, *args, tables.platform_q, tables.platform_v, J, R, p)
            E, r, G = np.empty((6, 3, 3)), np.empty(6 * solver.rows), np.full(solver.G.shape, np.nan)
            closure_residual(R, p, solver.rows, E, r, 1.0)
            jac(J, solver.leg_cols, solver.ff_cols, solver.colmap, solver.rows, p, E, G)
            out.append((J, R, p, G))
        for compiled, python in zip(*out):
            np.testing.assert_allclose(compiled, python, rtol=0, atol=1e-14)  # m, rad and their derivatives
        x, v = q[clm.platform_q : clm.platform_q + 7], rng.normal(0.0, 0.3, 6)
        a, b = x.copy(), x.copy()
        integrate_free_flyer(a, v)
        integrate_free_flyer.py_func(b, v)
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-15)  # m, and the unit quaternion


def test_tables_refuse_legs_of_different_joint_counts():
    assert ChainTables.of(idle_roll_hexapod().closed_loop) is None


def test_free_flyer_integration_matches_pinocchio():
    hexa = hexapod("reference")
    m, i = hexa.model, hexa.closed_loop.platform_q
    iv = hexa.closed_loop.platform_v
    rng = np.random.default_rng(23)
    for scale in (1e-8, 1e-3, 0.5):
        for _ in range(100):
            q = random_q(hexa, rng)
            dv = np.zeros(m.nv)
            dv[iv : iv + 6] = rng.normal(0.0, scale, 6)
            x = q[i : i + 7].copy()
            integrate_free_flyer(x, dv[iv : iv + 6])
            np.testing.assert_allclose(x, pin.integrate(m, q, dv)[i : i + 7], rtol=0, atol=1e-15)


def test_free_flyer_difference_matches_pinocchio():
    hexa = hexapod("reference")
    m, i = hexa.model, hexa.closed_loop.platform_q
    iv = hexa.closed_loop.platform_v
    rng = np.random.default_rng(24)
    out, scratch = np.empty(6), (np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty(3))
    for scale in (1e-9, 1e-6, 1e-3, 0.5, 2.0):  # both sides of the Taylor threshold, up to large turns
        for _ in range(50):
            q0 = random_q(hexa, rng)
            dv = np.zeros(m.nv)
            dv[iv : iv + 6] = rng.normal(0.0, scale, 6)
            q1 = pin.integrate(m, q0, dv)
            difference_free_flyer(q0[i : i + 7], q1[i : i + 7], out, *scratch)
            atol = 1e-14 if scale < 1 else 1e-12  # acos is ill-conditioned towards a half turn
            np.testing.assert_allclose(out, pin.difference(m, q0, q1)[iv : iv + 6], rtol=0, atol=atol)
