"""The per-leg Krawczyk test (:mod:`hexapod_model.kinematics.newton.krawczyk_blocks`) against the dense one.

Both are Krawczyk operators ``K(X)`` of the same box with different preconditioners, and each
holds the unique zero of the box when it proves one: so wherever the per-leg test proves a box,
the dense operator on that box must meet it (``K(X) & X`` empty would prove that the box holds no
zero) and meet the per-leg ``K``. On seeded warm steps, small and large, both prove at rates
within a stated margin. The kernels also run as Python (coverage, and the compiled answers).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from hexapod_model.kinematics.newton import krawczyk, krawczyk_blocks, proof_kernel
from hexapod_model.kinematics.newton.proof import StepProver
from hexapod_model.lie import rpy_to_matrix

from ..conftest import limits_only as hexapod

PRESETS = ["reference", "intersecting", "spherical", "3-6", "guideway"]
RATE_MARGIN = 0.05  # the two tests' proven fractions differ by at most this on the same steps


@functools.cache
def _prover(name: str) -> StepProver:
    prover = StepProver.of(hexapod(name).closed_loop)
    assert prover is not None
    prover.regions = False  # each step by a test of its own: the two tests compared on the same boxes
    return prover


def _steps(name: str, seed: int, count: int, size: float):
    """``count`` warm steps ``(q0, q1)`` of preset ``name``: a random pose, then a move of ``size`` m / rad."""
    hexa = hexapod(name)
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        T = hexa.home_pose.copy()
        T[:3, 3] += rng.uniform(-0.03, 0.03, 3)
        T[:3, :3] = T[:3, :3] @ rpy_to_matrix(*np.radians(rng.uniform(-10, 10, 3)))
        step = np.eye(4)
        step[:3, 3] = rng.normal(size=3) * size
        step[:3, :3] = rpy_to_matrix(*(rng.normal(size=3) * size))
        start = hexa.inverse(T, check=False)
        truth = hexa.inverse(T @ step, check=False)
        if start.converged and truth.converged:
            out.append((start.q, hexa.forward(truth.lengths, guess=start, check=False).q))
    return out


def _box(prover: StepProver, q0: np.ndarray, q1: np.ndarray):
    """The whole readings path from ``q0`` to ``q1`` as one box test's inputs (as :func:`.krawczyk.prove_path`)."""
    T0 = prover.platform(q1)
    x0, x1 = prover.unknowns(q0, T0), prover.unknowns(q1, T0)
    l0, l1 = q0[prover.held_q], q1[prover.held_q]
    dl = l1 - l0
    hm, hr = l0 + 0.5 * dl, 0.5 * np.abs(dl) * (1 + 1e-9) + 1e-15
    return T0, 0.5 * (x0 + x1), 0.5 * np.abs(x1 - x0), hm, hr, dl


@pytest.mark.parametrize("name", PRESETS)
def test_a_box_the_structured_test_proves_is_not_refuted_by_the_dense_test(name):
    prover = _prover(name)
    nf, rows = prover.nf, prover.tables[4]
    work_s, work_d = krawczyk.workspace(nf, rows), krawczyk.workspace(nf, rows)
    proven, dense_too = 0, 0
    for q0, q1 in _steps(name, 5, 12, 1e-4) + _steps(name, 6, 6, 3e-3):
        T0, xc, spread, hm, hr, dl = _box(prover, q0, q1)
        off, rad, rho = np.empty(nf), np.empty(nf), np.empty(nf)
        if not krawczyk.prove_box(prover.tables, T0, xc, spread, hm, hr, dl, 0.5, off, rad, rho, True, work_s):
            continue
        proven += 1
        assert np.all(np.abs(off) + rad < rho)
        assert krawczyk.precondition(prover.tables, T0, xc, hm, False, work_d)
        off_d, rad_d = np.empty(nf), np.empty(nf)
        dense_too += krawczyk.try_box(prover.tables, T0, xc, rho, hm, hr, dl, 0.5, False, work_d, off_d, rad_d)
        assert np.all(np.abs(off_d) <= rho + rad_d), "the dense K misses the box: no zero in it"
        assert np.all(np.abs(off_d - off) <= rad_d + rad), "the two K miss each other: no zero in both"
    assert proven >= 12 and dense_too >= proven - 1


@pytest.mark.parametrize("name", PRESETS)
def test_the_structured_and_dense_proofs_prove_seeded_warm_steps_at_rates_within_the_margin(name):
    prover = _prover(name)
    steps = _steps(name, 7, 16, 1e-4) + _steps(name, 8, 16, 5e-3) + _steps(name, 9, 8, 2e-2)
    structured = [prover.prove(q0, q1, structured=True) for q0, q1 in steps]
    dense = [prover.prove(q0, q1, structured=False) for q0, q1 in steps]
    rate_s = np.mean([p.proven for p in structured])
    rate_d = np.mean([p.proven for p in dense])
    assert abs(rate_s - rate_d) <= RATE_MARGIN, (rate_s, rate_d)
    assert rate_s >= 0.5
    for s, d in zip(structured, dense, strict=True):
        if s.proven and d.proven:  # both bound the distance to the same exact pose (about 1e-10 m)
            assert s.position_m < 1e-6 and abs(s.position_m - d.position_m) <= 0.5 * max(s.position_m, d.position_m)


def test_the_block_kernels_run_as_python_give_the_compiled_answers():
    prover = _prover("reference")
    nf, rows = prover.nf, prover.tables[4]
    ((q0, q1),) = _steps("reference", 3, 1, 1e-4)
    T0, xc, spread, hm, hr, dl = _box(prover, q0, q1)
    work = krawczyk.workspace(nf, rows)
    assert krawczyk.precondition(prover.tables, T0, xc, hm, True, work)
    rho = spread * 5 + 1e-6
    off, rad = np.empty(nf), np.empty(nf)
    krawczyk.try_box(prover.tables, T0, xc, rho, hm, hr, dl, 0.5, True, work, off, rad)
    V, Jm, Jr, _, _, blocks, _ = work
    results = []
    for f in (lambda g: g, lambda g: g.py_func):
        ws = krawczyk_blocks.workspace(rows)
        assert f(krawczyk_blocks.setup)(Jm, rows, ws)
        f(krawczyk_blocks.transform)(Jm, rows, ws)
        YFm, YFr, tm, tr = np.empty(nf), np.empty(nf), np.empty(nf), np.empty(nf)
        f(krawczyk.preconditioned_blocks)(ws, rows, V[0], V[1], V[5].copy(), V[6].copy(), 0.5, YFm, YFr, tm, tr)
        o, r = np.empty(nf), np.empty(nf)
        ok = f(krawczyk_blocks.krawczyk_blocks)(YFm, YFr, Jr, rows, ws, rho, o, r)
        results.append((ok, o, r, ws[3], ws[4]))
    (ok_c, o_c, r_c, M_c, R_c), (ok_p, o_p, r_p, M_p, R_p) = results
    assert ok_c == ok_p
    for c, p in ((o_c, o_p), (r_c, r_p), (M_c, M_p), (R_c, R_p)):
        np.testing.assert_allclose(p, c, rtol=1e-9, atol=1e-18)
    T, Tp = np.empty((4, 4)), np.empty((4, 4))
    proof_kernel.platform_placement(prover.home, q1, prover.platform_q, T)
    proof_kernel.platform_placement.py_func(prover.home, q1, prover.platform_q, Tp)
    np.testing.assert_allclose(Tp, T, atol=1e-15)
    x, xp = np.empty(nf), np.empty(nf)
    proof_kernel.unknowns_into(q1, T0, np.empty((4, 4)), prover.home, prover.platform_q, prover.leg_q, prover.free, x)
    args = (prover.home, prover.platform_q, prover.leg_q, prover.free, xp)
    proof_kernel.unknowns_into.py_func(q1, T0, np.empty((4, 4)), *args)
    np.testing.assert_allclose(xp, x, atol=1e-14)
    work_p, ends = prover.work()
    res = proof_kernel.prove_configurations.py_func(
        prover.tables,
        prover.home,
        prover.platform_q,
        prover.leg_q,
        prover.free,
        prover.held_q,
        q0,
        q1,
        True,
        True,
        work_p,
        ends,
    )
    assert res[0] and prover.prove(q0, q1).proven


def test_the_proof_of_a_configuration_with_a_nan_is_not_run():
    prover = _prover("3-6")
    q = hexapod("3-6").q_home.copy()
    bad = q.copy()
    bad[prover.held_q[0]] = np.nan
    proof = prover.prove(q, bad)
    assert not proof.proven and proof.tests == 0


def _exact_magnitudes(ws, rows: int, v: np.ndarray) -> list:
    """``|Y| v`` in exact rational arithmetic, ``Y = Y2 L`` formed entry by entry from the block workspace."""
    from fractions import Fraction

    L, W, Z = ws[0], ws[1], ws[2]
    m, nf = rows - 1, 6 * rows
    F = [Fraction(float(x)) for x in v]
    out = []
    for i in range(6):  # the legs' own rows: L_i (own columns) - W[i, :, j] n_j
        for a in range(m):
            s = Fraction(0)
            for j in range(6):
                for k in range(rows):
                    y = -Fraction(float(W[i, a, j])) * Fraction(float(L[j, m, k]))
                    if i == j:
                        y += Fraction(float(L[i, a, k]))
                    s += abs(y) * F[j * rows + k]
            out.append(s)
    for p in range(6):  # the platform's rows: Z n
        s = sum(
            abs(Fraction(float(Z[p, j])) * Fraction(float(L[j, m, k]))) * F[j * rows + k]
            for j in range(6)
            for k in range(rows)
        )
        out.append(s)
    assert len(out) == nf
    return out


@pytest.mark.parametrize("name", ["reference", "3-6"])
def test_the_factored_magnitudes_of_the_preconditioner_bound_the_exact_ones(name):
    """``_magnitudes`` (|Y| v through one sum per leg) is at least the exact |Y2 L| v, and hardly more."""
    from fractions import Fraction

    prover = _prover(name)
    nf, rows = prover.nf, prover.tables[4]
    ((q0, q1),) = _steps(name, 11, 1, 1e-4)
    T0, xc, spread, hm, hr, dl = _box(prover, q0, q1)
    work = krawczyk.workspace(nf, rows)
    assert krawczyk.precondition(prover.tables, T0, xc, hm, True, work)
    ws = work[5]
    rng = np.random.default_rng(3)
    for v in (np.ones(nf), rng.uniform(0.0, 1.0, nf), rng.uniform(0.0, 1e-9, nf) * (rng.uniform(size=nf) < 0.3)):
        w, wp = np.empty(nf), np.empty(nf)
        krawczyk_blocks._magnitudes(ws, rows, v, w)
        krawczyk_blocks._magnitudes.py_func(ws, rows, v, wp)  # run as Python: the same bounds
        np.testing.assert_allclose(wp, w, rtol=1e-12, atol=0.0)
        for bound, exact in zip(w, _exact_magnitudes(ws, rows, v), strict=True):
            assert Fraction(float(bound)) >= exact
            assert float(bound) <= float(exact) * (1 + 1e-9) + 1e-290


def test_the_preconditioner_blocks_are_inverted_and_a_singular_block_is_refused():
    rng = np.random.default_rng(4)
    LU, out = np.empty((6, 6)), np.empty((6, 6))
    for invert in (krawczyk_blocks._invert, krawczyk_blocks._invert.py_func):  # compiled, then as Python
        for n in (3, 6):
            A = rng.normal(size=(6, 6))
            assert invert(A, n, LU, out)
            np.testing.assert_allclose(out[:n, :n] @ A[:n, :n], np.eye(n), atol=1e-12)
        singular = rng.normal(size=(6, 6))
        singular[:, 2] = 0.0
        assert not invert(singular, 6, LU, out)
        singular[:, 2] = np.nan
        assert not invert(singular, 6, LU, out)


def _leaves(nested) -> list:
    """The arrays of a nested tuple, depth first."""
    return [leaf for item in nested for leaf in (_leaves(item) if isinstance(item, tuple) else [item])]


def test_the_packed_work_arrays_are_the_ones_the_kernels_unpack():
    """``StepProver``'s arrays and ``proof_kernel.unpack`` of its two buffers: the same memory, the same shapes."""
    prover = StepProver.of(hexapod("reference").closed_loop)  # its arrays are written below
    assert prover is not None
    (work, ends), (floats, ints, spec) = prover.work(), prover.buffers()
    unpacked_work, unpacked_ends, model = proof_kernel.unpack(floats, ints, spec)
    as_python = proof_kernel.unpack.py_func(floats, ints, spec)  # the same views, made by NumPy
    for a, b in zip(_leaves(as_python), _leaves((unpacked_work, unpacked_ends, model)), strict=True):
        assert a.shape == b.shape and np.shares_memory(a, b)
    leaves = [*work[:5], *work[5], *work[6], *ends]
    unpacked = [*unpacked_work[:5], *unpacked_work[5], *unpacked_work[6], *unpacked_ends]
    assert len(leaves) == len(unpacked) == 35
    for k, (a, b) in enumerate(zip(leaves, unpacked, strict=True)):
        assert a.shape == b.shape and a.dtype == b.dtype, k
        assert np.shares_memory(a, floats) and np.shares_memory(b, floats), k
        a.flat[0] = k + 0.5  # a write through one is read through the other
        assert b.flat[0] == k + 0.5, k
    placements, motions, closure, held, _ = prover.tables
    for a, b in zip(
        (placements, motions, closure, held, prover.home, prover.leg_q, prover.free, prover.held_q), model, strict=True
    ):
        np.testing.assert_array_equal(b, a)
        assert b.dtype == a.dtype
    with pytest.raises(ValueError, match="layout"):
        proof_kernel.pack((np.zeros(3),))


@pytest.mark.parametrize("name", ["reference", "3-6"])
def test_the_packed_entry_proves_what_the_unpacked_one_proves(name):
    """``prove_packed`` against ``prove_configurations`` run as Python on the arrays it unpacks.

    (Run as Python: compiled, the unpacked entry would compile the whole proof once more.)
    """
    prover = _prover(name)
    for q0, q1 in _steps(name, 12, 4, 1e-4) + _steps(name, 13, 2, 2e-2):
        packed = prover.prove(q0, q1)
        work, ends = prover.work()
        p = proof_kernel.prove_configurations.py_func(
            prover.tables, prover.home, prover.platform_q, prover.leg_q, prover.free, prover.held_q,
            q0, q1, True, True, work, ends,
        )  # fmt: skip
        assert (packed.proven, packed.tests, packed.subdivisions) == (bool(p[0]), p[1], p[4])
        if packed.proven:  # the same test: bounds of about 1e-10 m, equal to 1e-18 m
            assert abs(packed.position_m - p[2]) <= 1e-18 and abs(packed.rotation_rad - p[3]) <= 1e-17


def test_a_strided_configuration_is_proven_by_the_one_compiled_signature():
    """A strided start (a column of a 2-D array) compiles no second proof: a minute and more, unannounced."""
    prover = _prover("reference")
    ((q0, q1),) = _steps("reference", 14, 1, 1e-4)
    want = prover.prove(q0, q1)
    kernel = proof_kernel.prove_packed
    before = len(kernel.signatures)
    columns = np.stack([q0, q1], axis=1)  # (nq, 2): each column a strided view
    assert not columns[:, 0].flags.c_contiguous
    got = prover.prove(columns[:, 0], columns[:, 1])
    assert len(kernel.signatures) == before
    assert got == want
