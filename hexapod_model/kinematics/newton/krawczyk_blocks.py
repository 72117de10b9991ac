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
``|Y|`` (a bound of the magnitudes of the exact ``Y2 L``, :func:`_magnitudes`: off the legs' own
blocks its entries are products ``W n`` and ``Z n`` of two floats, so ``|Y| v`` factors through
one sum per leg): the radius term is as tight as the dense test's ``|Y| rad(J)``. ``Y F(xc)``
goes through ``L`` and ``Y2`` in midpoint-radius arithmetic (:func:`apply`). Every sum is raised
by the rounding allowance of :mod:`.intervals`. The cost is a few small blocks and O(nf) products instead of
36 x 36 matrix products and a dense inverse (Rump, "Verification methods: rigorous results
using floating-point arithmetic", Acta Numerica 19, 2010, sec. 10, on preconditioning with any
approximate inverse). Work arrays come from :func:`workspace`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .intervals import REL, up


def workspace(rows: int) -> tuple:
    """The work arrays of the structured test for legs of ``rows`` closure rows (6 or 3)."""
    m, nf = rows - 1, 6 * rows
    return (
        np.zeros((6, rows, rows)),  # L: the legs' left factors
        np.zeros((6, m, 6)),  # W = G Z (rounded: Y2 is whatever matrix it holds)
        np.zeros((6, 6)),  # Z ~ S^-1
        np.zeros((6, rows, m + 6)),  # Mm: L mid(J) (own columns, then the platform's)
        np.zeros((6, rows, m + 6)),  # Mr: its rounding (and re-centring)
        np.zeros((6, 6)),  # the inversion's scratch
        np.zeros(6),  # sigma (:func:`_magnitudes`)
        np.zeros((6, 6)),  # R: |I - Z S| bound
        np.zeros((6, rows)),  # u: L v
        np.zeros((6, rows)),  # its rounding
        np.zeros(6),  # six-vectors, then an nf-vector
        np.zeros(6),
        np.zeros(nf),
        np.zeros((6, m, 6)),  # G: midpoints of L_i B_i's own rows
        np.zeros((6, m, rows)),  # |Y|'s diagonal blocks: a bound of |L_i - W_ii n_i| (the rest is |W| |n|, |Z| |n|)
        np.zeros((6, m, 6)),  # D: |G - W S| bound
    )


@njit(cache=True)
def _invert(A, n, LU, out):
    """``out[:n, :n] = A[:n, :n]^-1``, Gauss-Jordan with partial pivoting (``LU`` scratch); False when singular.

    Any matrix serves as the preconditioner (see the module doc): this one only needs to be close
    to the inverse, and is what the test then bounds, as computed.
    """
    for a in range(n):
        for b in range(n):
            LU[a, b] = A[a, b]
            out[a, b] = 1.0 if a == b else 0.0
    for k in range(n):
        p, best = k, abs(LU[k, k])
        for i in range(k + 1, n):
            v = abs(LU[i, k])
            if v > best:
                best, p = v, i
        if not best > 0.0:  # zero pivot, or NaN entries
            return False
        if p != k:
            for j in range(n):
                LU[k, j], LU[p, j] = LU[p, j], LU[k, j]
                out[k, j], out[p, j] = out[p, j], out[k, j]
        inv = 1.0 / LU[k, k]
        for j in range(n):
            LU[k, j] *= inv
            out[k, j] *= inv
        for i in range(n):
            f = LU[i, k]
            if i != k and f != 0.0:
                for j in range(k, n):
                    LU[i, j] -= f * LU[k, j]
                for j in range(n):
                    out[i, j] -= f * out[k, j]
    for a in range(n):
        for b in range(n):
            if not np.isfinite(out[a, b]):
                return False
    return True


@njit(cache=True)
def setup(Jm, rows, ws):
    """The preconditioner ``Y = Y2 L`` from the Jacobian's midpoints ``Jm`` (nf x nf + 6); False when singular.

    Also the diagonal blocks of ``|Y|`` (:func:`_magnitudes`): an upper bound of the magnitude of
    each entry of the exact product ``Y2 L`` in a leg's own rows and columns.
    """
    L, W, Z, _, _, LU, _, R, _, _, _, _, _, G, aY, _ = ws
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
        if not _invert(A, rows, LU, L[i]):
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
    if not _invert(S, Z.shape[0], LU, Z):  # 6, not a constant: a literal would compile _invert once more
        return False
    for i in range(6):
        for a in range(m):
            for j in range(6):
                s = 0.0
                for k in range(6):
                    s += G[i, a, k] * Z[k, j]
                W[i, a, j] = s
    for i in range(6):  # the diagonal blocks of Y: leg i's own rows and columns, L_i - W_ii n_i
        for a in range(m):
            for k in range(rows):
                d, t = L[i, a, k], W[i, a, i] * L[i, m, k]
                aY[i, a, k] = up(abs(d - t) + REL * (abs(d) + abs(t)))
    return True


@njit(cache=True)
def transform(Jm, rows, ws):
    """``L mid(J)`` leg by leg with its rounding (own rows' platform columns centred on ``G``), and ``R``, ``D``."""
    L, W, Z, Mm, Mr, _, _, R, _, _, _, _, _, G, _, D = ws
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
def _magnitudes(ws, rows, v, w):
    """``w >= |Y| v`` for ``v >= 0`` (nf,): an upper bound of the exact ``Y2 L``'s magnitudes times ``v``.

    ``Y``'s entries are ``L_i[a, k] - W[i, a, i] n_i[k]`` in leg ``i``'s own rows and columns (the
    bound :func:`setup` keeps), ``-W[i, a, j] n_j[k]`` in its own rows and leg ``j``'s columns, and
    ``Z[p, j] n_j[k]`` in the platform's rows (``n_j`` the last row of ``L_j``): the last two are
    products of two floats, whose exact magnitudes ``|W| |n|`` and ``|Z| |n|`` factor through
    ``sigma_j = sum_k |n_j[k]| v_j[k]``. O(nf * 6) instead of the dense ``nf x nf`` product.
    """
    L, W, Z, _, _, _, sigma, _, _, _, _, _, _, _, aY, _ = ws
    m = rows - 1
    nl = 6 * m
    for j in range(6):
        s = 0.0
        for k in range(rows):
            s += abs(L[j, m, k]) * v[j * rows + k]
        sigma[j] = up(s)
    for p in range(6):
        s = 0.0
        for j in range(6):
            s += abs(Z[p, j]) * sigma[j]
        w[nl + p] = up(s)
    for i in range(6):
        for a in range(m):
            s = 0.0
            for k in range(rows):
                s += aY[i, a, k] * v[i * rows + k]
            for j in range(6):
                if j != i:
                    s += abs(W[i, a, j]) * sigma[j]
            w[i * m + a] = up(s)


@njit(cache=True)
def apply(ws, rows, vm, vr, wm, wr):
    """``wm +- wr`` (nf,) encloses ``Y v`` for every ``v`` in ``vm +- vr`` (nf,)."""
    L, W, Z, _, _, _, _, _, um, ur, _, _, _, _, _, _ = ws
    m = rows - 1
    nl = 6 * m
    _magnitudes(ws, rows, vr, wr)
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
    _, W, Z, Mm, Mr, _, _, R, _, _, u, zu, t, _, _, D = ws
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
    _magnitudes(ws, rows, t, rad)
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
