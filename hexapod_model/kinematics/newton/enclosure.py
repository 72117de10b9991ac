"""Enclosures of the closure residual and its Jacobian over a box (:func:`enclose_into`).

The leg chains and the platform are evaluated as :mod:`.chains` does at a point (``oMi =
oM_parent * M_i * exp(S_i q_i)``, the closure residual and its exact derivative of
:mod:`.kernels`), with the joints given as intervals, in the midpoint-radius arithmetic of
:mod:`.intervals` (every rounding bounded): the results hold the exact values for every point of
the box.

**The platform** is a chart around a fixed placement ``T0`` (the solver's platform pose):
``T0 * Trans(v_0, v_1, v_2) * Rx(v_3) * Ry(v_4) * Rz(v_5)``, six one-dof joints of the same
kind as the legs' (translations along ``T0``'s axes, m; rotations about the moving axes, rad).
The unknowns are the legs' joints but the held one (each leg's prismatic joint, whose value is
the reading) and the six chart coordinates: 6 (n - 1) + 6 of them, as many as the residual's
rows (36 for 6-D closures, 18 for point closures).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .intervals import (
    REL,
    ZERO,
    placement,
    store,
    times_motion,
    times_motion_inline,
    times_point,
    times_point_inline,
    up,
)
from .kernels import BOOLEANS

#: :func:`enclose_into`'s ``jacobian`` for its callers: ``JACOBIAN[1]`` with the Jacobian,
#: ``JACOBIAN[0]`` the residual alone, plain booleans (:data:`.kernels.BOOLEANS`): with the
#: constants the enclosure compiled twice, about 10 s of the proof's first compilation.
JACOBIAN = BOOLEANS


@njit(cache=True, inline="always")
def _turned(Wm, Wr, S, a, o):
    """Row ``a`` of ``R S[o:o + 3]`` for the interval rotation ``R`` of ``W``: midpoint and radius."""
    m, s, r = 0.0, 0.0, 0.0
    for k in range(3):
        t = Wm[a, k] * S[o + k]
        m += t
        s += abs(t)
        r += Wr[a, k] * abs(S[o + k])
    return m, up(r + REL * s)


@njit(cache=True, inline="always")
def _crossed(vm, vr, db, dbr, dc, dcr, wb, wbr, wc, wcr):
    """A row of ``v + d x w``: ``v_a + d_b w_c - d_c w_b`` (midpoint, radius) with ``(a, b, c)`` cyclic."""
    t1, t2 = db * wc, dc * wb
    m = vm + t1 - t2
    r = vr + abs(db) * wcr + dbr * (abs(wc) + wcr)
    r += abs(dc) * wbr + dcr * (abs(wb) + wbr)
    return m, up(r + REL * (abs(vm) + abs(t1) + abs(t2)))


@njit(cache=True, inline="always")
def _weighted(Hm, Hr, a, w0, w1, w2, r0, r1, r2):
    """Row ``a`` of ``H w`` (intervals): midpoint and radius."""
    m, s, r = 0.0, 0.0, 0.0
    t = Hm[a, 0] * w0
    m += t
    s += abs(t)
    r += abs(Hm[a, 0]) * r0 + Hr[a, 0] * (abs(w0) + r0)
    t = Hm[a, 1] * w1
    m += t
    s += abs(t)
    r += abs(Hm[a, 1]) * r1 + Hr[a, 1] * (abs(w1) + r1)
    t = Hm[a, 2] * w2
    m += t
    s += abs(t)
    r += abs(Hm[a, 2]) * r2 + Hr[a, 2] * (abs(w2) + r2)
    return m, up(r + REL * s)


@njit(cache=True, inline="always")
def _column(Wm, Wr, S, d, Hm, Hr, rows, sign, Jm, Jr, row, col):
    """Closure Jacobian column of the joint at world placement ``W`` with motion ``S``.

    ``[R v + (p - point) x R w; H R w]`` times ``sign``; ``d = p - point`` is given (a 6-tuple:
    three midpoints, three radii). The column's vectors are held in registers, not arrays.
    """
    d0, d1, d2, e0, e1, e2 = d
    w0, u0 = _turned(Wm, Wr, S, 0, 3)
    w1, u1 = _turned(Wm, Wr, S, 1, 3)
    w2, u2 = _turned(Wm, Wr, S, 2, 3)
    v0, y0 = _turned(Wm, Wr, S, 0, 0)
    v1, y1 = _turned(Wm, Wr, S, 1, 0)
    v2, y2 = _turned(Wm, Wr, S, 2, 0)
    m, r = _crossed(v0, y0, d1, e1, d2, e2, w1, u1, w2, u2)
    Jm[row, col], Jr[row, col] = sign * m, r
    m, r = _crossed(v1, y1, d2, e2, d0, e0, w2, u2, w0, u0)
    Jm[row + 1, col], Jr[row + 1, col] = sign * m, r
    m, r = _crossed(v2, y2, d0, e0, d1, e1, w0, u0, w1, u1)
    Jm[row + 2, col], Jr[row + 2, col] = sign * m, r
    if rows == 6:
        for a in range(3):
            m, r = _weighted(Hm, Hr, a, w0, w1, w2, u0, u1, u2)
            Jm[row + 3 + a, col], Jr[row + 3 + a, col] = sign * m, r


@njit(cache=True, inline="always")
def _offset(Pm, Pr, Qm, Qr):
    """``p - q`` of two interval placements' translations, as a 6-tuple: three midpoints, three radii."""
    a, b, c = Pm[0, 3], Pm[1, 3], Pm[2, 3]
    x, y, z = Qm[0, 3], Qm[1, 3], Qm[2, 3]
    return (
        a - x,
        b - y,
        c - z,
        up(Pr[0, 3] + Qr[0, 3] + REL * (abs(a) + abs(x))),
        up(Pr[1, 3] + Qr[1, 3] + REL * (abs(b) + abs(y))),
        up(Pr[2, 3] + Qr[2, 3] + REL * (abs(c) + abs(z))),
    )


@njit(cache=True)
def _weights(Em, Er, transpose, Hm, Hr):
    """``H = (tr(E) I - E)/2`` (tip side) or ``(tr(E) I - E^T)/2`` (anchor side), intervals."""
    tm = Em[0, 0] + Em[1, 1] + Em[2, 2]
    tr = up(Er[0, 0] + Er[1, 1] + Er[2, 2] + REL * (abs(Em[0, 0]) + abs(Em[1, 1]) + abs(Em[2, 2])))
    for a in range(3):
        for b in range(3):
            e, er = (Em[b, a], Er[b, a]) if transpose else (Em[a, b], Er[a, b])
            if a == b:
                Hm[a, b] = 0.5 * (tm - e)
                Hr[a, b] = up(0.5 * (tr + er) + REL * (abs(tm) + abs(e)))
            else:
                Hm[a, b] = -0.5 * e
                Hr[a, b] = 0.5 * er  # exact: halving


@njit(cache=True)
def enclosure_workspace(n):
    """The work arrays of :func:`enclose_into` for legs of ``n`` joints (a tuple of arrays)."""
    chart = np.zeros((6, 6))  # the chart's six unit motions
    for j in range(6):
        chart[j, j] = 1.0
    return (
        np.zeros((8, 3, 4)),  # the primitives' scratch placements (:func:`.intervals.times_point`)
        np.zeros((2, 6, n, 3, 4)),  # the joints' world placements
        np.zeros((6, 6, 3, 4)),  # the chart's joints', the tips' and the anchors' world placements
        np.zeros((2, 6, 3, 3)),  # E = R_tip R_anchor^T per leg
        np.zeros((2, 3, 3)),  # H
        chart,
    )


@njit(cache=True)
def enclose(placements, motions, closure, held, rows, T0, xm, xr, hm, hr, jacobian, Fm, Fr, Jm, Jr):
    """:func:`enclose_into` with work arrays of its own."""
    work = enclosure_workspace(placements.shape[1])
    enclose_into(placements, motions, closure, held, rows, T0, xm, xr, hm, hr, jacobian, Fm, Fr, Jm, Jr, work)


@njit(cache=True)
def enclose_into(placements, motions, closure, held, rows, T0, xm, xr, hm, hr, jacobian, Fm, Fr, Jm, Jr, work):
    """Enclosures of the closure residual ``F`` (6 rows) and, if ``jacobian``, of its Jacobian.

    Args:
        placements: (6, n, 4, 4) joint placements (:class:`.legs.ChainTables`).
        motions: (6, n, 6) motion subspaces.
        closure: (12, 4, 4) tip, then anchor frames.
        held: (6,) position of the held joint in each leg.
        rows: 6 (6-D closures) or 3 (point closures).
        T0: (4, 4) the platform chart's origin (world placement of the platform joint).
        xm: (nf,) the unknowns' midpoints (leg joints but the held one, leg after leg, then the
            six chart coordinates).
        xr: (nf,) their radii.
        hm: (6,) the held joints' midpoints (m).
        hr: (6,) their radii (m).
        jacobian: whether to fill ``Jm``, ``Jr`` (derivative of ``F`` in the unknowns).
        Fm: (6 rows,) written: the residual's midpoints.
        Fr: (6 rows,) written: its radii.
        Jm: (6 rows, nf) written when ``jacobian``: the Jacobian's midpoints; with nf + 6
            columns, the last six are the derivatives in the held joints (leg order).
        Jr: (6 rows, nf or nf + 6) written when ``jacobian``: its radii.
        work: :func:`enclosure_workspace` ``(n)``, overwritten.
    """
    n = placements.shape[1]
    nl = 6 * (n - 1)
    nf = xm.shape[0]
    P3, W, P6, E, H, chart = work
    Wm, Wr = W[0], W[1]  # joints' world placements
    Pm, Pr = P6[0], P6[1]  # the chart's joints' world placements
    tipm, tipr, ancm, ancr = P6[2], P6[3], P6[4], P6[5]
    Am, Ar = placement(T0), ZERO  # the walk's placement: tuples (:mod:`.intervals`), stored where J needs it
    for j in range(6):
        Am, Ar = times_motion(Am, Ar, chart[j], xm[nl + j], xr[nl + j], P3)
        store(Am, Pm[j])
        store(Ar, Pr[j])
    Cm, Cr = Am, Ar
    for i in range(6):
        Am, Ar = times_point(Cm, Cr, closure[6 + i], P3)
        store(Am, ancm[i])
        store(Ar, ancr[i])
        Am, Ar = placement(placements[i, 0]), ZERO
        v = i * (n - 1)
        for k in range(n):  # the walk's most calls: inlined, once each
            if k > 0:
                Am, Ar = times_point_inline(Am, Ar, placements[i, k], P3)
            if k == held[i]:
                x, r = hm[i], hr[i]
            else:
                x, r = xm[v], xr[v]
                v += 1
            Am, Ar = times_motion_inline(Am, Ar, motions[i, k], x, r, P3)
            store(Am, Wm[i, k])
            store(Ar, Wr[i, k])
        Am, Ar = times_point(Am, Ar, closure[i], P3)
        store(Am, tipm[i])
        store(Ar, tipr[i])
    Em, Er = E[0], E[1]
    for i in range(6):
        o = i * rows
        for a in range(3):
            t, c = tipm[i, a, 3], ancm[i, a, 3]
            Fm[o + a] = t - c
            Fr[o + a] = up(tipr[i, a, 3] + ancr[i, a, 3] + REL * (abs(t) + abs(c)))
        if rows == 6:
            for a in range(3):
                for b in range(3):
                    m, s, r = 0.0, 0.0, 0.0
                    for k in range(3):
                        x, y = tipm[i, a, k], ancm[i, b, k]
                        m += x * y
                        s += abs(x * y)
                        r += abs(x) * ancr[i, b, k] + tipr[i, a, k] * (abs(y) + ancr[i, b, k])
                    Em[i, a, b], Er[i, a, b] = m, up(r + REL * s)
            for a in range(3):
                b, c = (a + 2) % 3, (a + 1) % 3  # e_R = vex(skew E): 0.5 (E[c, b] - E[b, c])
                Fm[o + 3 + a] = 0.5 * (Em[i, b, c] - Em[i, c, b])
                Fr[o + 3 + a] = up(0.5 * (Er[i, b, c] + Er[i, c, b]) + REL * (abs(Em[i, b, c]) + abs(Em[i, c, b])))
    if not jacobian:
        return
    Jm[:, :] = 0.0
    Jr[:, :] = 0.0
    Hm, Hr = H[0], H[1]
    for i in range(6):
        o = i * rows
        if rows == 6:
            _weights(Em[i], Er[i], BOOLEANS[0], Hm, Hr)  # plain booleans: one compile, not one per literal
        v = i * (n - 1)
        for k in range(n):
            if k == held[i] and Jm.shape[1] == nf:
                continue
            d = _offset(Wm[i, k], Wr[i, k], tipm[i], tipr[i])
            c = nf + i if k == held[i] else v
            _column(Wm[i, k], Wr[i, k], motions[i, k], d, Hm, Hr, rows, 1.0, Jm, Jr, o, c)
            if k != held[i]:
                v += 1
        if rows == 6:
            _weights(Em[i], Er[i], BOOLEANS[1], Hm, Hr)
        for j in range(6):
            d = _offset(Pm[j], Pr[j], ancm[i], ancr[i])
            _column(Pm[j], Pr[j], chart[j], d, Hm, Hr, rows, -1.0, Jm, Jr, o, nl + j)
