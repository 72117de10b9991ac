"""A plain clearance query and body check, to compare ``hexapod_model``'s against (like ``floor_newton.py``).

The query: every joint of the model's tree placed by 4x4 products from ``q``, the bodies
placed, capsules and spheres measured by segment distances; a pair with a plate gets a slab
bound (exact when the whole capsule faces the disc) and coal measures each one whose bound lies
below the smallest exact distance, at coal's default tolerance. Every call allocates its
arrays. The body check: the NumPy cone angles of :mod:`hexapod_model.kinematics.cones`, then
that query. Used by ``benchmarks/clearance.py``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from hexapod_model.kinematics.clearance import Clearance, ClearanceQuery
from hexapod_model.kinematics.cones import ConeAngles, ConeGeometry, cone_limits

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


for _name in ("_compose", "_local", "place_joints", "_closest"):
    globals()[_name] = njit(cache=True)(globals()[_name])
nearest_pair_compiled = njit(cache=True)(nearest_pair)


class PlainQuery:
    """The plain query on the bodies and pairs of ``query`` (a :class:`ClearanceQuery` of the same hexapod)."""

    def __init__(self, query: ClearanceQuery):
        self.query = query
        g = query.collision.geometry
        self.gdata = pin.GeometryData(g)  # coal's default tolerance
        self.arrays = _arrays(query)

    def __call__(self, q: np.ndarray) -> Clearance:
        """The clearance of ``q``: the kernel, then coal on the plate pairs it could not rule out."""
        best, k, points, placements, candidates = nearest_pair_compiled(q, *self.arrays)
        if np.any(candidates):
            geometry = self.query.collision.geometry
            for c in np.flatnonzero(candidates):
                pair = geometry.collisionPairs[int(c)]
                for g in (pair.first, pair.second):
                    self.gdata.oMg[g] = pin.SE3(placements[g])
                r = pin.computeDistance(geometry, self.gdata, int(c))
                if r.min_distance < best:
                    best, k = r.min_distance, int(c)
                    points = np.array([r.getNearestPoint1(), r.getNearestPoint2()])
        return Clearance(float(best), self.query.pairs[k], points, self.query.min_clearance)


class PlainCheck:
    """The plain body check: NumPy cones, then :class:`PlainQuery`; the violations' names."""

    def __init__(self, hexa):
        self.cones = ConeGeometry(hexa.closed_loop)
        self.limits = cone_limits(hexa.geometry)
        self.data = hexa.model.createData()
        self.query = PlainQuery(ClearanceQuery(hexa.closed_loop, hexa.geometry.min_clearance))

    def __call__(self, q: np.ndarray) -> list[str]:
        """``cone_limit``, ``collision``: what ``q`` violates."""
        out = []
        if not ConeAngles(self.cones.angles(q, self.data), self.limits).within:
            out.append("cone_limit")
        if self.query(q).collision:
            out.append("collision")
        return out


def _arrays(query: ClearanceQuery) -> tuple[np.ndarray, ...]:
    """The old kernel's arguments, from the tables of ``query``."""
    from hexapod_model.kinematics import placement_kernel as pk

    ints, floats, frames = query.tables
    nj, ng, npairs = (int(x) for x in ints[pk.SIZES, :3])
    kind = ints[pk.KIND, :nj].copy()
    axis = floats[pk.AXIS : pk.AXIS + 3, :nj].T.copy()
    shape = np.where(ints[pk.SHAPE, :ng] == pk.DISC, DISC, CAPSULE).astype(np.int64)
    return (
        ints[pk.PARENT, :nj].copy(), frames[:nj].copy(), kind, axis, ints[pk.IDX_Q, :nj].copy(),
        ints[pk.BODY_JOINT, :ng].copy(), frames[nj:].copy(), floats[pk.HALF, :ng].copy(),
        floats[pk.RADIUS, :ng].copy(), shape, ints[pk.FIRST, :npairs].copy(), ints[pk.SECOND, :npairs].copy(),
    )  # fmt: skip
