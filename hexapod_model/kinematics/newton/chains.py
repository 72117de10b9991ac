"""Compiled forward kinematics of the six leg chains and the platform, from the Pinocchio model.

:class:`.legs.ChainTables` reads, for every leg joint, what Pinocchio's model holds: the joint
placement in its parent's frame (``model.jointPlacements``), its motion subspace ``S`` (from
the joint model's own ``calc``: ``[0; axis]`` for a revolute joint, ``[axis; 0]`` for a
prismatic one), its ``q``/``v`` indices; the closure frames' placements
(``model.frames[...].placement``) and the platform's home placement. :func:`evaluate_chains`
then computes, for a configuration ``q``, what ``pin.computeJointJacobians`` followed by
``pin.updateFramePlacements`` would give for these joints and frames:

* ``oMi = oM_parent * M_i * exp(S_i q_i)`` for every leg joint (Featherstone's recursion;
  ``exp`` is a rotation about the axis or a translation along it);
* the WORLD Jacobian column of each leg joint, ``oMi.act(S_i)``: ``[p_i x a; a]`` for a revolute
  joint with world axis ``a`` through the origin ``p_i``, ``[a; 0]`` for a prismatic one;
* the platform's ``oMp = home * X(q_p)`` (``X``: free-flyer position and quaternion) and its six
  columns ``oMp.act(e_k)``;
* the closure placements ``oMtip = oMi_last * M_tip`` and ``oManchor = oMp * M_anchor``.

Outputs use the layouts of :mod:`.kernels` (``J``: 6 x nv as Pinocchio's ``data.J``; ``R``,
``p``: the 12 closure frames, leg tips then platform anchors), so the residual, Jacobian and
Schur/block kernels run unchanged on them. Checked against Pinocchio in
``tests/kinematics/test_chains.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .legs import GENERAL, SHIFT


# A placement is a tuple of 12 floats: the rotation row by row, then the translation. The functions
# below are inlined into evaluate_chains (numba's inlining; as separate calls they took half the time).
# Arrays are indexed in full (``M[i, a, b]``) rather than through views: a view costs a
# reference count update, which would dominate these few multiplications.
@njit(cache=True, inline="always")
def _load(M, i):
    """The placement of the homogeneous matrix ``M[i]`` (4x4)."""
    return (
        M[i, 0, 0], M[i, 0, 1], M[i, 0, 2], M[i, 1, 0], M[i, 1, 1], M[i, 1, 2],
        M[i, 2, 0], M[i, 2, 1], M[i, 2, 2], M[i, 0, 3], M[i, 1, 3], M[i, 2, 3],
    )  # fmt: skip


@njit(cache=True, inline="always")
def _load_joint(M, i, k):
    """The placement of the homogeneous matrix ``M[i, k]`` (4x4)."""
    return (
        M[i, k, 0, 0], M[i, k, 0, 1], M[i, k, 0, 2], M[i, k, 1, 0], M[i, k, 1, 1], M[i, k, 1, 2],
        M[i, k, 2, 0], M[i, k, 2, 1], M[i, k, 2, 2], M[i, k, 0, 3], M[i, k, 1, 3], M[i, k, 2, 3],
    )  # fmt: skip


@njit(cache=True, inline="always")
def _mul(a, b):
    """SE(3) product ``a * b``: ``R = Ra Rb``, ``p = Ra pb + pa``."""
    return (
        a[0] * b[0] + a[1] * b[3] + a[2] * b[6],
        a[0] * b[1] + a[1] * b[4] + a[2] * b[7],
        a[0] * b[2] + a[1] * b[5] + a[2] * b[8],
        a[3] * b[0] + a[4] * b[3] + a[5] * b[6],
        a[3] * b[1] + a[4] * b[4] + a[5] * b[7],
        a[3] * b[2] + a[4] * b[5] + a[5] * b[8],
        a[6] * b[0] + a[7] * b[3] + a[8] * b[6],
        a[6] * b[1] + a[7] * b[4] + a[8] * b[7],
        a[6] * b[2] + a[7] * b[5] + a[8] * b[8],
        a[0] * b[9] + a[1] * b[10] + a[2] * b[11] + a[9],
        a[3] * b[9] + a[4] * b[10] + a[5] * b[11] + a[10],
        a[6] * b[9] + a[7] * b[10] + a[8] * b[11] + a[11],
    )


@njit(cache=True, inline="always")
def _rodrigues(ax, ay, az, c, s):
    """Rotation about the unit axis ``a`` by the angle of cosine ``c`` and sine ``s``, as a placement.

    Rodrigues: ``R = c I + s [a] + (1 - c) a a^T``.
    """
    o = 1.0 - c
    return (
        o * ax * ax + c, o * ax * ay - s * az, o * ax * az + s * ay,
        o * ax * ay + s * az, o * ay * ay + c, o * ay * az - s * ax,
        o * ax * az - s * ay, o * ay * az + s * ax, o * az * az + c,
        0.0, 0.0, 0.0,
    )  # fmt: skip


@njit(cache=True, inline="always")
def _turn(T, axis, c, s):
    """``T * R_axis`` for a rotation about the joint frame's x, y or z axis (``axis`` 0, 1, 2).

    Two columns ``u``, ``v`` of ``T``'s rotation mix into ``c u + s v`` and ``c v - s u``
    (``R_x = [[1, 0, 0], [0, c, -s], [0, s, c]]``; ``R_y``: columns z, x; ``R_z``: columns x, y).
    """
    if axis == 0:
        return (
            T[0], c * T[1] + s * T[2], c * T[2] - s * T[1],
            T[3], c * T[4] + s * T[5], c * T[5] - s * T[4],
            T[6], c * T[7] + s * T[8], c * T[8] - s * T[7],
            T[9], T[10], T[11],
        )  # fmt: skip
    if axis == 1:
        return (
            c * T[0] - s * T[2], T[1], c * T[2] + s * T[0],
            c * T[3] - s * T[5], T[4], c * T[5] + s * T[3],
            c * T[6] - s * T[8], T[7], c * T[8] + s * T[6],
            T[9], T[10], T[11],
        )  # fmt: skip
    return (
        c * T[0] + s * T[1], c * T[1] - s * T[0], T[2],
        c * T[3] + s * T[4], c * T[4] - s * T[3], T[5],
        c * T[6] + s * T[7], c * T[7] - s * T[6], T[8],
        T[9], T[10], T[11],
    )  # fmt: skip


@njit(cache=True, inline="always")
def _move(T, S, i, k, x):
    """``T * exp(S[i, k] x)``: the placement after joint ``k`` of leg ``i`` moved by ``x``.

    Prismatic (``S = [v; 0]``): ``p += x R v``. Revolute (``S = [0; a]``): ``R <- R Rot(a, x)``,
    with two columns mixed when ``a`` is a coordinate axis (Pinocchio's RX, RY, RZ joints).
    """
    ax, ay, az = S[i, k, 3], S[i, k, 4], S[i, k, 5]
    if ax == 0.0 and ay == 0.0 and az == 0.0:
        vx, vy, vz = S[i, k, 0] * x, S[i, k, 1] * x, S[i, k, 2] * x
        return (
            T[0], T[1], T[2], T[3], T[4], T[5], T[6], T[7], T[8],
            T[9] + T[0] * vx + T[1] * vy + T[2] * vz,
            T[10] + T[3] * vx + T[4] * vy + T[5] * vz,
            T[11] + T[6] * vx + T[7] * vy + T[8] * vz,
        )  # fmt: skip
    c, s = np.cos(x), np.sin(x)
    if ay == 0.0 and az == 0.0 and ax == 1.0:
        axis = 0
    elif ax == 0.0 and az == 0.0 and ay == 1.0:
        axis = 1
    elif ax == 0.0 and ay == 0.0 and az == 1.0:
        axis = 2
    else:
        return _mul(T, _rodrigues(ax, ay, az, c, s))
    return _turn(T, axis, c, s)  # one call: each inlined call is a copy of _turn's three cases


# Tuples are indexed with constants only: a computed index compiles to a switch over 12 cases.
@njit(cache=True, inline="always")
def _store(T, R, p, i):
    """Write the placement ``T`` into ``R[i]`` (3x3) and ``p[i]`` (3,)."""
    R[i, 0, 0], R[i, 0, 1], R[i, 0, 2] = T[0], T[1], T[2]
    R[i, 1, 0], R[i, 1, 1], R[i, 1, 2] = T[3], T[4], T[5]
    R[i, 2, 0], R[i, 2, 1], R[i, 2, 2] = T[6], T[7], T[8]
    p[i, 0], p[i, 1], p[i, 2] = T[9], T[10], T[11]


@njit(cache=True, inline="always")
def _store_joint(T, R, p, i, k):
    """Write the placement ``T`` into ``R[i, k]`` (3x3) and ``p[i, k]`` (3,)."""
    R[i, k, 0, 0], R[i, k, 0, 1], R[i, k, 0, 2] = T[0], T[1], T[2]
    R[i, k, 1, 0], R[i, k, 1, 1], R[i, k, 1, 2] = T[3], T[4], T[5]
    R[i, k, 2, 0], R[i, k, 2, 1], R[i, k, 2, 2] = T[6], T[7], T[8]
    p[i, k, 0], p[i, k, 1], p[i, k, 2] = T[9], T[10], T[11]


@njit(cache=True, inline="always")
def _column(J, c, vx, vy, vz, wx, wy, wz, px, py, pz):
    """``J[:, c] = [v + p x w; w]``: the WORLD column of a motion ``(v, w)`` of the frame at ``p``."""
    J[0, c] = vx + py * wz - pz * wy
    J[1, c] = vy + pz * wx - px * wz
    J[2, c] = vz + px * wy - py * wx
    J[3, c], J[4, c], J[5, c] = wx, wy, wz


@njit(cache=True, inline="always")
def _act_column(T, S, i, k, J, c):
    """``J[:, c] = M.act(S[i, k])`` for ``M = T``: ``w = R S_w``, ``v = R S_v + p x w`` (WORLD column)."""
    a0, a1, a2, b0, b1, b2 = S[i, k, 0], S[i, k, 1], S[i, k, 2], S[i, k, 3], S[i, k, 4], S[i, k, 5]
    _column(
        J, c,
        T[0] * a0 + T[1] * a1 + T[2] * a2, T[3] * a0 + T[4] * a1 + T[5] * a2, T[6] * a0 + T[7] * a1 + T[8] * a2,
        T[0] * b0 + T[1] * b1 + T[2] * b2, T[3] * b0 + T[4] * b1 + T[5] * b2, T[6] * b0 + T[7] * b1 + T[8] * b2,
        T[9], T[10], T[11],
    )  # fmt: skip


@njit(cache=True, inline="always")
def _shift(a, b):
    """``a * b`` for a placement ``b`` whose rotation is the identity: ``R = Ra``, ``p = Ra pb + pa``."""
    return (
        a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8],
        a[0] * b[9] + a[1] * b[10] + a[2] * b[11] + a[9],
        a[3] * b[9] + a[4] * b[10] + a[5] * b[11] + a[10],
        a[6] * b[9] + a[7] * b[10] + a[8] * b[11] + a[11],
    )  # fmt: skip


@njit(cache=True)
def evaluate_chains(
    q, placements, kinds, motions, leg_q, leg_v, closure, home, platform_q, platform_v, oR, op, J, R, p
):
    """Everything the Newton step needs at configuration ``q`` (see the module docstring).

    Writes the leg joints' world placements ``oR`` (6, n, 3, 3) / ``op`` (6, n, 3), the leg and
    platform columns of ``J`` (6 x nv, WORLD) and the 12 closure frames ``R`` (12, 3, 3) /
    ``p`` (12, 3).
    """
    for i in range(leg_q.shape[0]):  # 6 as a variable: unrolled, every unit that holds it compiled longer
        T = _load_joint(placements, i, 0)  # the first joint hangs from the root: oM_parent = identity
        for k in range(placements.shape[1]):
            if k > 0:
                kind = kinds[i, k]
                if kind == GENERAL:
                    T = _mul(T, _load_joint(placements, i, k))
                elif kind == SHIFT:
                    T = _shift(T, _load_joint(placements, i, k))
            T = _move(T, motions, i, k, q[leg_q[i, k]])
            _store_joint(T, oR, op, i, k)
            _act_column(T, motions, i, k, J, leg_v[i, k])
        _store(_mul(T, _load(closure, i)), R, p, i)
    x = q[platform_q : platform_q + 7]
    qx, qy, qz, qw = x[3], x[4], x[5], x[6]
    tx, ty, tz = 2.0 * qx, 2.0 * qy, 2.0 * qz  # X's rotation as quat_to_matrix (Eigen) writes it
    X = (
        1.0 - (ty * qy + tz * qz),
        ty * qx - tz * qw,
        tz * qx + ty * qw,
        ty * qx + tz * qw,
        1.0 - (tx * qx + tz * qz),
        tz * qy - tx * qw,
        tz * qx - ty * qw,
        tz * qy + tx * qw,
        1.0 - (tx * qx + ty * qy),
        x[0],
        x[1],
        x[2],
    )
    T = _mul((home[0, 0], home[0, 1], home[0, 2], home[1, 0], home[1, 1], home[1, 2],
              home[2, 0], home[2, 1], home[2, 2], home[0, 3], home[1, 3], home[2, 3]), X)  # fmt: skip
    v = platform_v  # oMp.act(e_k): linear columns [R e_k; 0], angular columns [p x R e_k; R e_k]
    _column(J, v[0], T[0], T[3], T[6], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    _column(J, v[1], T[1], T[4], T[7], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    _column(J, v[2], T[2], T[5], T[8], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    _column(J, v[3], 0.0, 0.0, 0.0, T[0], T[3], T[6], T[9], T[10], T[11])
    _column(J, v[4], 0.0, 0.0, 0.0, T[1], T[4], T[7], T[9], T[10], T[11])
    _column(J, v[5], 0.0, 0.0, 0.0, T[2], T[5], T[8], T[9], T[10], T[11])
    for i in range(6):
        _store(_mul(T, _load(closure, 6 + i)), R, p, 6 + i)
