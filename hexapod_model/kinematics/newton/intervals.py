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


@njit(cache=True, inline="always")
def cos_sin(xm, xr):
    """``(c, s, cr, sr)``: ``cos`` and ``sin`` of ``xm +- xr`` as midpoints ``c``, ``s`` and radii ``cr``, ``sr``."""
    c, s = np.cos(xm), np.sin(xm)
    cr = up(min(xr, abs(s) * xr + 0.5 * xr * xr) + REL)
    sr = up(min(xr, abs(c) * xr + 0.5 * xr * xr) + REL)
    return c, s, cr, sr


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
    c, s, cr, sr = cos_sin(xm, xr)
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


# On a walk along a chain (:mod:`.enclosure`) the placements are tuples of 12 floats, the rows of
# the 3 x 4 placement (index 4 a + b), one of the midpoints and one of the radii: they stay in
# registers from joint to joint, where arrays went through memory at every product (2.6 times the
# time of a leg's chain). Every sum is the one :func:`product` forms, term for term in the same
# order: the same floating-point values.
ZERO = (0.0,) * 12  # the radii of a point placement


@njit(cache=True, inline="always")
def placement(M):
    """The 12-tuple of a placement's first three rows (a 4 x 4 or 3 x 4 array)."""
    return (M[0, 0], M[0, 1], M[0, 2], M[0, 3], M[1, 0], M[1, 1], M[1, 2], M[1, 3], M[2, 0], M[2, 1], M[2, 2], M[2, 3])


@njit(cache=True, inline="always")
def store(T, M):
    """Write the 12-tuple ``T`` into the (3, 4) array ``M``."""
    M[0, 0], M[0, 1], M[0, 2], M[0, 3] = T[0], T[1], T[2], T[3]
    M[1, 0], M[1, 1], M[1, 2], M[1, 3] = T[4], T[5], T[6], T[7]
    M[2, 0], M[2, 1], M[2, 2], M[2, 3] = T[8], T[9], T[10], T[11]


@njit(cache=True, inline="always")
def _through(Am, Ar, scratch):
    """``A * B`` by :func:`product`: ``B`` (midpoints, radii) in ``scratch[2:4]``, ``A`` copied to ``scratch[0:2]``."""
    store(Am, scratch[0])
    store(Ar, scratch[1])
    product(scratch[0], scratch[1], scratch[2], scratch[3], scratch[4], scratch[5])
    return placement(scratch[4]), placement(scratch[5])


@njit(cache=True, inline="always")
def _shift_row(a0, a1, a2, a3, r0, r1, r2, r3, p0, p1, p2):
    """A row's translation of ``A * P`` for a translation ``P``: its midpoint and radius."""
    m, s, r = a3, abs(a3), r3
    t = a0 * p0
    m += t
    s += abs(t)
    r += r0 * abs(p0)
    t = a1 * p1
    m += t
    s += abs(t)
    r += r1 * abs(p1)
    t = a2 * p2
    m += t
    s += abs(t)
    r += r2 * abs(p2)
    return m, up(r + REL * s)


@njit(cache=True, inline="always")
def times_point_inline(Am, Ar, P, scratch):
    """``C = A * P`` for an interval placement ``A`` (two 12-tuples) and a point placement ``P`` (4x4).

    When ``P``'s rotation is exactly the identity (most joint placements), the rotation is
    copied exactly and only the translation is summed. ``scratch`` (6, 3, 4) is overwritten.
    Returns ``(Cm, Cr)``, 12-tuples.
    """
    for a in range(3):
        for b in range(3):
            if P[a, b] != (1.0 if a == b else 0.0):
                point(P, scratch[2], scratch[3])
                return _through(Am, Ar, scratch)
    p0, p1, p2 = P[0, 3], P[1, 3], P[2, 3]
    m0, q0 = _shift_row(Am[0], Am[1], Am[2], Am[3], Ar[0], Ar[1], Ar[2], Ar[3], p0, p1, p2)
    m1, q1 = _shift_row(Am[4], Am[5], Am[6], Am[7], Ar[4], Ar[5], Ar[6], Ar[7], p0, p1, p2)
    m2, q2 = _shift_row(Am[8], Am[9], Am[10], Am[11], Ar[8], Ar[9], Ar[10], Ar[11], p0, p1, p2)
    return (
        (Am[0], Am[1], Am[2], m0, Am[4], Am[5], Am[6], m1, Am[8], Am[9], Am[10], m2),
        (Ar[0], Ar[1], Ar[2], q0, Ar[4], Ar[5], Ar[6], q1, Ar[8], Ar[9], Ar[10], q2),
    )


@njit(cache=True, inline="always")
def _slide_row(a3, aj, r3, rj, t, tr):
    """A row's translation after a translation ``t +- tr`` along the axis whose column is ``aj``."""
    p = aj * t
    return a3 + p, up(r3 + abs(aj) * tr + rj * (abs(t) + tr) + REL * (abs(a3) + abs(p)))


@njit(cache=True, inline="always")
def _slide(Am, Ar, j, t, tr):
    """``A * Trans(t e_j)``, ``t`` in ``t +- tr``: the translation column moves along column ``j``."""
    if j == 0:
        c0, c1, c2, d0, d1, d2 = Am[0], Am[4], Am[8], Ar[0], Ar[4], Ar[8]
    elif j == 1:
        c0, c1, c2, d0, d1, d2 = Am[1], Am[5], Am[9], Ar[1], Ar[5], Ar[9]
    else:
        c0, c1, c2, d0, d1, d2 = Am[2], Am[6], Am[10], Ar[2], Ar[6], Ar[10]
    m0, q0 = _slide_row(Am[3], c0, Ar[3], d0, t, tr)
    m1, q1 = _slide_row(Am[7], c1, Ar[7], d1, t, tr)
    m2, q2 = _slide_row(Am[11], c2, Ar[11], d2, t, tr)
    return (
        (Am[0], Am[1], Am[2], m0, Am[4], Am[5], Am[6], m1, Am[8], Am[9], Am[10], m2),
        (Ar[0], Ar[1], Ar[2], q0, Ar[4], Ar[5], Ar[6], q1, Ar[8], Ar[9], Ar[10], q2),
    )


@njit(cache=True, inline="always")
def _mix(ap, aq, rp, rq, c, s, cr, sr):
    """A row's entries in columns ``p``, ``q`` after a rotation about the third axis: ``R e_p = c e_p + s e_q``."""
    t1, t2, t3, t4 = ap * c, aq * s, ap * s, aq * c
    mp = t1 + t2
    rp2 = up(abs(ap) * cr + rp * (abs(c) + cr) + abs(aq) * sr + rq * (abs(s) + sr) + REL * (abs(t1) + abs(t2)))
    mq = t4 - t3
    rq2 = up(abs(aq) * cr + rq * (abs(c) + cr) + abs(ap) * sr + rp * (abs(s) + sr) + REL * (abs(t3) + abs(t4)))
    return mp, rp2, mq, rq2


@njit(cache=True, inline="always")
def _turn(Am, Ar, j, c, s, cr, sr):
    """``A * Rot(e_j)``, cosine ``c +- cr`` and sine ``s +- sr``: columns ``j + 1`` and ``j + 2`` (mod 3) mixed."""
    if j == 0:  # columns 1 and 2
        m01, r01, m02, r02 = _mix(Am[1], Am[2], Ar[1], Ar[2], c, s, cr, sr)
        m11, r11, m12, r12 = _mix(Am[5], Am[6], Ar[5], Ar[6], c, s, cr, sr)
        m21, r21, m22, r22 = _mix(Am[9], Am[10], Ar[9], Ar[10], c, s, cr, sr)
        return (
            (Am[0], m01, m02, Am[3], Am[4], m11, m12, Am[7], Am[8], m21, m22, Am[11]),
            (Ar[0], r01, r02, Ar[3], Ar[4], r11, r12, Ar[7], Ar[8], r21, r22, Ar[11]),
        )
    if j == 1:  # columns 2 and 0
        m02, r02, m00, r00 = _mix(Am[2], Am[0], Ar[2], Ar[0], c, s, cr, sr)
        m12, r12, m10, r10 = _mix(Am[6], Am[4], Ar[6], Ar[4], c, s, cr, sr)
        m22, r22, m20, r20 = _mix(Am[10], Am[8], Ar[10], Ar[8], c, s, cr, sr)
        return (
            (m00, Am[1], m02, Am[3], m10, Am[5], m12, Am[7], m20, Am[9], m22, Am[11]),
            (r00, Ar[1], r02, Ar[3], r10, Ar[5], r12, Ar[7], r20, Ar[9], r22, Ar[11]),
        )
    m00, r00, m01, r01 = _mix(Am[0], Am[1], Ar[0], Ar[1], c, s, cr, sr)  # columns 0 and 1
    m10, r10, m11, r11 = _mix(Am[4], Am[5], Ar[4], Ar[5], c, s, cr, sr)
    m20, r20, m21, r21 = _mix(Am[8], Am[9], Ar[8], Ar[9], c, s, cr, sr)
    return (
        (m00, m01, Am[2], Am[3], m10, m11, Am[6], Am[7], m20, m21, Am[10], Am[11]),
        (r00, r01, Ar[2], Ar[3], r10, r11, Ar[6], Ar[7], r20, r21, Ar[10], Ar[11]),
    )


@njit(cache=True, inline="always")
def times_motion_inline(Am, Ar, S, xm, xr, scratch):
    """``C = A * exp(S x)``, ``x = xm +- xr``, for an interval placement ``A`` (two 12-tuples).

    A translation along a coordinate axis moves only the translation column; a rotation about
    one mixes two columns by ``cos x`` and ``sin x`` (enclosed as in :func:`motion`); any other
    motion is :func:`motion` then :func:`product`. ``scratch`` (6, 3, 4) is overwritten.
    Returns ``(Cm, Cr)``, 12-tuples.
    """
    kind, j, sign = _axis(S)
    if kind == 1:
        return _slide(Am, Ar, j, sign * xm, xr)
    if kind == 2:
        c, s, cr, sr = cos_sin(xm, xr)
        return _turn(Am, Ar, j, c, sign * s, cr, sr)
    motion(S, xm, xr, scratch[2], scratch[3])
    return _through(Am, Ar, scratch)


# Each inlined copy of the two above adds seconds to the compilation of every kernel that holds
# the walk: a walk inlines them where it calls them most, and calls these for its other uses.


@njit(cache=True)
def times_point(Am, Ar, P, scratch):
    """:func:`times_point_inline` as a call."""
    return times_point_inline(Am, Ar, P, scratch)


@njit(cache=True)
def times_motion(Am, Ar, S, xm, xr, scratch):
    """:func:`times_motion_inline` as a call."""
    return times_motion_inline(Am, Ar, S, xm, xr, scratch)
