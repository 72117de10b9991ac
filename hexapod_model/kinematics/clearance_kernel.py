"""The distance half of the body kernel: exact body distances, one call with the placements (numba or NumPy).

Coal's distance on every pair of a hexapod's ~26 bodies costs several warm forward solves (its
per-pair set-up dominates). :func:`measure_body` places the bodies and takes the cone angles
(:mod:`.placement_kernel`), then :func:`nearest` measures the pairs:

* capsules and spheres (a sphere is a capsule of zero length) exactly by the distance of their
  segments (Ericson, *Real-Time Collision Detection*, 5.1.9);
* a capsule against a plate (a solid cylinder) exactly: the distance of a point to the cylinder
  is convex along the capsule's segment, so its minimum is found by bisection on the sign of
  its derivative, stopped when the bracket times the segment's length is below ``DISC_TOL``
  (the distance is then within that of the minimum); a segment that enters the plate (an
  overlap: its depth needs coal's EPA) and two plates that a bound cannot keep apart are flagged
  for coal;
* a pair is skipped when a lower bound (bounding spheres, or the plate's slab and axis) is at
  least the smallest distance found so far, which starts at the caller's ``bound``: with the
  geometry's ``min_clearance`` a clear pose measures almost no pair exactly, and with ``inf``
  the kernel gives the smallest distance of all. Skipping never changes the answer.

The tables (:func:`~hexapod_model.kinematics.body_tables.kernel_tables`) are read-only; the work
arrays are the caller's (one per thread), so a call allocates nothing.
"""

from __future__ import annotations

import numpy as np

from . import placement_kernel as placement
from .placement_kernel import DISC, FIRST, FLAGS, HALF, ORDER, POINTS, RADIUS, REACH, SECOND, SHAPE, SIZES

EPS = 1e-300
#: the capsule-to-plate bisection stops when its bracket times the segment length is below this (m)
DISC_TOL = 1e-13
#: a lower bound skips a pair only when it exceeds the smallest distance so far by this (m): rounding
PRUNE_MARGIN = 1e-9


def _closest(a0, a1, a2, b0, b1, b2, c0, c1, c2, d0, d1, d2):
    """Parameters ``s``, ``t`` of the closest points of the segments ``a b`` and ``c d`` (coordinates)."""
    u0, u1, u2, v0, v1, v2, r0, r1, r2 = b0 - a0, b1 - a1, b2 - a2, d0 - c0, d1 - c1, d2 - c2, a0 - c0, a1 - c1, a2 - c2
    a = u0 * u0 + u1 * u1 + u2 * u2
    e = v0 * v0 + v1 * v1 + v2 * v2
    f = v0 * r0 + v1 * r1 + v2 * r2
    c = u0 * r0 + u1 * r1 + u2 * r2
    b = u0 * v0 + u1 * v1 + u2 * v2
    if a <= EPS and e <= EPS:
        return 0.0, 0.0
    if a <= EPS:
        return 0.0, min(max(f / e, 0.0), 1.0)
    if e <= EPS:
        return min(max(-c / a, 0.0), 1.0), 0.0
    denom = a * e - b * b
    s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > 0.0 else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        return min(max(-c / a, 0.0), 1.0), 0.0
    if t > 1.0:
        return min(max((b - c) / a, 0.0), 1.0), 1.0
    return s, t


def _in_plate(M, S):
    """Segment ``S`` (2, 3+) in the frame of the plate placed at ``M``: its start ``u`` and direction ``v``."""
    u0 = M[0, 0] * (S[0, 0] - M[0, 3]) + M[1, 0] * (S[0, 1] - M[1, 3]) + M[2, 0] * (S[0, 2] - M[2, 3])
    u1 = M[0, 1] * (S[0, 0] - M[0, 3]) + M[1, 1] * (S[0, 1] - M[1, 3]) + M[2, 1] * (S[0, 2] - M[2, 3])
    u2 = M[0, 2] * (S[0, 0] - M[0, 3]) + M[1, 2] * (S[0, 1] - M[1, 3]) + M[2, 2] * (S[0, 2] - M[2, 3])
    v0 = M[0, 0] * (S[1, 0] - M[0, 3]) + M[1, 0] * (S[1, 1] - M[1, 3]) + M[2, 0] * (S[1, 2] - M[2, 3]) - u0
    v1 = M[0, 1] * (S[1, 0] - M[0, 3]) + M[1, 1] * (S[1, 1] - M[1, 3]) + M[2, 1] * (S[1, 2] - M[2, 3]) - u1
    v2 = M[0, 2] * (S[1, 0] - M[0, 3]) + M[1, 2] * (S[1, 1] - M[1, 3]) + M[2, 2] * (S[1, 2] - M[2, 3]) - u2
    return u0, u1, u2, v0, v1, v2


def _off_cylinder(u0, u1, u2, v0, v1, v2, t, R, h):
    """Point ``u + t v`` (plate frame) minus its nearest point of the solid cylinder (radius R, half-height h)."""
    x, y, z = u0 + t * v0, u1 + t * v1, u2 + t * v2
    r = np.sqrt(x * x + y * y)
    s = 1.0 - R / r if r > R else 0.0
    return x * s, y * s, z - min(max(z, -h), h)


def _disc(M, S, R, h, radius, best):
    """A capsule (segment ``S``, ``radius``) against a plate (placement ``M``, radius R, half-height h).

    Returns ``(distance, t, kind)``: ``kind`` 0 when a lower bound is at least ``best`` (the
    distance is that bound), 1 exact (``t`` the segment parameter of the nearest point), 2 the
    segment enters the plate (an overlap whose depth coal measures).
    """
    u0, u1, u2, v0, v1, v2 = _in_plate(M, S)
    z0, z1 = u2, u2 + v2
    slab = max(min(z0, z1) - h, -h - max(z0, z1), 0.0)
    s, t = _closest(u0, u1, u2, u0 + v0, u1 + v1, u2 + v2, 0.0, 0.0, -h, 0.0, 0.0, h)  # against the plate's axis
    x, y, z = u0 + s * v0, u1 + s * v1, u2 + s * v2 - (t * 2.0 * h - h)
    low = max(slab, np.sqrt(x * x + y * y + z * z) - R) - radius
    if low - PRUNE_MARGIN >= best:
        return low, 0.0, 0
    length = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    lo, hi = 0.0, 1.0
    e0, e1, e2 = _off_cylinder(u0, u1, u2, v0, v1, v2, 0.0, R, h)
    if e0 == 0.0 and e1 == 0.0 and e2 == 0.0:
        return -radius, 0.0, 2
    if length * length <= EPS or e0 * v0 + e1 * v1 + e2 * v2 >= 0.0:
        hi = 0.0
    else:
        e0, e1, e2 = _off_cylinder(u0, u1, u2, v0, v1, v2, 1.0, R, h)
        if e0 * v0 + e1 * v1 + e2 * v2 <= 0.0:
            lo = 1.0
        while (hi - lo) * length > DISC_TOL:
            mid = 0.5 * (lo + hi)
            e0, e1, e2 = _off_cylinder(u0, u1, u2, v0, v1, v2, mid, R, h)
            if e0 == 0.0 and e1 == 0.0 and e2 == 0.0:
                return -radius, mid, 2
            if e0 * v0 + e1 * v1 + e2 * v2 > 0.0:
                hi = mid
            else:
                lo = mid
    t = 0.5 * (lo + hi)
    e0, e1, e2 = _off_cylinder(u0, u1, u2, v0, v1, v2, t, R, h)
    if e0 == 0.0 and e1 == 0.0 and e2 == 0.0:
        return -radius, t, 2
    return np.sqrt(e0 * e0 + e1 * e1 + e2 * e2) - radius, t, 1


def _slabs(A, B, floats, a, b):
    """A lower bound (m) of the distance of plates ``a`` (placement ``A``) and ``b`` (``B``): ``a``'s slab."""
    c = A[0, 2] * B[0, 2] + A[1, 2] * B[1, 2] + A[2, 2] * B[2, 2]  # cosine of the two axes
    reach = abs(c) * floats[HALF, b] + floats[RADIUS, b] * np.sqrt(
        max(0.0, 1.0 - c * c)
    )  # b's half-extent along a's axis
    z = A[0, 2] * (B[0, 3] - A[0, 3]) + A[1, 2] * (B[1, 3] - A[1, 3]) + A[2, 2] * (B[2, 3] - A[2, 3])
    return abs(z) - reach - floats[HALF, a] - PRUNE_MARGIN


def nearest(ints, floats, work, out, bound):
    """The smallest distance below ``bound`` (m) of the pairs of the bodies placed in ``work`` (:func:`place`).

    Returns:
        ``(distance, pair index, flagged)``: ``distance`` ``bound`` and the index -1 when no
        pair measured lies below it; the witness points (base frame, m) in
        ``out[POINTS:POINTS + 6]``; ``flagged`` pairs for coal (``out[FLAGS + k]`` 1.0).
    """
    nj, ng, npairs = ints[SIZES, 0], ints[SIZES, 1], ints[SIZES, 2]
    seg = nj + ng
    best, best_k, best_s, best_t = bound, -1, 0.0, 0.0
    flagged, ncap = 0, ints[SIZES, 6]
    for i in range(ncap):  # capsules and spheres first (in pair order): their exact distances bound the plates'
        k = ints[ORDER, i]
        a, b = ints[FIRST, k], ints[SECOND, k]
        reach = best + floats[REACH, k] + PRUNE_MARGIN
        u0 = work[nj + a, 0, 3] - work[nj + b, 0, 3]
        u1 = work[nj + a, 1, 3] - work[nj + b, 1, 3]
        u2 = work[nj + a, 2, 3] - work[nj + b, 2, 3]
        if reach <= 0.0 or u0 * u0 + u1 * u1 + u2 * u2 >= reach * reach:  # bounding spheres at least ``best`` apart
            continue
        A, B = work[seg + a], work[seg + b]
        s, t = _closest(
            A[0, 0], A[0, 1], A[0, 2], A[1, 0], A[1, 1], A[1, 2], B[0, 0], B[0, 1], B[0, 2], B[1, 0], B[1, 1], B[1, 2]
        )
        dd = 0.0
        for m in range(3):
            u = B[0, m] + t * (B[1, m] - B[0, m]) - A[0, m] - s * (A[1, m] - A[0, m])
            dd += u * u
        d = np.sqrt(dd) - floats[RADIUS, a] - floats[RADIUS, b]
        if d < best:
            best, best_k, best_s, best_t = d, k, s, t
    if best_k >= 0:
        a, b = ints[FIRST, best_k], ints[SECOND, best_k]
        Sa, Sb = work[seg + a], work[seg + b]
        dd = 0.0
        for m in range(3):
            out[POINTS + m] = Sa[0, m] + best_s * (Sa[1, m] - Sa[0, m])
            out[POINTS + 3 + m] = Sb[0, m] + best_t * (Sb[1, m] - Sb[0, m])
            dd += (out[POINTS + 3 + m] - out[POINTS + m]) ** 2
        dist = np.sqrt(dd)
        if dist > 0.0:
            ra, rb = floats[RADIUS, a] / dist, floats[RADIUS, b] / dist
            for m in range(3):
                u = out[POINTS + 3 + m] - out[POINTS + m]
                out[POINTS + m] += ra * u
                out[POINTS + 3 + m] -= rb * u
    for i in range(ncap, npairs):
        k = ints[ORDER, i]
        a, b = ints[FIRST, k], ints[SECOND, k]
        out[FLAGS + k] = 0.0
        if ints[SHAPE, a] == DISC and ints[SHAPE, b] == DISC:  # two plates: either one's slab, else coal
            if (
                max(_slabs(work[nj + a], work[nj + b], floats, a, b), _slabs(work[nj + b], work[nj + a], floats, b, a))
                < best
            ):
                out[FLAGS + k] = 1.0
                flagged += 1
            continue
        disc, other = (a, b) if ints[SHAPE, a] == DISC else (b, a)
        z0 = z1 = 0.0  # the slab's bound first: the heights of the segment's ends over the plate's mid-plane
        for m in range(3):
            z0 += work[nj + disc, m, 2] * (work[seg + other, 0, m] - work[nj + disc, m, 3])
            z1 += work[nj + disc, m, 2] * (work[seg + other, 1, m] - work[nj + disc, m, 3])
        h = floats[HALF, disc]
        if max(min(z0, z1) - h, -h - max(z0, z1)) - floats[RADIUS, other] - PRUNE_MARGIN >= best:
            continue
        M, S = work[nj + disc], work[seg + other]
        d, t, kind = _disc(M, S, floats[RADIUS, disc], floats[HALF, disc], floats[RADIUS, other], best)
        if kind == 2:
            out[FLAGS + k] = 1.0
            flagged += 1
        elif kind == 1 and d < best:
            best, best_k = d, k
            u0, u1, u2, v0, v1, v2 = _in_plate(M, S)
            e0, e1, e2 = _off_cylinder(u0, u1, u2, v0, v1, v2, t, floats[RADIUS, disc], floats[HALF, disc])
            off = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
            w = floats[RADIUS, other] / off if off > 0.0 else 0.0
            pc, pd = (POINTS + 3, POINTS) if disc == a else (POINTS, POINTS + 3)
            for m in range(3):
                x = S[0, m] + t * (S[1, m] - S[0, m])  # the segment's nearest point, base frame
                e = M[m, 0] * e0 + M[m, 1] * e1 + M[m, 2] * e2  # from the plate's nearest point to it
                out[pd + m] = x - e
                out[pc + m] = x - w * e
    return best, best_k, flagged


def measure_body(q, ints, floats, frames, work, out, bound, with_cones):
    """The body check of ``q``: :func:`.placement_kernel.place`, its ``cones`` when ``with_cones``, :func:`nearest`.

    Returns:
        ``(distance, pair index, flagged, within)``: :func:`nearest`'s, and whether every
        joint lies within its cone (True without ``with_cones``).
    """
    placement.place(q, ints, floats, frames, work, out)
    within = placement.cones(ints, floats, work, out) if with_cones else True
    best, k, flagged = nearest(ints, floats, work, out, bound)
    return best, k, flagged, within


_COMPILED: dict[str, object] = {}


def compiled_measure():
    """:func:`measure_body` compiled by numba (imported, and compiled once per machine, at the first call)."""
    fn = _COMPILED.get("measure_body")
    if fn is None:
        from numba import njit

        # the small leaves are inlined into their callers: called, each call cost more than its
        # arithmetic (a check took a quarter longer); the four functions that call them stay units
        # of their own (all inlined into one, the first compile took half as long again)
        leaf = njit(cache=True, inline="always")
        for name in ("_compose", "_local", "_shifted", "_turn"):  # the placement half first
            setattr(placement, name, leaf(getattr(placement, name)))
        for name in ("place", "cones"):
            setattr(placement, name, njit(cache=True)(getattr(placement, name)))
        g = globals()
        for name in ("_closest", "_in_plate", "_off_cylinder", "_slabs"):
            g[name] = leaf(g[name])
        for name in ("_disc", "nearest"):
            g[name] = njit(cache=True)(g[name])
        fn = _COMPILED["measure_body"] = njit(cache=True)(measure_body)
    return fn
