"""Compiled midpoint-radius interval arithmetic of rigid placements (the primitives of :mod:`.enclosure`).

An interval is a midpoint ``m`` and a radius ``r >= 0``: the set ``[m - r, m + r]`` of reals.
The functions here multiply placements (3 x 4: rotation, then translation) given as intervals
and the exponentials of joint motions over an interval of joint values, and return intervals
proven to contain the exact value for every point of their arguments.

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
def point(M, Pm, Pr):
    """The 4x4 homogeneous ``M`` as an interval placement of radius 0."""
    for a in range(3):
        for b in range(4):
            Pm[a, b] = M[a, b]
            Pr[a, b] = 0.0


@njit(cache=True, inline="always")
def _axis(S):
    """``(kind, j, sign)`` of a unit motion ``S = [v; w]`` along or about a coordinate axis ``j``.

    ``kind`` is 1 (translation along ``sign e_j``), 2 (rotation about ``sign e_j``) or 0 (any
    other direction).
    """
    for j in range(6):
        if S[j] != 0.0:
            for k in range(j + 1, 6):
                if S[k] != 0.0:
                    return 0, 0, 0.0
            if abs(S[j]) != 1.0:
                return 0, 0, 0.0
            return (1, j, S[j]) if j < 3 else (2, j - 3, S[j])
    return 0, 0, 0.0


@njit(cache=True)
def times_point(Am, Ar, P, Cm, Cr, Mm, Mr):
    """``C = A * P`` for an interval placement ``A`` and a point placement ``P`` (4x4).

    When ``P``'s rotation is exactly the identity (most joint placements), the rotation is
    copied exactly and only the translation is summed. ``Mm``, ``Mr`` (3, 4) are scratch.
    """
    for a in range(3):
        for b in range(3):
            if P[a, b] != (1.0 if a == b else 0.0):
                point(P, Mm, Mr)
                product(Am, Ar, Mm, Mr, Cm, Cr)
                return
    for a in range(3):
        m, s, r = Am[a, 3], abs(Am[a, 3]), Ar[a, 3]
        for k in range(3):
            t = Am[a, k] * P[k, 3]
            m += t
            s += abs(t)
            r += Ar[a, k] * abs(P[k, 3])
            Cm[a, k], Cr[a, k] = Am[a, k], Ar[a, k]
        Cm[a, 3], Cr[a, 3] = m, up(r + REL * s)


@njit(cache=True)
def times_motion(Am, Ar, S, xm, xr, Cm, Cr, Mm, Mr):
    """``C = A * exp(S x)``, ``x = xm +- xr``: as :func:`motion` then :func:`product`, by columns for an axis.

    A translation along a coordinate axis moves only the translation column; a rotation about
    one mixes two columns by ``cos x`` and ``sin x`` (enclosed as in :func:`motion`). ``Mm``,
    ``Mr`` (3, 4) are scratch.
    """
    kind, j, sign = _axis(S)
    if kind == 0:
        motion(S, xm, xr, Mm, Mr)
        product(Am, Ar, Mm, Mr, Cm, Cr)
        return
    if kind == 1:
        t, tr = sign * xm, xr
        for a in range(3):
            p = Am[a, j] * t
            m = Am[a, 3] + p
            Cm[a, 3] = m
            Cr[a, 3] = up(Ar[a, 3] + abs(Am[a, j]) * tr + Ar[a, j] * (abs(t) + tr) + REL * (abs(Am[a, 3]) + abs(p)))
            for b in range(3):
                Cm[a, b], Cr[a, b] = Am[a, b], Ar[a, b]
        return
    c, s = np.cos(xm), sign * np.sin(xm)
    cr = up(min(xr, abs(s) * xr + 0.5 * xr * xr) + REL)
    sr = up(min(xr, abs(c) * xr + 0.5 * xr * xr) + REL)
    p, q = (j + 1) % 3, (j + 2) % 3  # R e_p = c e_p + s e_q, R e_q = -s e_p + c e_q
    for a in range(3):
        ap, aq, rp, rq = Am[a, p], Am[a, q], Ar[a, p], Ar[a, q]
        t1, t2, t3, t4 = ap * c, aq * s, ap * s, aq * c
        Cm[a, p] = t1 + t2
        Cr[a, p] = up(abs(ap) * cr + rp * (abs(c) + cr) + abs(aq) * sr + rq * (abs(s) + sr) + REL * (abs(t1) + abs(t2)))
        Cm[a, q] = t4 - t3
        Cr[a, q] = up(abs(aq) * cr + rq * (abs(c) + cr) + abs(ap) * sr + rp * (abs(s) + sr) + REL * (abs(t3) + abs(t4)))
        Cm[a, j], Cr[a, j] = Am[a, j], Ar[a, j]
        Cm[a, 3], Cr[a, 3] = Am[a, 3], Ar[a, 3]
