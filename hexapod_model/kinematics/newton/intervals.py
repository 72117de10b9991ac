"""Compiled midpoint-radius interval enclosures of the closure residual and its Jacobian over a box.

An interval is a midpoint ``m`` and a radius ``r >= 0``: the set ``[m - r, m + r]`` of reals.
The functions here evaluate the leg chains and the platform (as :mod:`.chains` does at a point,
with the same formulas: ``oMi = oM_parent * M_i * exp(S_i q_i)``, the closure residual and its
exact derivative of :mod:`.kernels`) for joint values given as intervals, and return intervals
that are proven to contain the exact value for every point of the box.

**Rounding.** numba cannot switch the rounding mode, so every operation is done in
round-to-nearest and its radius is made rigorous by a bound of the rounding error (Rump's
midpoint-radius arithmetic, "Fast and parallel interval arithmetic", BIT 39, 1999): the
floating-point error of a sum of ``n`` products is at most ``gamma_n = n u / (1 - n u)``
(``u = 2^-53``) times the sum of their absolute values. Here every radius is

    (exact-arithmetic radius + ``REL`` * sum of |terms| of the midpoint) * (1 + ``REL``) + ``ETA``

with ``REL = 2^-40`` (above ``gamma_n`` for any ``n < 8000``; the sums here have at most 40
terms, so it also covers the rounding of the radius' own sum) and ``ETA = 2^-1000`` (underflow).
``sin`` and ``cos`` (libm, within a few ulp) count an absolute error ``REL``; over an angle
``m +- r`` they are bounded by the mean-value form ``|cos(m + d) - cos m| <= min(r, |sin m| r + r^2/2)``.

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

REL = 2.0**-40  # relative rounding allowance of one operation (far above gamma_n for n < 8000)
ETA = 2.0**-1000  # absolute allowance (underflow)
UP = 1.0 + REL


@njit(cache=True, inline="always")
def up(x):
    """``x`` (>= 0, computed in round-to-nearest) raised to an upper bound of the exact value."""
    return x * UP + ETA


@njit(cache=True)
def product(Am, Ar, Bm, Br, Cm, Cr):
    """``C = A * B`` for interval placements (3 x 4: rotation, then translation column)."""
    for a in range(3):
        for b in range(4):
            m, s, r = 0.0, 0.0, 0.0
            for k in range(3):
                t = Am[a, k] * Bm[k, b]
                m += t
                s += abs(t)
                r += abs(Am[a, k]) * Br[k, b] + Ar[a, k] * (abs(Bm[k, b]) + Br[k, b])
            if b == 3:
                m += Am[a, 3]
                s += abs(Am[a, 3])
                r += Ar[a, 3]
            Cm[a, b] = m
            Cr[a, b] = up(r + REL * s)


@njit(cache=True)
def motion(S, xm, xr, Mm, Mr):
    """``exp(S x)`` for a unit motion ``S = [v; w]`` (prismatic or revolute) and ``x = xm +- xr``."""
    ax, ay, az = S[3], S[4], S[5]
    Mm[:, :] = 0.0
    Mr[:, :] = 0.0
    if ax == 0.0 and ay == 0.0 and az == 0.0:
        for a in range(3):
            Mm[a, a] = 1.0
            t = xm * S[a]
            Mm[a, 3] = t
            Mr[a, 3] = up(xr * abs(S[a]) + REL * abs(t))
        return
    c, s = np.cos(xm), np.sin(xm)
    cr = up(min(xr, abs(s) * xr + 0.5 * xr * xr) + REL)
    sr = up(min(xr, abs(c) * xr + 0.5 * xr * xr) + REL)
    axis = (ax, ay, az)
    K = ((0.0, -az, ay), (az, 0.0, -ax), (-ay, ax, 0.0))
    for a in range(3):
        for b in range(3):
            aa = axis[a] * axis[b]
            P = (1.0 if a == b else 0.0) - aa
            t1, t2 = c * P, s * K[a][b]
            Mm[a, b] = t1 + t2 + aa
            Mr[a, b] = up(cr * abs(P) + sr * abs(K[a][b]) + REL * (abs(t1) + abs(t2) + abs(aa) + 1.0))


@njit(cache=True, inline="always")
def _point(M, Pm, Pr):
    """The 4x4 homogeneous ``M`` as an interval placement of radius 0."""
    for a in range(3):
        for b in range(4):
            Pm[a, b] = M[a, b]
            Pr[a, b] = 0.0


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
def enclose(placements, motions, closure, held, rows, T0, xm, xr, hm, hr, jacobian, Fm, Fr, Jm, Jr):
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
    """
    n = placements.shape[1]
    nl = 6 * (n - 1)
    nf = xm.shape[0]
    Am, Ar, Bm, Br = np.empty((3, 4)), np.empty((3, 4)), np.empty((3, 4)), np.empty((3, 4))
    Mm, Mr = np.empty((3, 4)), np.empty((3, 4))
    Wm, Wr = np.empty((6, n, 3, 4)), np.empty((6, n, 3, 4))  # joints' world placements
    Pm, Pr = np.empty((6, 3, 4)), np.empty((6, 3, 4))  # the chart's joints' world placements
    tipm, tipr = np.empty((6, 3, 4)), np.empty((6, 3, 4))
    ancm, ancr = np.empty((6, 3, 4)), np.empty((6, 3, 4))
    chart = np.zeros((6, 6))
    for j in range(3):
        chart[j, j] = 1.0
        chart[3 + j, 3 + j] = 1.0
    _point(T0, Am, Ar)
    for j in range(6):
        motion(chart[j], xm[nl + j], xr[nl + j], Mm, Mr)
        product(Am, Ar, Mm, Mr, Pm[j], Pr[j])
        Am[:, :], Ar[:, :] = Pm[j], Pr[j]
    for i in range(6):
        _point(closure[6 + i], Mm, Mr)
        product(Pm[5], Pr[5], Mm, Mr, ancm[i], ancr[i])
        _point(placements[i, 0], Am, Ar)
        v = i * (n - 1)
        for k in range(n):
            if k > 0:
                _point(placements[i, k], Mm, Mr)
                product(Am, Ar, Mm, Mr, Bm, Br)
                Am[:, :], Ar[:, :] = Bm, Br
            if k == held[i]:
                motion(motions[i, k], hm[i], hr[i], Mm, Mr)
            else:
                motion(motions[i, k], xm[v], xr[v], Mm, Mr)
                v += 1
            product(Am, Ar, Mm, Mr, Wm[i, k], Wr[i, k])
            Am[:, :], Ar[:, :] = Wm[i, k], Wr[i, k]
        _point(closure[i], Mm, Mr)
        product(Am, Ar, Mm, Mr, tipm[i], tipr[i])
    Em, Er = np.empty((6, 3, 3)), np.empty((6, 3, 3))
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
    Hm, Hr, dm, dr = np.empty((3, 3)), np.empty((3, 3)), np.empty(3), np.empty(3)
    wm, wr, vm, vr = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
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
