"""The Krawczyk test on the block-arrow structure of the closure Jacobian (per-leg Schur form).

The closure Jacobian ``J`` of :mod:`.enclosure` has, in each leg's ``r`` rows (6, or 3 for point
closures), nonzero entries only in that leg's ``m = r - 1`` free joints and the six chart
coordinates of the platform: ``J = [diag(A_i) | B]``, ``A_i`` (r x m), ``B_i`` (r x 6), a
block-arrow matrix (every other entry is an exact zero of the enclosure: a leg's closure does
not depend on another leg's joints). The dense test of :mod:`.krawczyk` multiplies 36 x 36
interval matrices; this one works leg by leg.

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
* ``Y2 = [[I, -G Z], [0, Z]]`` (the legs' first m rows, then the six ``n_i`` rows), ``G`` the
  midpoints of ``L_i B_i``'s first m rows and ``Z ~ S^-1`` (6 x 6): block elimination of the
  platform unknowns, so that ``Y ~ J(xc)^-1`` as the dense test's.

**The bound.** With ``M = L J(X)`` enclosed leg by leg (``r x (m + 6)`` intervals per leg,
re-centred so that its (own rows, platform columns) midpoints are exactly ``G``), every real
matrix ``A`` of the interval matrix ``J(X)`` has ``L A`` in ``M`` and

    |I - Y A| <= |I - Y2 mid(M)| + |Y2| rad(M),
    I - Y2 mid(M) = [[-E11 + G Z E21, -G R], [-Z E21, R]],   R = I - Z mid(S),

``E11 = mid(M)``'s own block minus ``I``, ``E21`` its ``n_i`` rows' own columns: all small.
:func:`krawczyk_blocks` evaluates ``|I - Y J(X)| rho`` from these as products of non-negative
matrices and vectors (6 legs' r x (m + 6) blocks and 6 x 6 ones), every sum raised by the
rounding allowance of :mod:`.intervals`, and ``Y F(xc)`` through ``L`` and ``Y2`` in
midpoint-radius arithmetic (:func:`apply`): the same enclosures as the dense test's, so the same
proof, at the cost of a few small blocks instead of 36 x 36 products (Rump, "Verification
methods: rigorous results using floating-point arithmetic", Acta Numerica 19, 2010, sec. 10,
on preconditioning with any approximate inverse). Work arrays come from :func:`workspace`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .intervals import REL, up
from .linalg import lu_factor_in_place, lu_solve_in_place


def workspace(rows: int) -> tuple:
    """The work arrays of the structured test for legs of ``rows`` closure rows (6 or 3)."""
    m = rows - 1
    return (
        np.zeros((6, rows, rows)),  # L: the legs' left factors
        np.zeros((6, m, 6)),  # G: midpoints of L_i B_i's own rows
        np.zeros((6, 6)),  # Z ~ S^-1
        np.zeros((6, rows, m + 6)),  # Mm: L J(X), midpoints (own columns, then the platform's)
        np.zeros((6, rows, m + 6)),  # Mr: its radii
        np.zeros((6, 6)),  # LU scratch
        np.zeros(6, dtype=np.int64),  # pivots
        np.zeros(6),  # a column
        np.zeros((6, 6)),  # R: |I - Z S| bound
        np.zeros((6, rows)),  # u: midpoints of L v
        np.zeros((6, rows)),  # its radii
        np.zeros(6),  # six-vectors
        np.zeros(6),
        np.zeros(6),
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
    """The preconditioner ``Y = Y2 L`` from the Jacobian's midpoints ``Jm`` (nf x nf + 6); False when singular."""
    L, G, Z, _, _, LU, piv, col, R, _, _, _, _, _ = ws
    m = rows - 1
    nf = Jm.shape[0]
    nl = 6 * m
    A = R  # scratch (R is recomputed per box)
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
    return _invert(S, 6, LU, piv, col, Z)


@njit(cache=True)
def transform(Jm, Jr, rows, ws):
    """``M = L J(X)`` leg by leg as midpoints and radii (its own rows' platform columns centred on ``G``)."""
    L, G, _, Mm, Mr, _, _, _, _, _, _, _, _, _ = ws
    m = rows - 1
    nl = 6 * m
    for i in range(6):
        o, c = i * rows, i * m
        for a in range(rows):
            for b in range(m + 6):
                j = c + b if b < m else nl + b - m
                t, s, r = 0.0, 0.0, 0.0
                for k in range(rows):
                    p = L[i, a, k] * Jm[o + k, j]
                    t += p
                    s += abs(p)
                    r += abs(L[i, a, k]) * Jr[o + k, j]
                r = up(r + REL * s)
                if a < m and b >= m:  # re-centred on G (exact: the midpoint moved, the radius grew)
                    g = G[i, a, b - m]
                    r = up(r + abs(t - g) + REL * (abs(t) + abs(g)))
                    t = g
                Mm[i, a, b], Mr[i, a, b] = t, r


@njit(cache=True)
def apply(ws, rows, vm, vr, wm, wr):
    """``wm +- wr`` (nf,) encloses ``Y v`` for every ``v`` in ``vm +- vr`` (nf,)."""
    L, G, Z, _, _, _, _, _, _, um, ur, pm, pr, _ = ws
    m = rows - 1
    nl = 6 * m
    for i in range(6):
        o = i * rows
        for a in range(rows):
            t, s, r = 0.0, 0.0, 0.0
            for k in range(rows):
                p = L[i, a, k] * vm[o + k]
                t += p
                s += abs(p)
                r += abs(L[i, a, k]) * vr[o + k]
            um[i, a], ur[i, a] = t, up(r + REL * s)
    for a in range(6):  # p = Z u_n: the platform's rows
        t, s, r = 0.0, 0.0, 0.0
        for j in range(6):
            p = Z[a, j] * um[j, m]
            t += p
            s += abs(p)
            r += abs(Z[a, j]) * ur[j, m]
        pm[a], pr[a] = t, up(r + REL * s)
        wm[nl + a], wr[nl + a] = pm[a], pr[a]
    for i in range(6):  # the legs' own rows: u_own - G p
        for a in range(m):
            t, s, r = um[i, a], abs(um[i, a]), ur[i, a]
            for b in range(6):
                p = G[i, a, b] * pm[b]
                t -= p
                s += abs(p)
                r += abs(G[i, a, b]) * pr[b]
            wm[i * m + a], wr[i * m + a] = t, up(r + REL * s)


@njit(cache=True)
def preconditioned(ws, rows, Fm, Fr, gm, gr, half, YFm, YFr, tm, tr):
    """``Y F(xc, S)`` as midpoint and radius, ``F in Fm +- (Fr + gr) + gm [-half, half]`` (:mod:`.krawczyk`).

    ``tm``, ``tr`` (nf,) are scratch, and so is ``gr`` once read.
    """
    nf = Fm.shape[0]
    for a in range(nf):
        tr[a] = up(Fr[a] + gr[a])
    apply(ws, rows, Fm, tr, YFm, YFr)
    tr[:] = 0.0
    apply(ws, rows, gm, tr, tm, gr)  # gr: free once added above
    for a in range(nf):
        YFr[a] = up(YFr[a] + up(abs(tm[a]) + gr[a]) * half)


@njit(cache=True)
def krawczyk_blocks(YFm, YFr, rows, ws, rho, off, rad):
    """One Krawczyk test of the box ``xc +- rho`` with ``M`` of :func:`transform` (see the module doc).

    Writes ``K = xc + off +- rad`` and returns True when ``K`` lies in the interior of the box.
    """
    _, G, Z, Mm, Mr, _, _, _, R, _, _, u, p, zu = ws
    m = rows - 1
    nl = 6 * m
    for a in range(6):  # R = |I - Z S|, S = mid(M)'s n rows
        for b in range(6):
            t, s = 1.0 if a == b else 0.0, 0.0
            for k in range(6):
                q = Z[a, k] * Mm[k, m, m + b]
                t -= q
                s += abs(q)
            R[a, b] = up(abs(t) + REL * (s + 1.0))
    for j in range(6):  # u = |E21| rho_own + rad(M)'s n rows rho
        s = 0.0
        for b in range(m):
            s += (abs(Mm[j, m, b]) + Mr[j, m, b]) * rho[j * m + b]
        for b in range(6):
            s += Mr[j, m, m + b] * rho[nl + b]
        u[j] = up(s)
    for a in range(6):  # p = |R| rho_p
        s = 0.0
        for b in range(6):
            s += R[a, b] * rho[nl + b]
        p[a] = up(s)
    ok = True
    for a in range(6):  # the platform's rows: |Z| u + p
        s = p[a]
        for j in range(6):
            s += abs(Z[a, j]) * u[j]
        zu[a] = up(s)
        off[nl + a] = -YFm[nl + a]
        rad[nl + a] = up(zu[a] + YFr[nl + a])
        if not up(abs(off[nl + a]) + rad[nl + a]) < rho[nl + a]:
            ok = False
    for i in range(6):  # the legs' own rows: |E11| rho_own + rad(M) rho + |G| (|Z| u + p)
        for a in range(m):
            s = 0.0
            for b in range(m):
                e = Mm[i, a, b]
                e = up(abs(e - 1.0) + REL * (abs(e) + 1.0)) if a == b else abs(e)
                s += (e + Mr[i, a, b]) * rho[i * m + b]
            for b in range(6):
                s += Mr[i, a, m + b] * rho[nl + b] + abs(G[i, a, b]) * zu[b]
            x = i * m + a
            off[x] = -YFm[x]
            rad[x] = up(up(s) + YFr[x])
            if not up(abs(off[x]) + rad[x]) < rho[x]:
                ok = False
    return ok
