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
from .krawczyk_blocks import apply, krawczyk_blocks, preconditioned, setup, transform
from .krawczyk_blocks import workspace as workspace_blocks
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
def _path_term(Jm, Jr, dl, half, e, gm, gr):
    """The readings path's part of ``F(xc, S)``: ``J_held(xc, S) (dl (s - sm) + e)``, ``|s - sm| <= half``.

    Writes ``gm`` (nf,) = ``J_held``'s midpoint times ``dl`` (the path's tangent, to be taken over
    ``[-half, half]``) and ``gr`` (nf,) the radius of the rest; ``e`` the rounding of the held
    joints' midpoint ``hm``.
    """
    nf = gm.shape[0]
    for a in range(nf):
        gm[a], gr[a] = 0.0, 0.0
        for i in range(6):
            t = Jm[a, nf + i] * dl[i]
            gm[a] += t
            gr[a] += Jr[a, nf + i] * abs(dl[i]) * half + REL * abs(t) * half
            gr[a] += (abs(Jm[a, nf + i]) + Jr[a, nf + i]) * e[i]


@njit(cache=True)
def _preconditioned(Y, Fm, Fr, gm, gr, half):
    """``Y F(xc, S)`` as midpoint and radius, by the mean-value form along the readings path.

    ``F(xc, l(s)) in F(xc, hm) + J_held(xc, S) (dl (s - sm) + e)`` (:func:`_path_term`): ``Y J_held
    dl`` is about the path's tangent, so the readings' change is not spread over every unknown
    as ``|Y| |F|`` would.
    """
    nf = Fm.shape[0]
    aY = np.abs(Y)
    YFm = Y @ Fm
    YFr = aY @ (Fr + REL * np.abs(Fm))
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


def workspace(nf: int, rows: int) -> tuple:
    """The work arrays of :func:`prove_path` for ``nf`` unknowns and legs of ``rows`` closure rows."""
    return (
        np.zeros((21, nf)),  # vectors
        np.zeros((nf, nf + 6)),  # Jm: the Jacobian's enclosure (and the held joints' columns)
        np.zeros((nf, nf + 6)),  # Jr
        np.zeros((nf, nf)),  # Y: the dense test's preconditioner
        np.zeros((5, 6)),  # six-vectors
        workspace_blocks(rows),
    )


@njit(cache=True)
def prove_box(tables, T0, xc, spread, hm, hr, dl, half, off, rad, rho, structured, work):
    """Krawczyk with epsilon-inflation around ``xc``; ``spread`` (nf,) is a first radius to cover.

    The held joints run over ``hm +- hr``, the path ``l0 + s dl`` with ``|s - sm| <= half``.
    The preconditioner is the inverse of the Jacobian's midpoint at ``xc`` and ``hm``, applied
    leg by leg (``structured``, :mod:`.krawczyk_blocks`) or as a dense matrix. Writes the last
    box tried (``rho``), its ``K`` (``off``, ``rad``) and, in ``work``, the Jacobian's enclosure
    over it and the preconditioner; True when proven.
    """
    placements, motions, closure, held, rows = tables
    V, Jm, Jr, Y, H, blocks = work
    Fm, Fr, Gm, Gr, zero, gm, gr, YFm, YFr, tm, tr = V[0], V[1], V[2], V[3], V[4], V[5], V[6], V[7], V[8], V[9], V[10]
    e, zero6 = H[0], H[1]
    nf = xc.shape[0]
    zero[:] = 0.0
    zero6[:] = 0.0
    enclose(placements, motions, closure, held, rows, T0, xc, zero, hm, zero6, False, Fm, Fr, Jm, Jr)
    enclose(placements, motions, closure, held, rows, T0, xc, zero, hm, hr, True, Gm, Gr, Jm, Jr)
    if structured:
        if not setup(Jm, rows, blocks):
            return False
    else:
        Y[:, :] = _inverse(Jm[:, :nf])
        if not np.all(np.isfinite(Y)):
            return False
    for i in range(6):
        e[i] = REL * (abs(hm[i]) + abs(dl[i]))  # hm's rounding
    _path_term(Jm, Jr, dl, half, e, gm, gr)
    if structured:
        preconditioned(blocks, rows, Fm, Fr, gm, gr, half, YFm, YFr, tm, tr)
    else:
        YFm[:], YFr[:] = _preconditioned(Y, Fm, Fr, gm, gr, half)
    for a in range(nf):
        rho[a] = spread[a] + 4.0 * (abs(YFm[a]) + YFr[a]) + 1e-12 * (1.0 + abs(xc[a]))  # room for the end box
    for _ in range(INFLATIONS):
        enclose(placements, motions, closure, held, rows, T0, xc, rho, hm, hr, True, Gm, Gr, Jm, Jr)
        if structured:
            transform(Jm, Jr, rows, blocks)
            ok = krawczyk_blocks(YFm, YFr, rows, blocks, rho, off, rad)
        else:
            ok = krawczyk(YFm, YFr, Jm, Jr, rho, Y, off, rad)
        if ok:
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
def prove_path(tables, T0, x0, x1, l0, l1, structured, work):
    """Prove that the readings path from ``x0`` (readings ``l0``) to ``x1`` (``l1``) stays on one assembly.

    Args:
        tables: ``(placements, motions, closure, held, rows)`` (:func:`.intervals.enclose`).
        T0: (4, 4) the platform chart's origin.
        x0: (nf,) the start in the unknowns' coordinates.
        x1: (nf,) the result.
        l0: (6,) the held joints' values at the start (m).
        l1: (6,) the held joints' values at the result (m).
        structured: the per-leg test of :mod:`.krawczyk_blocks` (else the dense 36 x 36 one).
        work: :func:`workspace` ``(nf, rows)``, overwritten.

    Returns:
        ``(proven, tests, radius, parts)`` (``tests``: the path's): ``radius`` (nf,) bounds ``|x - x1|`` for the unique
        exact solution ``x`` the path ends at (rad for the joints and the chart's rotations, m for
        its translations); ``tests`` the Krawczyk tests run; ``parts`` the sub-intervals of the
        proven path. ``radius`` is a row of ``work``.
    """
    nf = x0.shape[0]
    V, Jm, Jr, Y, H, blocks = work
    Fm, Fr, zero, YFm, YFr = V[0], V[1], V[4], V[7], V[8]
    off, rad, rho, prev_c, prev_off, prev_rad, prev_rho = V[11], V[12], V[13], V[14], V[15], V[16], V[17]
    xc, spread, box = V[18], V[19], V[20]
    hm, hr, dl = H[2], H[3], H[4]
    placements, motions, closure, held, rows = tables
    for i in range(6):
        dl[i] = l1[i] - l0[i]
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
        ok = prove_box(tables, T0, xc, spread, hm, hr, dl, half, off, rad, rho, structured, work)
        zero[:] = 0.0
        if ok and s0 == 0.0:  # the start must lie in the first box
            ok = _inside(x0, zero, zero, xc, rho)
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
    enclose(placements, motions, closure, held, rows, T0, x1, zero, l1, H[1], False, Fm, Fr, Jm, Jr)
    if structured:
        apply(blocks, rows, Fm, Fr, YFm, YFr)
    else:
        YFm[:] = Y @ Fm
        YFr[:] = np.abs(Y) @ (Fr + REL * np.abs(Fm))
    for a in range(nf):
        YFr[a] = up(YFr[a] + REL * abs(YFm[a]))
        box[a] = 2.0 * (abs(YFm[a]) + YFr[a]) + 1e-15 * (1.0 + abs(x1[a]))
    for _ in range(INFLATIONS):
        if not _inside(x1, zero, box, prev_c, prev_rho):
            break
        if structured:
            ok = krawczyk_blocks(YFm, YFr, rows, blocks, box, off, rad)
        else:
            ok = krawczyk(YFm, YFr, Jm, Jr, box, Y, off, rad)
        if ok:
            for a in range(nf):
                rad[a] = up(abs(off[a]) + rad[a])
            return True, tests, rad, parts
        for a in range(nf):
            box[a] = max(box[a], 1.5 * (abs(off[a]) + rad[a]))
    return False, tests, box, 0
