"""The placement half of the body kernel: joint and body placements, joint cone angles (numba or NumPy).

:func:`place` places every joint of the model's tree from ``q`` (the joint placements, axes
and kinds read off the Pinocchio model: :func:`~hexapod_model.kinematics.body_tables.kernel_tables`),
then the collision bodies and their axis segments; :func:`cones` takes each joint's cone angle
(:mod:`.cones`) from them. The tables' layout (the rows below) is shared with
:mod:`.clearance_kernel`, which measures the bodies so placed. Nothing is allocated: the work
arrays are the caller's.
"""

from __future__ import annotations

import numpy as np

FREE, REVOLUTE, PRISMATIC = 0, 1, 2
CAPSULE, DISC = 0, 1
# rows of the integer table (SIZES: njoints, nbodies, npairs, ncardan, nball, platform joint, the
# count of ORDER's first pairs, the slot of the first cosine in the output;
# SHIFT: 1 where a joint's (then a body's) placement is a translation, its rotation exactly the
# identity; UNIT: 0, 1, 2 where a joint's axis is exactly x, y, z, else -1; ORDER: the pairs of
# capsules and spheres, then those with a plate; CARDAN_A, CARDAN_B: joint ids)
PARENT, KIND, IDX_Q, BODY_JOINT, SHAPE, FIRST, SECOND, SIZES = range(8)
CARDAN_A, CARDAN_B, CARDAN_SLOT, BALL_SLOT, BALL_SECOND, BALL_TIP, SHIFT, UNIT, ORDER = range(8, 17)
N_INT = 17
# rows of the float table: joint axes (3), half-lengths, radii, cone limits, ball tip points (3), home
# directions (3), per pair the sum of the two bodies' half-lengths and radii (their bounding spheres)
AXIS, HALF, RADIUS, LIMIT, TIP, HOME, REACH = 0, 3, 4, 5, 6, 9, 12
N_FLOAT = 13
# slots of the output array: 12 cone angles (leg * 2 + end, rad), the two witness points, a coal flag per
# pair, each joint's cosine
POINTS, FLAGS = 12, 18


def _compose(A, B, out) -> None:
    """``out = A @ B`` for rigid 4x4 transforms (last row 0 0 0 1), without allocation."""
    for r in range(3):
        a0, a1, a2 = A[r, 0], A[r, 1], A[r, 2]
        for c in range(4):
            out[r, c] = a0 * B[0, c] + a1 * B[1, c] + a2 * B[2, c]
        out[r, 3] += A[r, 3]
    out[3, 0] = out[3, 1] = out[3, 2] = 0.0
    out[3, 3] = 1.0


def _local(kind, x, y, z, q, i, c, s, out) -> None:
    """The joint's own motion at ``q`` (axis ``x, y, z``; a revolute's angle's cosine and sine ``c, s``) as ``out``."""
    out[:] = 0.0
    out[0, 0] = out[1, 1] = out[2, 2] = out[3, 3] = 1.0
    if kind == FREE:
        x, y, z, w = q[i + 3], q[i + 4], q[i + 5], q[i + 6]
        out[0, 0], out[0, 1], out[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
        out[1, 0], out[1, 1], out[1, 2] = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
        out[2, 0], out[2, 1], out[2, 2] = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)
        out[0, 3], out[1, 3], out[2, 3] = q[i], q[i + 1], q[i + 2]
    elif kind == REVOLUTE:
        C = 1.0 - c
        out[0, 0], out[0, 1], out[0, 2] = c + x * x * C, x * y * C - z * s, x * z * C + y * s
        out[1, 0], out[1, 1], out[1, 2] = y * x * C + z * s, c + y * y * C, y * z * C - x * s
        out[2, 0], out[2, 1], out[2, 2] = z * x * C - y * s, z * y * C + x * s, c + z * z * C
    else:
        out[0, 3], out[1, 3], out[2, 3] = x * q[i], y * q[i], z * q[i]


def _shifted(P, F, out) -> None:
    """``out = P @ F`` for a placement ``F`` that is a translation (its rotation exactly the identity)."""
    for m in range(3):
        out[m, 0], out[m, 1], out[m, 2] = P[m, 0], P[m, 1], P[m, 2]
        out[m, 3] = P[m, 0] * F[0, 3] + P[m, 1] * F[1, 3] + P[m, 2] * F[2, 3] + P[m, 3]
    out[3, 0] = out[3, 1] = out[3, 2] = 0.0
    out[3, 3] = 1.0


def _turn(out, k, c, s) -> None:
    """``out``'s rotation times the rotation of cosine ``c``, sine ``s`` about the unit axis ``k`` (0, 1, 2)."""
    i, j = (k + 1) % 3, (k + 2) % 3
    for m in range(3):
        a, b = out[m, i], out[m, j]
        out[m, i] = c * a + s * b
        out[m, j] = c * b - s * a


def place(q, ints, floats, frames, work, out) -> None:
    """Joint placements ``work[:nj]``, body placements ``work[nj:nj+ng]`` and segments ``work[nj+ng:]`` at ``q``.

    Each revolute's cosine goes to ``out[ints[SIZES, 7] + joint]`` (the cones read it).

    A joint whose placement is a translation and whose axis is a unit axis of its frame (a
    URDF's usual joint) is placed by a shift and a planar turn; the others by products.
    """
    nj, ng = ints[SIZES, 0], ints[SIZES, 1]
    local, tmp = work[nj + 2 * ng], work[nj + 2 * ng + 1]
    work[0] = 0.0
    work[0, 0, 0] = work[0, 1, 1] = work[0, 2, 2] = work[0, 3, 3] = 1.0
    cosines = ints[SIZES, 7]
    for j in range(1, nj):
        kind, k, M = ints[KIND, j], ints[UNIT, j], work[j]
        v = q[ints[IDX_Q, j]]
        c = s = 0.0
        if kind == REVOLUTE:
            c, s = np.cos(v), np.sin(v)
            out[cosines + j] = c
        if kind != FREE and k >= 0 and ints[SHIFT, j]:
            _shifted(work[ints[PARENT, j]], frames[j], M)
            if kind == REVOLUTE:
                _turn(M, k, c, s)
            else:
                for m in range(3):
                    M[m, 3] += M[m, k] * v
            continue
        x, y, z = floats[AXIS, j], floats[AXIS + 1, j], floats[AXIS + 2, j]
        _local(kind, x, y, z, q, ints[IDX_Q, j], c, s, local)
        _compose(frames[j], local, tmp)
        _compose(work[ints[PARENT, j]], tmp, M)
    for g in range(ng):
        M, S, h = work[nj + g], work[nj + ng + g], floats[HALF, g]
        if ints[SHIFT, nj + g]:
            _shifted(work[ints[BODY_JOINT, g]], frames[nj + g], M)
        else:
            _compose(work[ints[BODY_JOINT, g]], frames[nj + g], M)
        for m in range(3):
            S[0, m] = M[m, 3] - h * M[m, 2]
            S[1, m] = M[m, 3] + h * M[m, 2]


def cones(ints, floats, work, out) -> bool:
    """Each joint's cone angle into ``out[:12]`` (rad, :mod:`.cones`); whether all lie within their limits.

    After :func:`place` (the placements, the revolutes' cosines).
    """
    out[:12] = 0.0
    cosines = ints[SIZES, 7]
    for c in range(ints[SIZES, 3]):
        out[ints[CARDAN_SLOT, c]] = np.arccos(
            min(1.0, out[cosines + ints[CARDAN_A, c]] * out[cosines + ints[CARDAN_B, c]])
        )
    P = work[ints[SIZES, 5]]
    for b in range(ints[SIZES, 4]):
        T, S = work[ints[BALL_TIP, b]], work[ints[BALL_SECOND, b]]
        t0, t1, t2 = floats[TIP, b], floats[TIP + 1, b], floats[TIP + 2, b]
        d0 = T[0, 0] * t0 + T[0, 1] * t1 + T[0, 2] * t2 + T[0, 3] - S[0, 3]
        d1 = T[1, 0] * t0 + T[1, 1] * t1 + T[1, 2] * t2 + T[1, 3] - S[1, 3]
        d2 = T[2, 0] * t0 + T[2, 1] * t1 + T[2, 2] * t2 + T[2, 3] - S[2, 3]
        n0 = P[0, 0] * d0 + P[1, 0] * d1 + P[2, 0] * d2  # R^T d: the leg axis in the platform frame
        n1 = P[0, 1] * d0 + P[1, 1] * d1 + P[2, 1] * d2
        n2 = P[0, 2] * d0 + P[1, 2] * d1 + P[2, 2] * d2
        norm = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        n0, n1, n2 = n0 / norm, n1 / norm, n2 / norm
        h0, h1, h2 = floats[HOME, b], floats[HOME + 1, b], floats[HOME + 2, b]
        c0, c1, c2 = n1 * h2 - n2 * h1, n2 * h0 - n0 * h2, n0 * h1 - n1 * h0
        out[ints[BALL_SLOT, b]] = np.arctan2(np.sqrt(c0 * c0 + c1 * c1 + c2 * c2), n0 * h0 + n1 * h1 + n2 * h2)
    within = True
    for k in range(12):
        if out[k] > floats[LIMIT, k]:
            within = False
    return within
