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

from .intervals import REL, point, times_motion, times_point, up


@njit(cache=True, inline="always")
def _column(Wm, Wr, S, dm, dr, Hm, Hr, rows, sign, Jm, Jr, row, col, wm, wr, vm, vr):
    """Closure Jacobian column of the joint at world placement ``W`` with motion ``S``.

    ``[R v + (p - point) x R w; H R w]`` times ``sign``; ``d = p - point`` is given; ``wm``,
    ``wr``, ``vm``, ``vr`` (3,) are scratch.
    """
    for a in range(3):
        m1, s1, r1, m2, s2, r2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        for k in range(3):
            t1, t2 = Wm[a, k] * S[3 + k], Wm[a, k] * S[k]
            m1 += t1
            s1 += abs(t1)
            r1 += Wr[a, k] * abs(S[3 + k])
            m2 += t2
            s2 += abs(t2)
            r2 += Wr[a, k] * abs(S[k])
        wm[a], wr[a] = m1, up(r1 + REL * s1)
        vm[a], vr[a] = m2, up(r2 + REL * s2)
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3  # (d x w)_a = d_b w_c - d_c w_b
        t1, t2 = dm[b] * wm[c], dm[c] * wm[b]
        m = vm[a] + t1 - t2
        r = vr[a] + abs(dm[b]) * wr[c] + dr[b] * (abs(wm[c]) + wr[c])
        r += abs(dm[c]) * wr[b] + dr[c] * (abs(wm[b]) + wr[b])
        Jm[row + a, col] = sign * m
        Jr[row + a, col] = up(r + REL * (abs(vm[a]) + abs(t1) + abs(t2)))
    if rows == 6:
        for a in range(3):
            m, s, r = 0.0, 0.0, 0.0
            for k in range(3):
                t = Hm[a, k] * wm[k]
                m += t
                s += abs(t)
                r += abs(Hm[a, k]) * wr[k] + Hr[a, k] * (abs(wm[k]) + wr[k])
            Jm[row + 3 + a, col] = sign * m
            Jr[row + 3 + a, col] = up(r + REL * s)


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
        np.zeros((8, 3, 4)),  # placements A, B, M: midpoints, then radii
        np.zeros((2, 6, n, 3, 4)),  # the joints' world placements
        np.zeros((6, 6, 3, 4)),  # the chart's joints', the tips' and the anchors' world placements
        np.zeros((2, 6, 3, 3)),  # E (tip^T anchor) per leg
        np.zeros((2, 3, 3)),  # H
        np.zeros((6, 3)),  # d, w, v: midpoints, then radii
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
    P3, W, P6, E, H, D, chart = work
    Am, Ar, Bm, Br, Mm, Mr = P3[0], P3[1], P3[2], P3[3], P3[4], P3[5]
    Wm, Wr = W[0], W[1]  # joints' world placements
    Pm, Pr = P6[0], P6[1]  # the chart's joints' world placements
    tipm, tipr, ancm, ancr = P6[2], P6[3], P6[4], P6[5]
    point(T0, Am, Ar)
    for j in range(6):
        times_motion(Am, Ar, chart[j], xm[nl + j], xr[nl + j], Pm[j], Pr[j], Mm, Mr)
        Am, Ar = Pm[j], Pr[j]
    for i in range(6):
        times_point(Pm[5], Pr[5], closure[6 + i], ancm[i], ancr[i], Mm, Mr)
        point(placements[i, 0], Bm, Br)
        Am, Ar = Bm, Br
        v = i * (n - 1)
        for k in range(n):
            if k > 0:
                times_point(Wm[i, k - 1], Wr[i, k - 1], placements[i, k], Bm, Br, Mm, Mr)
                Am, Ar = Bm, Br
            if k == held[i]:
                times_motion(Am, Ar, motions[i, k], hm[i], hr[i], Wm[i, k], Wr[i, k], Mm, Mr)
            else:
                times_motion(Am, Ar, motions[i, k], xm[v], xr[v], Wm[i, k], Wr[i, k], Mm, Mr)
                v += 1
        times_point(Wm[i, n - 1], Wr[i, n - 1], closure[i], tipm[i], tipr[i], Mm, Mr)
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
    Hm, Hr, dm, dr, wm, wr, vm, vr = H[0], H[1], D[0], D[1], D[2], D[3], D[4], D[5]
    for i in range(6):
        o = i * rows
        if rows == 6:
            _weights(Em[i], Er[i], False, Hm, Hr)
        v = i * (n - 1)
        for k in range(n):
            if k == held[i] and Jm.shape[1] == nf:
                continue
            for a in range(3):
                dm[a] = Wm[i, k, a, 3] - tipm[i, a, 3]
                dr[a] = up(Wr[i, k, a, 3] + tipr[i, a, 3] + REL * (abs(Wm[i, k, a, 3]) + abs(tipm[i, a, 3])))
            c = nf + i if k == held[i] else v
            _column(Wm[i, k], Wr[i, k], motions[i, k], dm, dr, Hm, Hr, rows, 1.0, Jm, Jr, o, c, wm, wr, vm, vr)
            if k != held[i]:
                v += 1
        if rows == 6:
            _weights(Em[i], Er[i], True, Hm, Hr)
        for j in range(6):
            for a in range(3):
                dm[a] = Pm[j, a, 3] - ancm[i, a, 3]
                dr[a] = up(Pr[j, a, 3] + ancr[i, a, 3] + REL * (abs(Pm[j, a, 3]) + abs(ancm[i, a, 3])))
            _column(Pm[j], Pr[j], chart[j], dm, dr, Hm, Hr, rows, -1.0, Jm, Jr, o, nl + j, wm, wr, vm, vr)
