"""A compiled Krawczyk (interval Newton) proof that a readings path stays on one assembly.

For the closure residual ``F(x, s)`` of direct kinematics (:mod:`.intervals`: the unknowns ``x``
are the legs' free joints and the platform's chart coordinates; the held prismatic joints move
with the readings path ``l(s) = l0 + s (l1 - l0)``), a box ``X = xc +- rho`` and a parameter
interval ``S = [s0, s1]``, the Krawczyk operator is

    K(X, S) = xc - Y F(xc, S) + (I - Y J(X, S)) (X - xc),   Y ~ J(xc, s_mid)^-1,

with ``F(xc, S)`` and ``J(X, S)`` the interval enclosures over the box and the parameter interval.
**Krawczyk's theorem** (Krawczyk 1969; Moore 1977; Neumaier, *Interval methods for systems of
equations*, 1990, thm. 5.1.8): if ``K(X, S)`` lies in the interior of ``X``, then for every ``s`` in
``S`` the system ``F(., s) = 0`` has exactly one solution in ``X`` (and ``J`` is regular on ``X``), so
the solutions for ``s`` in ``S`` form one continuous path inside ``X`` (the implicit function theorem).

:func:`prove_path` covers ``[0, 1]`` with such tests, halving a sub-interval whose test fails (at
most ``MAX_TESTS`` tests), and chains them: consecutive boxes must hold each other's ``K``
(then the path's point at the shared ``s`` is the unique solution of both boxes), the first box
the start ``x0``, and a last test at ``s = 1`` alone, on a box about the result ``x1`` inside the
last box (whose Jacobian enclosure, over a larger box and parameter interval, holds the
Jacobian over it: inclusion isotonicity), gives the box that holds the exact solution the path
ends at (the unique one of the last box at ``s = 1``).
Each test tries ``INFLATIONS`` boxes (epsilon-inflation: ``rho <- 1.5 |K - xc|``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .intervals import REL, enclose, up
from .linalg import lu_factor_in_place, lu_solve_in_place

MAX_TESTS = 32  # Krawczyk tests per path (each sub-interval that fails is halved)
MIN_WIDTH = 1.0 / 64.0  # narrowest sub-interval of the readings path tried
INFLATIONS = 4  # boxes tried per test (epsilon-inflation)


@njit(cache=True)
def krawczyk(YFm, YFr, Jm, Jr, rho, Y, off, rad):
    """One Krawczyk test of the box ``xc +- rho``.

    ``YFm +- YFr`` encloses ``Y F(xc, S)``, ``Jm +- Jr`` (its first nf columns) ``J(X, S)``; ``Y``
    is the preconditioner (an approximate inverse of the Jacobian at ``xc``). Writes
    ``K = xc + off +- rad`` and returns True when ``K`` lies in the interior of the box.
    """
    nf = YFm.shape[0]
    aY = np.abs(Y)
    Jf = np.ascontiguousarray(Jm[:, :nf])
    YJ = Y @ Jf
    Cr = aY @ (Jr[:, :nf] + REL * np.abs(Jf))  # J's radius and the product's rounding
    ok = True
    for a in range(nf):
        s = 0.0
        for b in range(nf):
            c = (1.0 if a == b else 0.0) - YJ[a, b]
            s += (abs(c) + up(Cr[a, b] + REL * (abs(YJ[a, b]) + 1.0))) * rho[b]
        off[a] = -YFm[a]
        rad[a] = up(up(s) + YFr[a])
        if not up(abs(off[a]) + rad[a]) < rho[a]:
            ok = False
    return ok


@njit(cache=True)
def _preconditioned(Y, Fm, Fr, Jm, Jr, dl, half, e):
    """``Y F(xc, S)`` as midpoint and radius, by the mean-value form along the readings path.

    ``F(xc, l(s)) in F(xc, hm) + J_held(xc, S) (dl (s - sm) + e)``, ``|s - sm| <= half``, ``e``
    the rounding of the held joints' midpoint ``hm``: ``Y J_held dl`` is about the path's
    tangent, so the readings' change is not spread over every unknown as ``|Y| |F|`` would.
    """
    nf = Fm.shape[0]
    aY = np.abs(Y)
    YFm = Y @ Fm
    YFr = aY @ (Fr + REL * np.abs(Fm))
    gm, gr = np.zeros(nf), np.zeros(nf)
    for a in range(nf):
        for i in range(6):
            t = Jm[a, nf + i] * dl[i]
            gm[a] += t
            gr[a] += Jr[a, nf + i] * abs(dl[i]) * half + REL * abs(t) * half
            gr[a] += (abs(Jm[a, nf + i]) + Jr[a, nf + i]) * e[i]
    Yg = Y @ gm
    YFr += aY @ gr + (np.abs(Yg) + REL * (aY @ np.abs(gm))) * half
    for a in range(nf):
        YFr[a] = up(YFr[a] + REL * abs(YFm[a]))
    return YFm, YFr


@njit(cache=True)
def _inverse(J):
    """``J^-1`` by the pivoted LU of :mod:`.linalg` (NaN when singular; any matrix serves as ``Y``)."""
    nf = J.shape[0]
    LU = J.copy()
    piv = np.empty(nf, dtype=np.int64)
    if lu_factor_in_place(LU, piv, nf) == 0.0:
        return np.full((nf, nf), np.nan)
    Y = np.zeros((nf, nf))
    for a in range(nf):
        Y[a, a] = 1.0
        lu_solve_in_place(LU, piv, Y[a], nf)  # row a: column a of J^-1
    return Y.T.copy()


@njit(cache=True)
def prove_box(tables, T0, xc, spread, hm, hr, dl, half, off, rad, rho, Jm, Jr, Y):
    """Krawczyk with epsilon-inflation around ``xc``; ``spread`` (nf,) is a first radius to cover.

    The held joints run over ``hm +- hr``, the path ``l0 + s dl`` with ``|s - sm| <= half``.
    ``Y`` is the inverse of the Jacobian's midpoint at ``xc`` and ``hm``. Writes the last box
    tried (``rho``), its ``K`` (``off``, ``rad``), the Jacobian's enclosure over it (``Jm``,
    ``Jr``: nf + 6 columns) and ``Y``; True when proven.
    """
    placements, motions, closure, held, rows = tables
    nf = xc.shape[0]
    Fm, Fr, Gm, Gr = np.empty(nf), np.empty(nf), np.empty(nf), np.empty(nf)
    zero = np.zeros(nf)
    enclose(placements, motions, closure, held, rows, T0, xc, zero, hm, np.zeros(6), False, Fm, Fr, Jm, Jr)
    enclose(placements, motions, closure, held, rows, T0, xc, zero, hm, hr, True, Gm, Gr, Jm, Jr)
    Y[:, :] = _inverse(Jm[:, :nf])
    if not np.all(np.isfinite(Y)):
        return False
    e = np.empty(6)
    for i in range(6):
        e[i] = REL * (abs(hm[i]) + abs(dl[i]))  # hm's rounding
    YFm, YFr = _preconditioned(Y, Fm, Fr, Jm, Jr, dl, half, e)
    for a in range(nf):
        rho[a] = spread[a] + 4.0 * (abs(YFm[a]) + YFr[a]) + 1e-12 * (1.0 + abs(xc[a]))  # room for the end box
    for _ in range(INFLATIONS):
        enclose(placements, motions, closure, held, rows, T0, xc, rho, hm, hr, True, Gm, Gr, Jm, Jr)
        if krawczyk(YFm, YFr, Jm, Jr, rho, Y, off, rad):
            return True
        for a in range(nf):
            rho[a] = max(rho[a], 1.5 * (abs(off[a]) + rad[a]))
    return False


@njit(cache=True, inline="always")
def _inside(c, off, rad, c2, rho2):
    """Whether the box ``c + off +- rad`` lies inside ``c2 +- rho2`` (rounding allowed for)."""
    for a in range(c.shape[0]):
        d = abs(c[a] - c2[a] + off[a])
        if not up(d + rad[a] + REL * (abs(c[a]) + abs(c2[a]) + abs(off[a]))) < rho2[a]:
            return False
    return True


@njit(cache=True)
def prove_path(tables, T0, x0, x1, l0, l1):
    """Prove that the readings path from ``x0`` (readings ``l0``) to ``x1`` (``l1``) stays on one assembly.

    Args:
        tables: ``(placements, motions, closure, held, rows)`` (:func:`.intervals.enclose`).
        T0: (4, 4) the platform chart's origin.
        x0: (nf,) the start in the unknowns' coordinates.
        x1: (nf,) the result.
        l0: (6,) the held joints' values at the start (m).
        l1: (6,) the held joints' values at the result (m).

    Returns:
        ``(proven, tests, radius, parts)`` (``tests``: the path's): ``radius`` (nf,) bounds ``|x - x1|`` for the unique
        exact solution ``x`` the path ends at (rad for the joints and the chart's rotations, m for
        its translations); ``tests`` the Krawczyk tests run; ``parts`` the sub-intervals of the
        proven path.
    """
    nf = x0.shape[0]
    off, rad, rho = np.empty(nf), np.empty(nf), np.empty(nf)
    prev_c, prev_off, prev_rad, prev_rho = np.empty(nf), np.empty(nf), np.empty(nf), np.empty(nf)
    hm, hr, xc, spread = np.empty(6), np.empty(6), np.empty(nf), np.empty(nf)
    Jm, Jr, Y = np.empty((nf, nf + 6)), np.empty((nf, nf + 6)), np.empty((nf, nf))
    dl = l1 - l0
    tests, parts, s0, width = 0, 0, 0.0, 1.0
    while s0 < 1.0:
        s1 = min(1.0, s0 + width)
        sm, half = 0.5 * (s0 + s1), 0.5 * (s1 - s0)
        for i in range(6):
            hm[i] = l0[i] + sm * dl[i]
            hr[i] = up(half * abs(dl[i]) + REL * (abs(l0[i]) + abs(dl[i])))
        for a in range(nf):
            d = x1[a] - x0[a]
            xc[a] = x0[a] + sm * d
            spread[a] = half * abs(d)
        tests += 1
        ok = prove_box(tables, T0, xc, spread, hm, hr, dl, half, off, rad, rho, Jm, Jr, Y)
        if ok and s0 == 0.0:  # the start must lie in the first box
            ok = _inside(x0, np.zeros(nf), np.zeros(nf), xc, rho)
        if ok and s0 > 0.0:  # chained to the box before
            ok = _inside(prev_c, prev_off, prev_rad, xc, rho) or _inside(xc, off, rad, prev_c, prev_rho)
        if ok:
            prev_c[:], prev_off[:], prev_rad[:], prev_rho[:] = xc, off, rad, rho
            s0 = s1
            parts += 1
            width = min(1.0 - s0, 2.0 * width) if s0 < 1.0 else width
        else:
            if width <= MIN_WIDTH or tests >= MAX_TESTS:
                return False, tests, rho, 0
            width *= 0.5
        if tests >= MAX_TESTS and s0 < 1.0:
            return False, tests, rho, 0
    # the end: a box about x1 inside the last one, whose Jacobian enclosure holds J over it at s = 1
    placements, motions, closure, held, rows = tables
    Fm, Fr = np.empty(nf), np.empty(nf)
    enclose(placements, motions, closure, held, rows, T0, x1, np.zeros(nf), l1, np.zeros(6), False, Fm, Fr, Jm, Jr)
    YFm = Y @ Fm
    YFr = np.abs(Y) @ (Fr + REL * np.abs(Fm))
    box = np.empty(nf)
    for a in range(nf):
        YFr[a] = up(YFr[a] + REL * abs(YFm[a]))
        box[a] = 2.0 * (abs(YFm[a]) + YFr[a]) + 1e-15 * (1.0 + abs(x1[a]))
    zero = np.zeros(nf)
    for _ in range(INFLATIONS):
        if not _inside(x1, zero, box, prev_c, prev_rho):
            break
        if krawczyk(YFm, YFr, Jm, Jr, box, Y, off, rad):
            for a in range(nf):
                rad[a] = up(abs(off[a]) + rad[a])
            return True, tests, rad, parts
        for a in range(nf):
            box[a] = max(box[a], 1.5 * (abs(off[a]) + rad[a]))
    return False, tests, box, 0
