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

The placement being built is held in scalars (the rotation's nine entries and the translation's
three), updated in place joint after joint: no array view and no tuple, so that it stays in
registers, and the code is plain arithmetic that numba types and LLVM compiles quickly (the same
operations in the same order as the small SE(3) functions it replaced, inlined as 12-tuples: the
same numbers, bit for bit, in a third less compile time).

Outputs use the layouts of :mod:`.kernels` (``J``: 6 x nv as Pinocchio's ``data.J``; ``R``,
``p``: the 12 closure frames, leg tips then platform anchors), so the residual, Jacobian and
Schur/block kernels run unchanged on them. Checked against Pinocchio in
``tests/kinematics/test_chains.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .legs import GENERAL, IDENTITY


@njit(cache=True)
def evaluate_chains(q, placements, kinds, motions, leg_q, leg_v, closure, home, platform_q, platform_v, J, R, p):
    """Everything the Newton step needs at configuration ``q`` (see the module docstring).

    Writes the leg and platform columns of ``J`` (6 x nv, WORLD) and the 12 closure frames
    ``R`` (12, 3, 3) / ``p`` (12, 3); the joints' own placements stay in registers.
    """
    n = placements.shape[1]
    for i in range(leg_q.shape[0]):  # 6 as a variable: unrolled, every unit that holds it compiled longer
        # the placement oMi, rotation r.. row by row and translation p., in scalars (registers)
        r00, r01, r02 = placements[i, 0, 0, 0], placements[i, 0, 0, 1], placements[i, 0, 0, 2]
        r10, r11, r12 = placements[i, 0, 1, 0], placements[i, 0, 1, 1], placements[i, 0, 1, 2]
        r20, r21, r22 = placements[i, 0, 2, 0], placements[i, 0, 2, 1], placements[i, 0, 2, 2]
        px, py, pz = placements[i, 0, 0, 3], placements[i, 0, 1, 3], placements[i, 0, 2, 3]
        for k in range(n):
            if k > 0:
                kind = kinds[i, k]
                if kind != IDENTITY:
                    bx, by, bz = placements[i, k, 0, 3], placements[i, k, 1, 3], placements[i, k, 2, 3]
                    px = r00 * bx + r01 * by + r02 * bz + px
                    py = r10 * bx + r11 * by + r12 * bz + py
                    pz = r20 * bx + r21 * by + r22 * bz + pz
                if kind == GENERAL:
                    b00, b01, b02 = placements[i, k, 0, 0], placements[i, k, 0, 1], placements[i, k, 0, 2]
                    b10, b11, b12 = placements[i, k, 1, 0], placements[i, k, 1, 1], placements[i, k, 1, 2]
                    b20, b21, b22 = placements[i, k, 2, 0], placements[i, k, 2, 1], placements[i, k, 2, 2]
                    r00, r01, r02 = (
                        r00 * b00 + r01 * b10 + r02 * b20,
                        r00 * b01 + r01 * b11 + r02 * b21,
                        r00 * b02 + r01 * b12 + r02 * b22,
                    )
                    r10, r11, r12 = (
                        r10 * b00 + r11 * b10 + r12 * b20,
                        r10 * b01 + r11 * b11 + r12 * b21,
                        r10 * b02 + r11 * b12 + r12 * b22,
                    )
                    r20, r21, r22 = (
                        r20 * b00 + r21 * b10 + r22 * b20,
                        r20 * b01 + r21 * b11 + r22 * b21,
                        r20 * b02 + r21 * b12 + r22 * b22,
                    )
            x = q[leg_q[i, k]]
            s0, s1, s2 = motions[i, k, 0], motions[i, k, 1], motions[i, k, 2]
            ax, ay, az = motions[i, k, 3], motions[i, k, 4], motions[i, k, 5]
            if ax == 0.0 and ay == 0.0 and az == 0.0:  # prismatic: p += x R v
                vx, vy, vz = s0 * x, s1 * x, s2 * x
                px = px + r00 * vx + r01 * vy + r02 * vz
                py = py + r10 * vx + r11 * vy + r12 * vz
                pz = pz + r20 * vx + r21 * vy + r22 * vz
            else:
                c, s = np.cos(x), np.sin(x)
                if ay == 0.0 and az == 0.0 and ax == 1.0:  # R_x: columns y, z mix
                    r01, r02 = c * r01 + s * r02, c * r02 - s * r01
                    r11, r12 = c * r11 + s * r12, c * r12 - s * r11
                    r21, r22 = c * r21 + s * r22, c * r22 - s * r21
                elif ax == 0.0 and az == 0.0 and ay == 1.0:  # R_y: columns z, x
                    r00, r02 = c * r00 - s * r02, c * r02 + s * r00
                    r10, r12 = c * r10 - s * r12, c * r12 + s * r10
                    r20, r22 = c * r20 - s * r22, c * r22 + s * r20
                elif ax == 0.0 and ay == 0.0 and az == 1.0:  # R_z: columns x, y
                    r00, r01 = c * r00 + s * r01, c * r01 - s * r00
                    r10, r11 = c * r10 + s * r11, c * r11 - s * r10
                    r20, r21 = c * r20 + s * r21, c * r21 - s * r20
                else:  # R <- R Rot(a, x), Rodrigues: R = c I + s [a] + (1 - c) a a^T
                    o = 1.0 - c
                    g00, g01, g02 = o * ax * ax + c, o * ax * ay - s * az, o * ax * az + s * ay
                    g10, g11, g12 = o * ax * ay + s * az, o * ay * ay + c, o * ay * az - s * ax
                    g20, g21, g22 = o * ax * az - s * ay, o * ay * az + s * ax, o * az * az + c
                    r00, r01, r02 = (
                        r00 * g00 + r01 * g10 + r02 * g20,
                        r00 * g01 + r01 * g11 + r02 * g21,
                        r00 * g02 + r01 * g12 + r02 * g22,
                    )
                    r10, r11, r12 = (
                        r10 * g00 + r11 * g10 + r12 * g20,
                        r10 * g01 + r11 * g11 + r12 * g21,
                        r10 * g02 + r11 * g12 + r12 * g22,
                    )
                    r20, r21, r22 = (
                        r20 * g00 + r21 * g10 + r22 * g20,
                        r20 * g01 + r21 * g11 + r22 * g21,
                        r20 * g02 + r21 * g12 + r22 * g22,
                    )
            # the WORLD column M.act(S): w = R S_w, v = R S_v + p x w
            col = leg_v[i, k]
            wx, wy, wz = r00 * ax + r01 * ay + r02 * az, r10 * ax + r11 * ay + r12 * az, r20 * ax + r21 * ay + r22 * az
            J[0, col] = r00 * s0 + r01 * s1 + r02 * s2 + py * wz - pz * wy
            J[1, col] = r10 * s0 + r11 * s1 + r12 * s2 + pz * wx - px * wz
            J[2, col] = r20 * s0 + r21 * s1 + r22 * s2 + px * wy - py * wx
            J[3, col], J[4, col], J[5, col] = wx, wy, wz
        # the tip: oMtip = oMi_last * M_tip
        for b in range(3):
            R[i, 0, b] = r00 * closure[i, 0, b] + r01 * closure[i, 1, b] + r02 * closure[i, 2, b]
            R[i, 1, b] = r10 * closure[i, 0, b] + r11 * closure[i, 1, b] + r12 * closure[i, 2, b]
            R[i, 2, b] = r20 * closure[i, 0, b] + r21 * closure[i, 1, b] + r22 * closure[i, 2, b]
        bx, by, bz = closure[i, 0, 3], closure[i, 1, 3], closure[i, 2, 3]
        p[i, 0] = r00 * bx + r01 * by + r02 * bz + px
        p[i, 1] = r10 * bx + r11 * by + r12 * bz + py
        p[i, 2] = r20 * bx + r21 * by + r22 * bz + pz
    # the platform: oMp = home * X(q_p), X's rotation as quat_to_matrix (Eigen) writes it
    x0, x1, x2 = q[platform_q], q[platform_q + 1], q[platform_q + 2]
    qx, qy, qz, qw = q[platform_q + 3], q[platform_q + 4], q[platform_q + 5], q[platform_q + 6]
    tx, ty, tz = 2.0 * qx, 2.0 * qy, 2.0 * qz
    X00, X01, X02 = 1.0 - (ty * qy + tz * qz), ty * qx - tz * qw, tz * qx + ty * qw
    X10, X11, X12 = ty * qx + tz * qw, 1.0 - (tx * qx + tz * qz), tz * qy - tx * qw
    X20, X21, X22 = tz * qx - ty * qw, tz * qy + tx * qw, 1.0 - (tx * qx + ty * qy)
    h00, h01, h02, h10, h11, h12 = home[0, 0], home[0, 1], home[0, 2], home[1, 0], home[1, 1], home[1, 2]
    h20, h21, h22 = home[2, 0], home[2, 1], home[2, 2]
    r00, r01, r02 = (
        h00 * X00 + h01 * X10 + h02 * X20,
        h00 * X01 + h01 * X11 + h02 * X21,
        h00 * X02 + h01 * X12 + h02 * X22,
    )
    r10, r11, r12 = (
        h10 * X00 + h11 * X10 + h12 * X20,
        h10 * X01 + h11 * X11 + h12 * X21,
        h10 * X02 + h11 * X12 + h12 * X22,
    )
    r20, r21, r22 = (
        h20 * X00 + h21 * X10 + h22 * X20,
        h20 * X01 + h21 * X11 + h22 * X21,
        h20 * X02 + h21 * X12 + h22 * X22,
    )
    px = h00 * x0 + h01 * x1 + h02 * x2 + home[0, 3]
    py = h10 * x0 + h11 * x1 + h12 * x2 + home[1, 3]
    pz = h20 * x0 + h21 * x1 + h22 * x2 + home[2, 3]
    v = platform_v  # oMp.act(e_k): linear columns [R e_k; 0], angular columns [p x R e_k; R e_k]
    J[0, v[0]], J[1, v[0]], J[2, v[0]], J[3, v[0]], J[4, v[0]], J[5, v[0]] = r00, r10, r20, 0.0, 0.0, 0.0
    J[0, v[1]], J[1, v[1]], J[2, v[1]], J[3, v[1]], J[4, v[1]], J[5, v[1]] = r01, r11, r21, 0.0, 0.0, 0.0
    J[0, v[2]], J[1, v[2]], J[2, v[2]], J[3, v[2]], J[4, v[2]], J[5, v[2]] = r02, r12, r22, 0.0, 0.0, 0.0
    for k in range(3):
        c = v[3 + k]
        wx, wy, wz = J[0, v[k]], J[1, v[k]], J[2, v[k]]
        J[0, c] = 0.0 + py * wz - pz * wy
        J[1, c] = 0.0 + pz * wx - px * wz
        J[2, c] = 0.0 + px * wy - py * wx
        J[3, c], J[4, c], J[5, c] = wx, wy, wz
    for f in range(6, 12):  # the anchors: oManchor = oMp * M_anchor
        for b in range(3):
            R[f, 0, b] = r00 * closure[f, 0, b] + r01 * closure[f, 1, b] + r02 * closure[f, 2, b]
            R[f, 1, b] = r10 * closure[f, 0, b] + r11 * closure[f, 1, b] + r12 * closure[f, 2, b]
            R[f, 2, b] = r20 * closure[f, 0, b] + r21 * closure[f, 1, b] + r22 * closure[f, 2, b]
        bx, by, bz = closure[f, 0, 3], closure[f, 1, 3], closure[f, 2, 3]
        p[f, 0] = r00 * bx + r01 * by + r02 * bz + px
        p[f, 1] = r10 * bx + r11 * by + r12 * bz + py
        p[f, 2] = r20 * bx + r21 * by + r22 * bz + pz
