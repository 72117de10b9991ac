"""Numba linear algebra of the Newton step: small dense LU and the block-diagonal solve.

* :func:`lu_factor` / :func:`lu_apply`: LU with partial pivoting, reporting the pivot ratio
  (smallest / largest pivot magnitude) that the solver uses to detect singularities.
* :func:`block_solve`: inverse kinematics, where the closure Jacobian is block diagonal (blocks
  read from the reduced Jacobian).

The Schur elimination and the blocks built from the joint Jacobians (the fast path's steps) are
in :mod:`.structured`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


# The factorisation and the solves work in place on the leading n x n block; they are inlined
# into the structured solves below (a call per 6x6 block cost as much as the arithmetic).
@njit(cache=True, inline="always")
def lu_factor_in_place(LU, piv, n):
    """LU factorisation with partial pivoting of ``LU[:n, :n]`` in place; returns the pivot ratio."""
    pmax = 0.0
    pmin = np.inf
    for k in range(n):
        p = k
        best = abs(LU[k, k])
        for i in range(k + 1, n):
            v = abs(LU[i, k])
            if v > best:
                best, p = v, i
        piv[k] = p
        if not best > 0.0:  # zero pivot, or NaN entries
            return 0.0
        if p != k:
            for j in range(n):
                LU[k, j], LU[p, j] = LU[p, j], LU[k, j]
        pmax = max(pmax, best)
        pmin = min(pmin, best)
        inv = 1.0 / LU[k, k]
        for i in range(k + 1, n):
            f = LU[i, k] * inv
            LU[i, k] = f
            if f != 0.0:
                for j in range(k + 1, n):
                    LU[i, j] -= f * LU[k, j]
    return pmin / pmax


@njit(cache=True, inline="always")
def lu_solve_in_place(LU, piv, x, n):
    """``x <- A^-1 x`` with the factors of :func:`lu_factor_in_place` (``P A = L U``)."""
    for k in range(n):
        p = piv[k]
        if p != k:
            x[k], x[p] = x[p], x[k]
    for i in range(n):
        s = x[i]
        for j in range(i):
            s -= LU[i, j] * x[j]
        x[i] = s
    for i in range(n - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * x[j]
        x[i] = s / LU[i, i]


@njit(cache=True, inline="always")
def lu_solve_transposed_in_place(LU, piv, x, n):
    """``x <- A^-T x`` with the factors of :func:`lu_factor_in_place`."""
    for i in range(n):  # U^T y = x
        s = x[i]
        for j in range(i):
            s -= LU[j, i] * x[j]
        x[i] = s / LU[i, i]
    for i in range(n - 1, -1, -1):  # L^T z = y
        s = x[i]
        for j in range(i + 1, n):
            s -= LU[j, i] * x[j]
        x[i] = s
    for k in range(n - 1, -1, -1):  # x = P^T z
        p = piv[k]
        if p != k:
            x[k], x[p] = x[p], x[k]


@njit(cache=True)
def lu_factor(A, LU, piv):
    """LU factorisation with partial pivoting of the square ``A`` into ``LU`` / ``piv``.

    Returns the ratio of the smallest to the largest pivot magnitude: 0 when ``A`` is
    singular (then ``LU`` is unusable), tiny near a singularity.
    """
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            LU[i, j] = A[i, j]
    return lu_factor_in_place(LU, piv, n)


@njit(cache=True)
def lu_apply(LU, piv, b, x):
    """Solve ``A x = b`` with the factors of :func:`lu_factor`."""
    n = LU.shape[0]
    for k in range(n):
        x[k] = b[k]
    lu_solve_in_place(LU, piv, x, n)


@njit(cache=True)
def lu_apply_transposed(LU, piv, b, x):
    """Solve ``A^T x = b`` with the factors of :func:`lu_factor` (``P A = L U``)."""
    n = LU.shape[0]
    for k in range(n):
        x[k] = b[k]
    lu_solve_transposed_in_place(LU, piv, x, n)


@njit(cache=True, inline="always")
def lu_det_sign(LU, piv, n):
    """Sign (+1.0 / -1.0) of ``det A`` from the factors of :func:`lu_factor_in_place` (``n`` x ``n``)."""
    s = 1.0
    for k in range(n):
        if piv[k] != k:
            s = -s
        if LU[k, k] < 0.0:
            s = -s
    return s


@njit(cache=True)
def block_solve(G, r, rows, block_cols, LUb, piv, rb, xb, x):
    """Solve a block-diagonal system by blocks.

    Solve ``G x = r`` when ``G`` is block diagonal: closure ``i``'s rows touch only the
    columns ``block_cols[i]`` (inverse kinematics: the platform is held). Six small LUs
    instead of one large one. Returns the smallest per-block pivot ratio (0 = singular).
    """
    worst = 1.0
    for i in range(block_cols.shape[0]):
        o = i * rows
        for a in range(rows):
            rb[a] = r[o + a]
            for b in range(rows):
                LUb[a, b] = G[o + a, block_cols[i, b]]
        ratio = lu_factor_in_place(LUb, piv, rows)
        if ratio == 0.0:
            return 0.0
        worst = min(worst, ratio)
        for a in range(rows):
            xb[a] = rb[a]
        lu_solve_in_place(LUb, piv, xb, rows)
        for b in range(rows):
            x[block_cols[i, b]] = xb[b]
    return worst
