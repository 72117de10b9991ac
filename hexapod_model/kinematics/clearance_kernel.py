"""The fast clearance query: body placements and capsule distances in one kernel (numba or NumPy).

Coal's distance on every pair of a hexapod's ~26 bodies costs several warm forward solves (its
per-pair set-up dominates). Here one kernel places every joint of the model's tree from ``q``
(the joint placements, axes and kinds read off the Pinocchio model), places the bodies, and
measures each pair of capsules and spheres (a sphere is a capsule of zero length) exactly by the
distance of their segments (Ericson, *Real-Time Collision Detection*, 5.1.9). A pair with a plate
(a disc) gets a lower bound only (the distance of the other body's capsule to the plate's
slab); the few pairs whose bound is below the smallest exact distance go to coal. The answer is
coal's to rounding (the tests hold it to 1e-9 m).
"""

from __future__ import annotations

import numpy as np

FREE, REVOLUTE, PRISMATIC = 0, 1, 2
CAPSULE, DISC = 0, 1
EPS = 1e-300


def _compose(A, B, out) -> None:
    """``out = A @ B`` for rigid 4x4 transforms (last row 0 0 0 1), without allocation."""
    for r in range(3):
        a0, a1, a2 = A[r, 0], A[r, 1], A[r, 2]
        for c in range(4):
            out[r, c] = a0 * B[0, c] + a1 * B[1, c] + a2 * B[2, c]
        out[r, 3] += A[r, 3]
    out[3, 0] = out[3, 1] = out[3, 2] = 0.0
    out[3, 3] = 1.0


def _local(kind, axis, q, i, out) -> None:
    """The joint's own motion at ``q`` as a rigid transform ``out``."""
    out[:] = 0.0
    out[0, 0] = out[1, 1] = out[2, 2] = out[3, 3] = 1.0
    if kind == FREE:
        x, y, z, w = q[i + 3], q[i + 4], q[i + 5], q[i + 6]
        out[0, 0], out[0, 1], out[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
        out[1, 0], out[1, 1], out[1, 2] = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
        out[2, 0], out[2, 1], out[2, 2] = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)
        out[0, 3], out[1, 3], out[2, 3] = q[i], q[i + 1], q[i + 2]
    elif kind == REVOLUTE:
        c, s = np.cos(q[i]), np.sin(q[i])
        x, y, z = axis[0], axis[1], axis[2]
        C = 1.0 - c
        out[0, 0], out[0, 1], out[0, 2] = c + x * x * C, x * y * C - z * s, x * z * C + y * s
        out[1, 0], out[1, 1], out[1, 2] = y * x * C + z * s, c + y * y * C, y * z * C - x * s
        out[2, 0], out[2, 1], out[2, 2] = z * x * C - y * s, z * y * C + x * s, c + z * z * C
    else:
        out[0, 3], out[1, 3], out[2, 3] = axis[0] * q[i], axis[1] * q[i], axis[2] * q[i]


def place_joints(q, parent, placement, kind, axis, idx_q, out) -> None:
    """World placements ``out`` (njoints, 4, 4) of every joint at ``q`` (parents precede children)."""
    out[0] = np.eye(4)
    local = np.empty((4, 4))
    tmp = np.empty((4, 4))
    for j in range(1, parent.shape[0]):
        _local(kind[j], axis[j], q, idx_q[j], local)
        _compose(placement[j], local, tmp)
        _compose(out[parent[j]], tmp, out[j])


def _closest(p1, q1, p2, q2):
    """Parameters ``s``, ``t`` of the closest points of segments ``p1 q1`` and ``p2 q2`` (3-vectors)."""
    a = e = f = c = b = 0.0
    for m in range(3):
        d1, d2, r = q1[m] - p1[m], q2[m] - p2[m], p1[m] - p2[m]
        a += d1 * d1
        e += d2 * d2
        f += d2 * r
        c += d1 * r
        b += d1 * d2
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


def nearest_pair(
    q, parent, placement, kind, axis, idx_q, body_joint, body_placement, half, radius, shape, first, second
):
    """The smallest exact capsule distance and its pair, and the plate pairs coal must still measure.

    Returns:
        ``(distance, pair index, witness points (2, 3), body placements (ng, 4, 4),
        candidates)``: ``candidates`` a boolean per pair, true for the plate pairs whose
        lower bound lies below ``distance``.
    """
    oMi = np.empty((parent.shape[0], 4, 4))
    place_joints(q, parent, placement, kind, axis, idx_q, oMi)
    ng = body_joint.shape[0]
    M = np.empty((ng, 4, 4))
    seg = np.empty((ng, 2, 3))
    for g in range(ng):
        _compose(oMi[body_joint[g]], body_placement[g], M[g])
        for m in range(3):
            seg[g, 0, m] = M[g, m, 3] - half[g] * M[g, m, 2]
            seg[g, 1, m] = M[g, m, 3] + half[g] * M[g, m, 2]
    npairs = first.shape[0]
    best, best_k, best_s, best_t = np.inf, -1, 0.0, 0.0
    for k in range(npairs):
        a, b = first[k], second[k]
        if shape[a] == DISC or shape[b] == DISC:
            continue
        s, t = _closest(seg[a, 0], seg[a, 1], seg[b, 0], seg[b, 1])
        dd = 0.0
        for m in range(3):
            u = seg[b, 0, m] + t * (seg[b, 1, m] - seg[b, 0, m]) - seg[a, 0, m] - s * (seg[a, 1, m] - seg[a, 0, m])
            dd += u * u
        d = np.sqrt(dd) - radius[a] - radius[b]
        if d < best:
            best, best_k, best_s, best_t = d, k, s, t
    points = np.zeros((2, 3))
    if best_k >= 0:
        a, b = first[best_k], second[best_k]
        ca = seg[a, 0] + best_s * (seg[a, 1] - seg[a, 0])
        cb = seg[b, 0] + best_t * (seg[b, 1] - seg[b, 0])
        u = cb - ca
        dist = np.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
        points[0], points[1] = ca, cb
        if dist > 0.0:
            points[0] = ca + radius[a] / dist * u
            points[1] = cb - radius[b] / dist * u
    bounds = np.full(npairs, np.inf)
    for k in range(npairs):
        a, b = first[k], second[k]
        if shape[a] != DISC and shape[b] != DISC:
            continue
        disc, other = (a, b) if shape[a] == DISC else (b, a)
        h = half[disc]
        s0 = s1 = r0 = r1 = 0.0
        for m in range(3):
            n, centre = M[disc, m, 2], M[disc, m, 3]
            s0 += n * (seg[other, 0, m] - centre)
            s1 += n * (seg[other, 1, m] - centre)
        for m in range(3):  # squared radial distances of the two ends from the disc's axis
            n, centre = M[disc, m, 2], M[disc, m, 3]
            r0 += (seg[other, 0, m] - centre - s0 * n) ** 2
            r1 += (seg[other, 1, m] - centre - s1 * n) ** 2
        side = 1.0 if s0 > h and s1 > h else (-1.0 if s0 < -h and s1 < -h else 0.0)
        if side == 0.0:
            bounds[k] = -np.inf
            continue
        low = 0 if side * s0 <= side * s1 else 1
        height = min(side * s0, side * s1)
        bound = height - h - radius[other]
        if max(r0, r1) <= radius[disc] ** 2:  # the whole segment faces the disc: the bound is its distance
            bounds[k] = np.inf
            if bound < best:
                best, best_k = bound, k
                for m in range(3):
                    n = side * M[disc, m, 2]
                    end = seg[other, low, m]
                    pc, pd = end - radius[other] * n, end - (height - h) * n
                    points[0, m], points[1, m] = (pd, pc) if disc == a else (pc, pd)
        else:
            bounds[k] = bound
    candidates = bounds < best
    return best, best_k, points, M, candidates


_COMPILED: dict[str, object] = {}


def compiled_nearest_pair():
    """:func:`nearest_pair` compiled by numba (imported, and compiled once per machine, at the first call)."""
    fn = _COMPILED.get("nearest_pair")
    if fn is None:
        from numba import njit

        g = globals()
        for name in ("_compose", "_local", "place_joints", "_closest"):
            g[name] = njit(cache=True)(g[name])
        fn = _COMPILED["nearest_pair"] = njit(cache=True)(nearest_pair)
    return fn
