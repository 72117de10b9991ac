"""The Krawczyk test on the block-arrow structure of the closure Jacobian (per-leg Schur form).

The closure Jacobian ``J`` of :mod:`.enclosure` has, in each leg's ``r`` rows (6, or 3 for point
closures), nonzero entries only in that leg's ``m = r - 1`` free joints and the platform's six
chart coordinates: ``J = [diag(A_i) | B]``, ``A_i`` (r x m), ``B_i`` (r x 6), a block-arrow
matrix (every other entry is an exact zero: a leg's closure does not depend on another leg's
joints). The dense test (:mod:`.krawczyk_dense`) multiplies 36 x 36 interval matrices.

**The preconditioner.** Krawczyk's operator

    K(X) = xc - Y F(xc) + (I - Y J(X)) (X - xc)

proves a unique zero in ``X`` when ``K(X)`` lies in the interior of ``X``, for **any** real
matrix ``Y`` (Krawczyk 1969; Neumaier, *Interval methods for systems of equations*, 1990,
thm. 5.1.8: the inclusion itself implies that ``Y`` and every matrix of ``J(X)`` are regular);
``Y`` only decides how often the test succeeds. Here ``Y = Y2 L`` is the exact product of two
point matrices built once per test from the Jacobian's midpoint at ``xc``:

* ``L = diag(L_i)``, ``L_i`` (r x r) the inverse of the leg's full joint Jacobian
  ``[A_i | a_i]`` (its free joints and its held prismatic joint ``a_i``): ``L_i A_i ~ [I; 0]``,
  its last row ``n_i`` a left null vector of ``A_i``, and ``S = [n_i B_i]`` (6 x 6) the
  platform's Jacobian of the held joints (the Schur complement of the legs' blocks);
* ``Y2 = [[I, -W], [0, Z]]`` (the legs' first m rows, then the six ``n_i`` rows), ``Z ~ S^-1``
  (6 x 6) and ``W = G Z`` rounded, ``G`` the midpoints of ``L_i B_i``'s first m rows: block
  elimination of the platform's unknowns, so that ``Y ~ J(xc)^-1`` as the dense test's.

**The bound.** Every real matrix ``A`` of the interval matrix ``J(X) = mid(J) +- rad(J)`` has

    |I - Y A| <= |I - Y mid(J)| + |Y| rad(J),   Y mid(J) = Y2 M,  M = L mid(J) in Mm +- Mr,
    |I - Y2 Mm| = |[[-E11 + W E21, -(G - W S)], [-Z E21, I - Z S]]|,

with ``M`` computed leg by leg (``r x (m + 6)`` per leg; ``Mr`` its rounding, its own rows'
platform columns re-centred on ``G``), ``E11`` its own block minus ``I``, ``E21`` its ``n_i``
rows' own columns, ``S`` their platform columns: all small. :func:`krawczyk_blocks` evaluates
``|I - Y J(X)| rho <= |I - Y2 Mm| rho + |Y2| Mr rho + |Y| (rad(J) rho)`` with non-negative
products of the 6 legs' blocks and 6 x 6 matrices, ``rad(J) rho`` by the block-arrow pattern and
``|Y|`` (a bound of each entry of the exact ``Y2 L``, formed once per test in O(nf^2)): the
radius term is as tight as the dense test's ``|Y| rad(J)``. ``Y F(xc)`` goes through ``L`` and
``Y2`` in midpoint-radius arithmetic (:func:`apply`). Every sum is raised by the rounding
allowance of :mod:`.intervals`. The cost is a few small blocks and O(nf^2) products instead of
36 x 36 matrix products and a dense inverse (Rump, "Verification methods: rigorous results
using floating-point arithmetic", Acta Numerica 19, 2010, sec. 10, on preconditioning with any
approximate inverse). Work arrays come from :func:`workspace`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .intervals import REL, UP, up
from .linalg import lu_factor_in_place, lu_solve_in_place


def workspace(rows: int) -> tuple:
    """The work arrays of the structured test for legs of ``rows`` closure rows (6 or 3)."""
    m, nf = rows - 1, 6 * rows
    return (
        np.zeros((6, rows, rows)),  # L: the legs' left factors
        np.zeros((6, m, 6)),  # W = G Z (rounded: Y2 is whatever matrix it holds)
        np.zeros((6, 6)),  # Z ~ S^-1
        np.zeros((6, rows, m + 6)),  # Mm: L mid(J) (own columns, then the platform's)
        np.zeros((6, rows, m + 6)),  # Mr: its rounding (and re-centring)
        np.zeros((6, 6)),  # LU scratch
        np.zeros(6, dtype=np.int64),  # pivots
        np.zeros(6),  # a column
        np.zeros((6, 6)),  # R: |I - Z S| bound
        np.zeros((6, rows)),  # u: L v
        np.zeros((6, rows)),  # its rounding
        np.zeros(6),  # six-vectors, then an nf-vector
        np.zeros(6),
        np.zeros(nf),
        np.zeros((6, m, 6)),  # G: midpoints of L_i B_i's own rows
        np.zeros((nf, nf)),  # |Y|: a bound of Y2 L's magnitudes
        np.zeros((6, m, 6)),  # D: |G - W S| bound
    )


@njit(cache=True)
def _invert(A, n, LU, piv, col, out):
    """``out[:n, :n] = A[:n, :n]^-1`` (pivoted LU of :mod:`.linalg`); False when singular."""
    LU[:n, :n] = A[:n, :n]
    if not lu_factor_in_place(LU, piv, n) > 0.0:
        return False
    for a in range(n):
        col[:n] = 0.0
        col[a] = 1.0
        lu_solve_in_place(LU, piv, col, n)
        for b in range(n):
            out[b, a] = col[b]
    for a in range(n):
        for b in range(n):
            if not np.isfinite(out[a, b]):
                return False
    return True


@njit(cache=True)
def setup(Jm, rows, ws):
    """The preconditioner ``Y = Y2 L`` from the Jacobian's midpoints ``Jm`` (nf x nf + 6); False when singular.

    Also ``|Y|``: an upper bound of the magnitude of each entry of the exact product ``Y2 L``.
    """
    L, W, Z, _, _, LU, piv, col, R, _, _, _, _, _, G, aY, _ = ws
    m = rows - 1
    nf = Jm.shape[0]
    nl = 6 * m
    A = R  # scratch
    for i in range(6):
        o, c = i * rows, i * m
        for a in range(rows):
            for b in range(m):
                A[a, b] = Jm[o + a, c + b]
            A[a, m] = Jm[o + a, nf + i]  # the held joint's column
        if not _invert(A, rows, LU, piv, col, L[i]):
            return False
    S = R  # scratch: Z's inverse
    for i in range(6):
        o = i * rows
        for b in range(6):
            for a in range(rows):
                s = 0.0
                for k in range(rows):
                    s += L[i, a, k] * Jm[o + k, nl + b]
                if a < m:
                    G[i, a, b] = s
                else:
                    S[i, b] = s
    if not _invert(S, 6, LU, piv, col, Z):
        return False
    for i in range(6):
        for a in range(m):
            for j in range(6):
                s = 0.0
                for k in range(6):
                    s += G[i, a, k] * Z[k, j]
                W[i, a, j] = s
    for j in range(6):  # Y's columns of leg j's rows: own rows L_j - W L_n, platform rows Z L_n
        for k in range(rows):
            y = j * rows + k
            n = L[j, m, k]
            for i in range(6):
                for a in range(m):
                    t = W[i, a, j] * n
                    d = L[j, a, k] if i == j else 0.0
                    aY[i * m + a, y] = up(abs(d - t) + REL * (abs(d) + abs(t)))
            for p in range(6):
                aY[nl + p, y] = up(abs(Z[p, j] * n) * UP)
    return True


@njit(cache=True)
def transform(Jm, rows, ws):
    """``L mid(J)`` leg by leg with its rounding (own rows' platform columns centred on ``G``), and ``R``, ``D``."""
    L, W, Z, Mm, Mr, _, _, _, R, _, _, _, _, _, G, _, D = ws
    m = rows - 1
    nl = 6 * m
    for i in range(6):
        o, c = i * rows, i * m
        for a in range(rows):
            for b in range(m + 6):
                j = c + b if b < m else nl + b - m
                t, s = 0.0, 0.0
                for k in range(rows):
                    p = L[i, a, k] * Jm[o + k, j]
                    t += p
                    s += abs(p)
                r = up(REL * s)
                if a < m and b >= m:  # re-centred on G (exact: the midpoint moved, the radius grew)
                    g = G[i, a, b - m]
                    r = up(r + abs(t - g) + REL * (abs(t) + abs(g)))
                    t = g
                Mm[i, a, b], Mr[i, a, b] = t, r
    for a in range(6):  # R = |I - Z S|, S = the n rows' platform columns
        for b in range(6):
            t, s = 1.0 if a == b else 0.0, 0.0
            for k in range(6):
                q = Z[a, k] * Mm[k, m, m + b]
                t -= q
                s += abs(q)
            R[a, b] = up(abs(t) + REL * (s + 1.0))
    for i in range(6):  # D = |G - W S|
        for a in range(m):
            for b in range(6):
                t, s = G[i, a, b], abs(G[i, a, b])
                for k in range(6):
                    q = W[i, a, k] * Mm[k, m, m + b]
                    t -= q
                    s += abs(q)
                D[i, a, b] = up(abs(t) + REL * s)


@njit(cache=True)
def _magnitudes(aY, v, w):
    """``w = |Y| v`` (upper bound; ``v >= 0``)."""
    n = v.shape[0]
    for a in range(n):
        s = 0.0
        for b in range(n):
            s += aY[a, b] * v[b]
        w[a] = up(s)


@njit(cache=True)
def apply(ws, rows, vm, vr, wm, wr):
    """``wm +- wr`` (nf,) encloses ``Y v`` for every ``v`` in ``vm +- vr`` (nf,)."""
    L, W, Z, _, _, _, _, _, _, um, ur, _, _, _, _, aY, _ = ws
    m = rows - 1
    nl = 6 * m
    _magnitudes(aY, vr, wr)
    for i in range(6):  # u = L vm, with its rounding
        o = i * rows
        for a in range(rows):
            t, s = 0.0, 0.0
            for k in range(rows):
                p = L[i, a, k] * vm[o + k]
                t += p
                s += abs(p)
            um[i, a], ur[i, a] = t, up(REL * s)
    for a in range(6):  # the platform's rows: Z u_n
        t, s, r = 0.0, 0.0, 0.0
        for j in range(6):
            p = Z[a, j] * um[j, m]
            t += p
            s += abs(p)
            r += abs(Z[a, j]) * ur[j, m]
        wm[nl + a] = t
        wr[nl + a] = up(wr[nl + a] + up(r + REL * s))
    for i in range(6):  # the legs' own rows: u_own - W u_n
        for a in range(m):
            t, s, r = um[i, a], abs(um[i, a]), ur[i, a]
            for j in range(6):
                p = W[i, a, j] * um[j, m]
                t -= p
                s += abs(p)
                r += abs(W[i, a, j]) * ur[j, m]
            x = i * m + a
            wm[x] = t
            wr[x] = up(wr[x] + up(r + REL * s))


@njit(cache=True)
def krawczyk_blocks(YFm, YFr, Jr, rows, ws, rho, off, rad):
    """One Krawczyk test of the box ``xc +- rho`` (``Jr``: the Jacobian's radii over it; see the module doc).

    Needs :func:`transform` of the Jacobian's midpoint. Writes ``K = xc + off +- rad`` and
    returns True when ``K`` lies in the interior of the box.
    """
    _, W, Z, Mm, Mr, _, _, _, R, _, _, u, zu, t, _, aY, D = ws
    m = rows - 1
    nl = 6 * m
    for i in range(6):  # t = rad(J) rho (the block-arrow pattern), then |Y| t into rad
        o, c = i * rows, i * m
        for a in range(rows):
            s = 0.0
            for b in range(m):
                s += Jr[o + a, c + b] * rho[c + b]
            for b in range(6):
                s += Jr[o + a, nl + b] * rho[nl + b]
            t[o + a] = up(s)
    _magnitudes(aY, t, rad)
    for j in range(6):  # u = |E21| rho_own + the n rows' rounding times rho
        s = 0.0
        for b in range(m):
            s += (abs(Mm[j, m, b]) + Mr[j, m, b]) * rho[j * m + b]
        for b in range(6):
            s += Mr[j, m, m + b] * rho[nl + b]
        u[j] = up(s)
    ok = True
    for a in range(6):  # the platform's rows: |Z| u + |R| rho_p
        s = 0.0
        for j in range(6):
            s += abs(Z[a, j]) * u[j] + R[a, j] * rho[nl + j]
        zu[a] = up(s)
        x = nl + a
        off[x] = -YFm[x]
        rad[x] = up(up(rad[x] + zu[a]) + YFr[x])
        if not up(abs(off[x]) + rad[x]) < rho[x]:
            ok = False
    for i in range(6):  # the legs' own rows: |E11| rho_own + rounding rho + |W| u + |D| rho_p
        for a in range(m):
            s = 0.0
            for b in range(m):
                e = Mm[i, a, b]
                e = up(abs(e - 1.0) + REL * (abs(e) + 1.0)) if a == b else abs(e)
                s += (e + Mr[i, a, b]) * rho[i * m + b]
            for b in range(6):
                s += Mr[i, a, m + b] * rho[nl + b] + abs(W[i, a, b]) * u[b] + D[i, a, b] * rho[nl + b]
            x = i * m + a
            off[x] = -YFm[x]
            rad[x] = up(up(rad[x] + up(s)) + YFr[x])
            if not up(abs(off[x]) + rad[x]) < rho[x]:
                ok = False
    return ok
