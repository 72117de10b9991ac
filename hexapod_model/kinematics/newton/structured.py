"""The structured Newton steps of the fast path: the Schur elimination and the leg blocks.

* :func:`schur_solve`: direct kinematics (the platform free, one joint held per leg): each leg's
  block is eliminated and only a 6x6 system in the platform step remains; it also gives the
  sign of the constraint Jacobian's determinant and a bound on the condition number of the
  eliminated 6x6 system (the assembly certificate and near-singularity flag of
  :mod:`hexapod_model.kinematics.certificate`).
* :func:`blocks_solve`: inverse kinematics (the platform held): six independent leg blocks.

Both build their blocks from the joint Jacobians ``J`` (:mod:`.kernels` layout) and factor them
with the pivoted LU of :mod:`.linalg`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .kernels import tip_weights
from .linalg import lu_det_sign, lu_factor_in_place, lu_solve_in_place, lu_solve_transposed_in_place


@njit(cache=True, inline="always")
def closure_weights(E, i, rows):
    """``(H_tip, H_anchor)`` of closure ``i`` as 9-tuples row by row (:func:`.kernels.tip_weights`).

    The weights of a 6-row closure's rotation rows (``H_anchor`` is ``H_tip`` transposed); zeros
    for a 3-row closure, which has no rotation rows.
    """
    ht = tip_weights(E, i) if rows == 6 else (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    return ht, (ht[0], ht[3], ht[6], ht[1], ht[4], ht[7], ht[2], ht[5], ht[8])


@njit(cache=True, inline="always")
def leg_block(J, cols, rows, point, h, B):
    """``B[:rows, :rows]``: the closure Jacobian's columns of the leg joints ``cols`` (written, not added).

    The columns' linear rows are the velocity of ``point`` (the closure's tip, world frame);
    for 6-row closures the rotation rows are ``h`` times the angular velocity, ``h = H_tip``
    (:func:`.kernels.tip_weights`) as a 9-tuple, row by row.
    """
    px, py, pz = point[0], point[1], point[2]
    for k in range(rows):
        c = cols[k]
        wx, wy, wz = J[3, c], J[4, c], J[5, c]
        B[0, k] = J[0, c] - (py * wz - pz * wy)
        B[1, k] = J[1, c] - (pz * wx - px * wz)
        B[2, k] = J[2, c] - (px * wy - py * wx)
        if rows == 6:
            B[3, k] = h[0] * wx + h[1] * wy + h[2] * wz
            B[4, k] = h[3] * wx + h[4] * wy + h[5] * wz
            B[5, k] = h[6] * wx + h[7] * wy + h[8] * wz


@njit(cache=True, inline="always")
def platform_block(J, cols, rows, point, h, B):
    """``B[:rows, :6] = -``(the closure Jacobian's columns of the platform velocity ``cols``).

    As :func:`leg_block` at the closure's anchor ``point``, with ``h = H_anchor`` (``H_tip``
    transposed) and the sign reversed: the three linear columns have no angular part
    (``oMp.act(e_k) = [R e_k; 0]``), so their rotation rows are zero.
    """
    px, py, pz = point[0], point[1], point[2]
    for k in range(3):
        c = cols[k]
        B[0, k], B[1, k], B[2, k] = -J[0, c], -J[1, c], -J[2, c]
        if rows == 6:
            B[3, k], B[4, k], B[5, k] = 0.0, 0.0, 0.0
    for k in range(3, 6):
        c = cols[k]
        wx, wy, wz = J[3, c], J[4, c], J[5, c]
        B[0, k] = -(J[0, c] - (py * wz - pz * wy))
        B[1, k] = -(J[1, c] - (pz * wx - px * wz))
        B[2, k] = -(J[2, c] - (px * wy - py * wx))
        if rows == 6:
            B[3, k] = -(h[0] * wx + h[1] * wy + h[2] * wz)
            B[4, k] = -(h[3] * wx + h[4] * wy + h[5] * wz)
            B[5, k] = -(h[6] * wx + h[7] * wy + h[8] * wz)


@njit(cache=True)
def schur_solve(J, leg_cols, held_pos, ff_cols, colmap, rows, p, E, r, x, LB, PB, A, M, pm, n, w, length):
    """Newton step when the platform is free and each leg has ``rows`` joints, one held.

    Per leg the square block ``L_i`` (all its joints) is factored once; ``n_i`` with
    ``L_i^T n_i = e_held`` eliminates the leg's free joints, leaving a 6x6 system
    ``(n_i^T A_i) v = -n_i^T r_i`` for the platform step ``v``; the leg steps follow from
    ``L_i dq_i = -(r_i + A_i v)`` (whose held entry is then zero). Writes ``x`` (``G x = r``,
    the step is ``-x``) and returns ``(ratio, kappa)``: the smallest pivot ratio (0 = singular)
    times the sign of ``prod_i det L_i * det M``, which is the sign of ``det G`` up to a
    constant of the layout, and ``2 (|M|_F / sqrt 6)^6 / |det M|``, an upper bound of the 2-norm
    condition number of ``M`` (Guggenheimer, Edelman and Johnson, 1995) at no extra solve, ``M``'s
    rotation columns (m/rad) divided by ``length`` (the geometry's length scale): scale-free.

    The loops run over ``rows`` and the legs as variables: with them constants (unrolled) a
    Schur step took 15 % less time, but every compiled unit that holds the Newton iteration
    took 10 s longer to compile (``benchmarks/compiled_newton.py``; first run after installation).
    """
    # the eliminated right-hand side, in a vector of its own: held in ``w`` (``n`` taking each
    # leg's step) the step ran slower, the compiler no longer telling the two vectors apart
    rhs = np.empty(6)
    worst = 1.0
    sign = 1.0
    for i in range(leg_cols.shape[0]):
        o = i * rows
        ht, ha = closure_weights(E, i, rows)
        leg_block(J, leg_cols[i], rows, p[i], ht, LB[i])  # L_i: the leg's joints
        platform_block(J, ff_cols, rows, p[6 + i], ha, A[i])  # A_i: the platform's velocity
        ratio = lu_factor_in_place(LB[i], PB[i], rows)
        if ratio == 0.0:
            return 0.0, np.inf
        worst = min(worst, ratio)
        sign *= lu_det_sign(LB[i], PB[i], rows)
        for a in range(rows):
            n[a] = 1.0 if a == held_pos[i] else 0.0
        lu_solve_transposed_in_place(LB[i], PB[i], n, rows)
        s = 0.0
        for a in range(rows):
            s += n[a] * r[o + a]
        rhs[i] = -s
        for k in range(6):
            s = 0.0
            for a in range(rows):
                s += n[a] * A[i, a, k]
            M[i, k] = s
    fro2 = 0.0
    for i in range(6):
        for k in range(6):
            v = M[i, k] / length if k >= 3 else M[i, k]  # rotation columns: scale-free
            fro2 += v * v
    ratio = lu_factor_in_place(M, pm, 6)
    if ratio == 0.0:
        return 0.0, np.inf
    worst = min(worst, ratio)
    sign *= lu_det_sign(M, pm, 6)
    det = 1.0
    for k in range(6):
        det *= M[k, k]
    mean = fro2 / 6.0  # cubed by hand: numba compiles a power function for ``** 3``, the same product
    kappa = 2.0 * (mean * mean * mean) / abs(det) * (length * length * length)  # det of the weighted M
    v = rhs
    lu_solve_in_place(M, pm, v, 6)
    for k in range(6):
        x[colmap[ff_cols[k]]] = -v[k]
    for i in range(leg_cols.shape[0]):
        o = i * rows
        for a in range(rows):
            s = r[o + a]
            for k in range(6):
                s += A[i, a, k] * v[k]
            w[a] = -s
        lu_solve_in_place(LB[i], PB[i], w, rows)
        for k in range(rows):
            c = colmap[leg_cols[i, k]]
            if c >= 0:
                x[c] = -w[k]
    return sign * worst, kappa


@njit(cache=True)
def blocks_solve(J, leg_cols, colmap, rows, p, E, r, x, LB, PB, w):
    """:func:`block_solve` with the blocks built from ``J`` directly (inverse kinematics).

    The platform is held, so closure ``i``'s block is ``L_i`` over its leg's joints in leg order
    (the columns ``block_cols[i]`` of the solver's ``G``, the same numbers): ``L_i x_i = r_i``.
    Writes ``x`` (``G x = r``) and returns the smallest pivot ratio (0 = singular).
    """
    worst = 1.0
    for i in range(leg_cols.shape[0]):
        o = i * rows
        ht = closure_weights(E, i, rows)[0]
        leg_block(J, leg_cols[i], rows, p[i], ht, LB[i])
        ratio = lu_factor_in_place(LB[i], PB[i], rows)
        if ratio == 0.0:
            return 0.0
        worst = min(worst, ratio)
        for a in range(rows):
            w[a] = r[o + a]
        lu_solve_in_place(LB[i], PB[i], w, rows)
        for k in range(rows):
            x[colmap[leg_cols[i, k]]] = w[k]
    return worst
