"""The Newton solver's kernels in NumPy: the same functions as :mod:`.kernels` and :mod:`.linalg`, uncompiled.

A :class:`~hexapod_model.kinematics.hexapod.Hexapod` built with ``compiled=False`` solves with
these instead of the numba kernels, so a short job (``hexapod fk`` on a few hundred rows) neither
imports numba nor waits for its compilation; results agree with the compiled kernels to rounding
(same equations, same pivoting, same pivot ratios, signs and condition bounds: see the docstrings
of :mod:`.kernels` and :func:`.structured.schur_solve`, which these mirror). Arrays are the same
buffers, filled in place; each function loops in Python only over the six legs or the rows of a
small factorisation, vectorised over the legs where it can.
"""

from __future__ import annotations

import numpy as np


def closure_residual(R, p, rows, E, r, length):
    """Fill ``r``, ``E`` from the closure frames ``R``, ``p``; ``(norm, min trace(E))`` as the compiled kernel."""
    r6 = r.reshape(6, rows)
    r6[:, :3] = p[:6] - p[6:]
    min_trace = 3.0
    if rows == 6:
        np.matmul(R[:6], R[6:].transpose(0, 2, 1), out=E)  # E_i = R_tip R_anchor^T
        r6[:, 3] = 0.5 * (E[:, 2, 1] - E[:, 1, 2])
        r6[:, 4] = 0.5 * (E[:, 0, 2] - E[:, 2, 0])
        r6[:, 5] = 0.5 * (E[:, 1, 0] - E[:, 0, 1])
        min_trace = min(3.0, float(np.min(np.trace(E, axis1=1, axis2=2))))
    return _norm(r, rows, length), min_trace


def _norm(r, rows, length):
    """``norm(r)``, the rotation rows (rad) times ``length``, as :func:`.kernels.closure_residual`."""
    if rows == 6 and length != 1.0:
        r = r.reshape(6, rows) * np.array([1.0, 1.0, 1.0, length, length, length])
    return float(np.sqrt(np.sum(r * r)))


def _weights(E):
    """``H_tip = (tr(E) I - E)/2`` and ``H_anchor = (tr(E) I - E^T)/2`` of every closure, (6, 3, 3) each."""
    half = 0.5 * np.trace(E, axis1=1, axis2=2)[:, None, None] * np.eye(3)
    return half - 0.5 * E, half - 0.5 * E.transpose(0, 2, 1)


def _columns(J, cols, rows, points, H):
    """The residual's derivative along velocities ``cols`` (6, n) of each closure: (6, rows, n).

    Closure ``i``'s column for velocity ``c``: the linear velocity of ``points[i]``,
    ``v_o - points[i] x w``, over ``H[i] w`` (:func:`.kernels.jacobian`); ``cols`` must be valid indices.
    """
    v, w = J[0:3, cols], J[3:6, cols]  # (3, 6, n)
    px, py, pz = (points[:, a, None] for a in range(3))
    out = np.empty((cols.shape[0], rows, cols.shape[1]))
    out[:, 0] = v[0] - (py * w[2] - pz * w[1])
    out[:, 1] = v[1] - (pz * w[0] - px * w[2])
    out[:, 2] = v[2] - (px * w[1] - py * w[0])
    if rows == 6:
        out[:, 3:] = np.einsum("iab,bin->ian", H, w)
    return out


def jacobian(J, leg_cols, ff_cols, colmap, rows, p, E, G):
    """Fill ``G`` (6*rows x n_free): derivative of the residual w.r.t. the free velocities."""
    G[:, :] = 0.0
    Ht, Ha = _weights(E) if rows == 6 else (None, None)
    row = np.arange(6)[:, None, None] * rows + np.arange(rows)[None, :, None]
    for cols, points, H, sign in ((leg_cols, p[:6], Ht, 1.0), (np.broadcast_to(ff_cols, (6, 6)), p[6:], Ha, -1.0)):
        target = np.where(cols >= 0, colmap[np.maximum(cols, 0)], -1)  # -1: padding or a held joint
        values = _columns(J, np.maximum(cols, 0), rows, points, H)
        keep = np.broadcast_to(target[:, None, :] >= 0, values.shape)
        G[np.broadcast_to(row, values.shape)[keep], np.broadcast_to(target[:, None, :], values.shape)[keep]] += (
            sign * values[keep]
        )


def scatter_step(x, free_v, dv, max_step, weights):
    """``dv[free_v] = -x``, shortened so that no ``weights * |x|`` exceeds ``max_step``; returns its largest."""
    biggest = float(np.max(np.abs(x) * weights)) if x.size else 0.0
    scale = 1.0 if biggest <= max_step else max_step / biggest
    dv[free_v] = -scale * x
    return biggest


def shift_residual(r, offset, scale, rows, length):
    """``r -= scale * offset`` (a homotopy from a start that does not close); returns its norm as :func:`_norm`."""
    r -= scale * offset
    return _norm(r, rows, length)


def _factor(LU, piv):
    """LU with partial pivoting of each matrix of ``LU`` (m, n, n) in place (:func:`.linalg.lu_factor_in_place`).

    Returns the smallest ratio of smallest to largest pivot magnitude over the ``m`` matrices
    (0 when one of them is singular, then the factors are unusable).
    """
    m, n = LU.shape[0], LU.shape[1]
    at = np.arange(m)
    pmax, pmin = np.zeros(m), np.full(m, np.inf)
    for k in range(n):
        col = np.abs(LU[:, k:, k])
        pk = col.argmax(axis=1)  # the first largest, as the compiled loop
        best = col[at, pk]
        pk += k
        piv[:, k] = pk
        if not (best > 0.0).all():  # zero pivot, or NaN entries
            return 0.0
        swap = pk != k
        if swap.any():
            w, pw = at[swap], pk[swap]
            row = LU[w, k].copy()
            LU[w, k] = LU[w, pw]
            LU[w, pw] = row
        np.maximum(pmax, best, out=pmax)
        np.minimum(pmin, best, out=pmin)
        f = LU[:, k + 1 :, k] / LU[:, k, k, None]
        LU[:, k + 1 :, k] = f
        LU[:, k + 1 :, k + 1 :] -= f[:, :, None] * LU[:, k, None, k + 1 :]
    return float((pmin / pmax).min())


def _solve(LU, piv, x):
    """``x[j] <- A_j^-1 x[j]`` for the factors of :func:`_factor` (``P A = L U``); ``x`` is (m, n)."""
    at, n = np.arange(x.shape[0]), x.shape[1]
    for k in range(n):
        pk = piv[:, k]
        xk = x[at, k].copy()
        x[at, k] = x[at, pk]
        x[at, pk] = xk
    for i in range(n):
        x[:, i] -= np.einsum("mj,mj->m", LU[:, i, :i], x[:, :i])
    for i in range(n - 1, -1, -1):
        x[:, i] = (x[:, i] - np.einsum("mj,mj->m", LU[:, i, i + 1 :], x[:, i + 1 :])) / LU[:, i, i]


def _det_signs(LU, piv):
    """Sign of each ``det A_j`` from the factors of :func:`_factor`."""
    n = LU.shape[1]
    swaps = np.sum(piv != np.arange(n), axis=1) + np.sum(np.diagonal(LU, axis1=1, axis2=2) < 0.0, axis=1)
    return np.where(swaps % 2 == 0, 1.0, -1.0)


def lu_factor(A, LU, piv):
    """LU factorisation with partial pivoting of the square ``A`` into ``LU`` / ``piv``; the pivot ratio."""
    LU[:, :] = A
    return _factor(LU[None], piv[None])


def lu_apply(LU, piv, b, x):
    """Solve ``A x = b`` with the factors of :func:`lu_factor`."""
    x[:] = b
    _solve(LU[None], piv[None], x[None])


def block_solve(G, r, rows, block_cols, LUb, piv, rb, xb, x):
    """Solve the block-diagonal ``G x = r`` by blocks (:func:`.linalg.block_solve`); the smallest pivot ratio."""
    legs = np.arange(block_cols.shape[0])[:, None, None] * rows
    blocks = G[legs + np.arange(rows)[None, :, None], block_cols[:, None, :]]
    ratio = _factor(blocks.copy(), np.zeros((block_cols.shape[0], rows), dtype=np.int64))
    if ratio == 0.0:
        return 0.0
    x[block_cols] = np.linalg.solve(blocks, r.reshape(-1, rows)[: block_cols.shape[0], :, None])[..., 0]
    return min(1.0, ratio)


def schur_solve(J, leg_cols, held_pos, ff_cols, colmap, rows, p, E, r, x, LB, PB, A, M, pm, n, w, length):
    """Newton step with each leg eliminated (:func:`.structured.schur_solve`): ``(signed ratio, kappa)``.

    The pivot ratios, determinant signs and condition bound come from the same pivoted
    factorisations as the compiled kernel; the solves are LAPACK's (``numpy.linalg.solve``).
    """
    Ht, Ha = _weights(E) if rows == 6 else (None, None)
    L = _columns(J, leg_cols[:, :rows], rows, p[:6], Ht)  # L_i: the leg's joints
    A[:] = -_columns(J, np.broadcast_to(ff_cols, (6, 6)), rows, p[6:], Ha)  # A_i: the platform's velocity
    LB[:] = L
    worst = _factor(LB, PB)
    if worst == 0.0:
        return 0.0, np.inf
    sign = float(np.prod(_det_signs(LB, PB)))
    e_held = np.zeros((6, rows, 1))
    e_held[np.arange(6), held_pos, 0] = 1.0
    N = np.linalg.solve(L.transpose(0, 2, 1), e_held)[..., 0]  # L_i^T n_i = e_held
    r6 = r.reshape(6, rows)
    rhs = -np.einsum("ia,ia->i", N, r6)
    M0 = np.einsum("ia,iak->ik", N, A)
    M[:, :] = M0
    ratio = _factor(M[None], pm[None])
    if ratio == 0.0:
        return 0.0, np.inf
    worst = min(worst, ratio)
    sign *= float(_det_signs(M[None], pm[None])[0])
    Mw = M0 if length == 1.0 else M0 / np.array([1.0, 1.0, 1.0, length, length, length])  # scale-free
    kappa = 2.0 * (float(np.sum(Mw * Mw)) / 6.0) ** 3 / abs(float(np.prod(np.diagonal(M)))) * length**3
    v = np.linalg.solve(M0, rhs)
    x[colmap[ff_cols]] = -v
    W = np.linalg.solve(L, -(r6 + A @ v)[..., None])[..., 0]
    cols = colmap[leg_cols[:, :rows]]
    free = cols >= 0
    x[cols[free]] = -W[free]
    return sign * worst, kappa


def first_outside(values, lower, upper, slack):
    """Index of the first entry that is NaN/inf or outside ``[lower - slack, upper + slack]``; -1 if none."""
    bad = np.flatnonzero(~((lower - slack <= values) & (values <= upper + slack)))
    return int(bad[0]) if bad.size else -1


def first_outside_at(q, idx, lower, upper, slack):
    """Like :func:`first_outside` on ``q[idx]``; returns the position in ``idx`` or -1."""
    return first_outside(q[idx], lower, upper, slack)


def rigid_error(T):
    """Distance of a 4x4 matrix from a rigid transform (:func:`.kernels.rigid_error`; ``inf`` for NaN/inf)."""
    if not np.all(np.isfinite(T)):
        return np.inf
    Rm = T[:3, :3]
    err = float(np.max(np.abs(Rm.T @ Rm - np.eye(3))))
    err = max(err, abs(float(np.linalg.det(Rm)) - 1.0))
    return max(err, float(np.max(np.abs(T[3] - (0.0, 0.0, 0.0, 1.0)))))


def copied(a):
    """A copy of ``a`` (the compiled kernel's twin, which keeps the GIL; here numpy's copy)."""
    return a.copy()
