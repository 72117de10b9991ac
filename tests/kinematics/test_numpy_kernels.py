"""The NumPy kernels (``compiled=False``) against the numba ones, and a short job without numba."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics.newton import numpy_kernels as nk
from hexapod_model.kinematics.newton.kernel_sets import kernel_set
from hexapod_model.kinematics.newton.solver import NewtonSolver

from ..conftest import PRESET_NAMES, hexapod


def random_configuration(hexa: hm.Hexapod, rng: np.random.Generator) -> np.ndarray:
    """A configuration near home (closures open): every joint and the platform moved a little."""
    m = hexa.closed_loop.model
    return pin.integrate(m, hexa.closed_loop.q_home, rng.uniform(-0.2, 0.2, m.nv))


@pytest.mark.parametrize("name", PRESET_NAMES)
@pytest.mark.parametrize("problem", ["forward", "inverse", "all free"])
def test_step_kernels_match_the_compiled_ones(name: str, problem: str) -> None:
    """Residual, Jacobian and the step's solve, pivot ratio, sign and condition bound to rounding."""
    hexa = hexapod(name)
    held = {"forward": hexa.engine.held_forward, "inverse": hexa.engine.held_inverse, "all free": ()}[problem]
    fast = NewtonSolver(hexa.closed_loop, held, kernel_set(True))
    slow = NewtonSolver(hexa.closed_loop, held, kernel_set(False))
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = random_configuration(hexa, rng)
        r1, G1 = fast.evaluate(q)
        r2, G2 = slow.evaluate(q)
        np.testing.assert_allclose(r2, r1, rtol=0, atol=1e-14)
        np.testing.assert_allclose(G2, G1, rtol=0, atol=1e-13)
        if not fast.square:
            continue
        ratio1, ratio2 = fast._solve_step(), slow._solve_step()
        np.testing.assert_allclose(ratio2, ratio1, rtol=1e-9)
        np.testing.assert_allclose(slow.x, fast.x, rtol=1e-9, atol=1e-12)
        assert slow.sign == fast.sign
        if fast.held_pos is not None:
            np.testing.assert_allclose(slow.kappa, fast.kappa, rtol=1e-9)


def test_factor_reports_singular_and_nan_as_zero() -> None:
    """A zero column or a NaN gives pivot ratio 0, as the compiled factorisation."""
    A = np.eye(4)
    A[:, 2] = 0.0
    assert nk.lu_factor(A, np.empty((4, 4)), np.empty(4, dtype=np.int64)) == 0.0
    A = np.eye(4)
    A[1, 1] = np.nan
    assert nk.lu_factor(A, np.empty((4, 4)), np.empty(4, dtype=np.int64)) == 0.0
    A = np.array([[1e-3, 1.0], [1.0, 1.0]])
    LU, piv = np.empty((2, 2)), np.empty(2, dtype=np.int64)
    ratio = nk.lu_factor(A, LU, piv)
    x = np.empty(2)
    nk.lu_apply(LU, piv, np.array([1.0, 2.0]), x)
    np.testing.assert_allclose(A @ x, [1.0, 2.0], rtol=0, atol=1e-15)
    assert list(piv) == [1, 1] and ratio == pytest.approx(abs(1.0 - 1e-3))


def test_pose_conversions_and_checks_match() -> None:
    """Free-flyer conversions, rigid-transform error and limit scans, NumPy vs numba."""
    hexa = hexapod("reference")
    fast, slow = kernel_set(True), kernel_set(False)
    H = hexa.engine.home_h
    for T in box_poses(hexa.home_pose, 50, seed=3):
        a, b = np.empty(7), np.empty(7)
        fast.pose_to_xyzquat(T, H, a)
        slow.pose_to_xyzquat(T, H, b)
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-15)
        Ta, Tb = np.empty((4, 4)), np.empty((4, 4))
        fast.xyzquat_to_pose(a, H, Ta)
        slow.xyzquat_to_pose(a, H, Tb)
        np.testing.assert_allclose(Tb, Ta, rtol=0, atol=1e-15)
        bent = T.copy()
        bent[0, 1] += 1e-3
        for M in (T, bent, np.full((4, 4), np.nan)):
            assert slow.rigid_error(M) == pytest.approx(fast.rigid_error(M), rel=1e-9, abs=1e-15)
    lo, hi = np.zeros(6), np.ones(6)
    for v in ([0.5] * 6, [0.5, 2, 0.5, -1, 0.5, 0.5], [0.5, np.nan, 0.5, 0.5, 0.5, 0.5]):
        v = np.array(v)
        assert slow.first_outside(v, lo, hi, 0.0) == fast.first_outside(v, lo, hi, 0.0)
        idx = np.array([5, 3, 1])
        assert slow.first_outside_at(v, idx, lo[:3], hi[:3], 0.0) == fast.first_outside_at(v, idx, lo[:3], hi[:3], 0.0)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_uncompiled_hexapod_gives_the_same_answers(name: str) -> None:
    """Round trips on seeded box poses: statuses, iterations, flags as the compiled hexapod, poses to 1e-12."""
    fast = hexapod(name)
    slow = hm.Hexapod.from_preset(name, compiled=False)
    assert not slow.compiled and fast.compiled
    for T in box_poses(fast.home_pose, 25, seed=11):
        a, b = fast.inverse(T, check=False), slow.inverse(T, check=False)
        assert (b.status, b.iterations) == (a.status, a.iterations)
        if not a.converged:
            continue
        np.testing.assert_allclose(b.lengths, a.lengths, rtol=0, atol=1e-12)
        fa, fb = fast.forward(a.lengths, check=False), slow.forward(a.lengths, check=False)
        assert (fb.status, fb.iterations, fb.flags, fb.det_sign) == (fa.status, fa.iterations, fa.flags, fa.det_sign)
        np.testing.assert_allclose(fb.pose, T, rtol=0, atol=1e-11)
    batch = slow.forward_batch(np.zeros((3, 6)))
    assert list(batch.status) == ["converged"] * 3


def test_a_short_job_imports_no_numba() -> None:
    """``compiled=False`` solves without importing numba, scipy or llvmlite (the start-up they cost)."""
    code = (
        "import sys, numpy as np\n"
        "import hexapod_model as hm\n"
        "h = hm.Hexapod.from_preset('reference', compiled=False)\n"
        "s = h.forward(h.inverse(h.home_pose).lengths + 0.001)\n"
        "assert s.converged\n"
        "print(sorted(m for m in ('numba', 'llvmlite', 'scipy') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
