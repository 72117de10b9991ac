"""Numba kernels of the Newton solver's hot path (no allocation, no Python loop per call).

Inputs: the closure frames' rotations ``R`` and positions ``p`` (tips, then anchors) and the
joint Jacobians ``J``: Pinocchio's ``data.J`` after ``pin.computeJointJacobians`` (6 x nv, WORLD
convention: column ``c`` is the spatial motion of velocity ``c`` expressed at the world
origin), or the compiled chains' equivalent (:mod:`.chains`).

Residual of closure ``i`` (Bem et al. (2026) eqs. 10-14, written in the base/world frame):

* translation ``e_t = p_tip - p_anchor`` (m);
* rotation ``e_R = vex(skew(E))`` with ``E = R_tip R_anchor^T`` (rad near closure), only for
  ``6d`` closures. ``e_R = 0`` also at a 180 deg flip: callers check ``trace(E) > 1``.

Its exact derivative along a velocity ``v`` (rows ``[d e_t; d e_R]``):

* ``d e_t = (v_o - p_tip x w)_tip - (v_o - p_anchor x w)_anchor``;
* ``d e_R = H_tip w_tip - H_anchor w_anchor``, ``H_tip = (tr(E) I - E)/2``,
  ``H_anchor = (tr(E) I - E^T)/2``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: ``BOOLEANS[0]`` (False) and ``BOOLEANS[1]`` (True) as plain booleans for compiled callers: an
#: element of an array is typed ``bool``, where a constant ``True`` or ``False`` is a literal, and
#: numba compiles a function once per literal it is called with (a second specialisation of a
#: kernel, seconds of compilation). Returning the constant from a function does not help: its
#: return type stays literal.
BOOLEANS = np.array([False, True])


@njit(cache=True)
def closure_residual(R, p, rows, E, r, length):
    """Fill ``r`` (6*rows) and ``E`` (6, 3, 3) from the closure frames ``R``, ``p`` (tips, then anchors).

    Returns ``(norm, min trace(E))``, ``norm`` the residual's norm with its rotation rows (rad)
    times ``length`` (the geometry's length scale, :func:`.solver.size_of`): metres at that scale.
    """
    min_trace = 3.0
    for i in range(6):
        o = i * rows
        for a in range(3):
            r[o + a] = p[i, a] - p[6 + i, a]
        if rows == 6:
            for a in range(3):
                for b in range(3):
                    E[i, a, b] = R[i, a, 0] * R[6 + i, b, 0] + R[i, a, 1] * R[6 + i, b, 1] + R[i, a, 2] * R[6 + i, b, 2]
            r[o + 3] = 0.5 * (E[i, 2, 1] - E[i, 1, 2])
            r[o + 4] = 0.5 * (E[i, 0, 2] - E[i, 2, 0])
            r[o + 5] = 0.5 * (E[i, 1, 0] - E[i, 0, 1])
            tr = E[i, 0, 0] + E[i, 1, 1] + E[i, 2, 2]
            if tr < min_trace:
                min_trace = tr
    s = 0.0
    for k in range(r.shape[0]):
        v = r[k] * length if rows == 6 and k % 6 >= 3 else r[k]
        s += v * v
    return np.sqrt(s), min_trace


@njit(cache=True, inline="always")
def tip_weights(E, i):
    """``H_tip = (tr(E) I - E)/2`` of closure ``i`` as a 9-tuple, row by row (``H_anchor`` is its transpose).

    The rotation rows of a closure's Jacobian: ``H_tip`` times a leg joint's angular velocity,
    ``H_anchor`` times the platform's (``E``: the closure's rotation error, :func:`closure_residual`).
    """
    t = 0.5 * (E[i, 0, 0] + E[i, 1, 1] + E[i, 2, 2])
    return (
        -0.5 * E[i, 0, 0] + t, -0.5 * E[i, 0, 1], -0.5 * E[i, 0, 2],
        -0.5 * E[i, 1, 0], -0.5 * E[i, 1, 1] + t, -0.5 * E[i, 1, 2],
        -0.5 * E[i, 2, 0], -0.5 * E[i, 2, 1], -0.5 * E[i, 2, 2] + t,
    )  # fmt: skip


@njit(cache=True)
def jacobian(J, leg_cols, ff_cols, colmap, rows, p, E, G):
    """Fill ``G`` (6*rows x n_free): derivative of the residual w.r.t. the free velocities.

    ``colmap[v]`` is the column of velocity index ``v`` in ``G`` or -1 when that joint is held.
    Each closure's column of a velocity is the velocity of the closure's point (the tip for its
    leg's joints, sign +1; the anchor for the platform's, sign -1) and, for 6-row closures,
    ``H_tip`` (the leg's joints) or ``H_anchor = H_tip^T`` (the platform's) times the angular
    velocity (:func:`tip_weights`), in scalars: no array is allocated. The per-leg blocks of
    :mod:`.structured` hold the same numbers.
    """
    for a in range(G.shape[0]):
        for b in range(G.shape[1]):
            G[a, b] = 0.0
    h00 = h01 = h02 = h10 = h11 = h12 = h20 = h21 = h22 = 0.0
    nl = leg_cols.shape[1]
    for i in range(6):
        o = i * rows
        if rows == 6:
            h00, h01, h02, h10, h11, h12, h20, h21, h22 = tip_weights(E, i)
        for k in range(nl + 6):  # the leg's joints at the tip, then the platform's velocity at the anchor
            tip = k < nl
            c = leg_cols[i, k] if tip else ff_cols[k - nl]
            if c < 0 or colmap[c] < 0:
                continue
            col, f, sign = colmap[c], i if tip else 6 + i, 1.0 if tip else -1.0
            wx, wy, wz = J[3, c], J[4, c], J[5, c]
            G[o + 0, col] += sign * (J[0, c] - (p[f, 1] * wz - p[f, 2] * wy))
            G[o + 1, col] += sign * (J[1, c] - (p[f, 2] * wx - p[f, 0] * wz))
            G[o + 2, col] += sign * (J[2, c] - (p[f, 0] * wy - p[f, 1] * wx))
            if rows == 6 and tip:
                G[o + 3, col] += sign * (h00 * wx + h01 * wy + h02 * wz)
                G[o + 4, col] += sign * (h10 * wx + h11 * wy + h12 * wz)
                G[o + 5, col] += sign * (h20 * wx + h21 * wy + h22 * wz)
            elif rows == 6:
                G[o + 3, col] += sign * (h00 * wx + h10 * wy + h20 * wz)
                G[o + 4, col] += sign * (h01 * wx + h11 * wy + h21 * wz)
                G[o + 5, col] += sign * (h02 * wx + h12 * wy + h22 * wz)


@njit(cache=True)
def copied(a):
    """A copy of ``a`` made in compiled code, which keeps the GIL.

    numpy's own copy releases the GIL around its copy loop for some arrays: a (36, 42) array
    (the reduced Jacobian's size on the presets) does, a one-dimensional one of 5000 elements
    did not (numpy 2.4). In a threaded service another thread then takes it, and getting it
    back can cost a scheduler round (milliseconds on a loaded machine) in the middle of a solve.
    """
    return a.copy()


@njit(cache=True, inline="always")
def copy_into(dst, src):
    """``dst[:] = src`` for 1-D arrays of one length, element by element.

    The slice assignment's shape check brings numba's error formatting into the compiled unit:
    about 2 s more to compile on a first run.
    """
    for k in range(dst.shape[0]):
        dst[k] = src[k]


@njit(cache=True)
def scatter_step(x, free_v, dv, max_step, weights):
    """Scatter a Newton step into the full velocity space, limited in size.

    ``dv[free_v] = -x`` (the Newton step in the full velocity space; held entries stay 0),
    scaled down, direction kept, so that no weighted entry ``weights[k] * |x[k]|`` exceeds
    ``max_step`` (rad, or m per length scale: :func:`.solver.velocity_weights`). Returns the
    largest weighted entry of the step, before shortening.
    """
    biggest = 0.0
    for k in range(x.shape[0]):
        biggest = max(biggest, abs(x[k]) * weights[k])
    scale = 1.0 if biggest <= max_step else max_step / biggest
    for k in range(free_v.shape[0]):
        dv[free_v[k]] = -scale * x[k]
    return biggest


@njit(cache=True)
def shift_residual(r, offset, scale, rows, length):
    """``r -= scale * offset`` (a homotopy from a start that does not close); its norm as :func:`closure_residual`'s."""
    s = 0.0
    for k in range(r.shape[0]):
        r[k] -= scale * offset[k]
        v = r[k] * length if rows == 6 and k % 6 >= 3 else r[k]
        s += v * v
    return np.sqrt(s)


@njit(cache=True)
def first_outside(values, lower, upper, slack):
    """Index of the first entry that is NaN/inf or outside ``[lower - slack, upper + slack]``; -1 if none."""
    for k in range(values.shape[0]):
        v = values[k]
        if not (lower[k] - slack <= v <= upper[k] + slack):
            return k
    return -1


@njit(cache=True)
def first_outside_at(q, idx, lower, upper, slack):
    """Like :func:`first_outside` on ``q[idx]``; returns the position in ``idx`` or -1."""
    for k in range(idx.shape[0]):
        v = q[idx[k]]
        if not (lower[k] - slack <= v <= upper[k] + slack):
            return k
    return -1


@njit(cache=True)
def largest_step(joints, guess, idx):
    """``max_k |joints[k] - guess[idx[k]]|`` (m): the held joints' step from the guess; NaN if one is NaN.

    The step a warm solve is proven over or not (the tracker's ``continuation_step``, a batch's
    :data:`~hexapod_model.kinematics.batch.PROOF_STEP`).

    Args:
        joints: (n,) the held joints' values (m).
        guess: the guess configuration.
        idx: (n,) int64, the held joints' configuration indices.
    """
    s = 0.0
    for k in range(idx.shape[0]):
        d = abs(joints[k] - guess[idx[k]])
        if d > s or d != d:
            s = d
        if s != s:
            return s
    return s


@njit(cache=True)
def rigid_error(T):
    """Distance of a 4x4 matrix from a rigid transform.

    How far the 4x4 ``T`` is from a rigid transform: ``max |R^T R - I|``, ``det R - 1``
    and the bottom row, folded into one number (``inf`` for NaN/inf entries).
    """
    err = 0.0
    for a in range(4):
        for b in range(4):
            if not np.isfinite(T[a, b]):
                return np.inf
    for a in range(3):
        for b in range(3):
            s = T[0, a] * T[0, b] + T[1, a] * T[1, b] + T[2, a] * T[2, b]
            err = max(err, abs(s - (1.0 if a == b else 0.0)))
    det = (
        T[0, 0] * (T[1, 1] * T[2, 2] - T[1, 2] * T[2, 1])
        - T[0, 1] * (T[1, 0] * T[2, 2] - T[1, 2] * T[2, 0])
        + T[0, 2] * (T[1, 0] * T[2, 1] - T[1, 1] * T[2, 0])
    )
    err = max(err, abs(det - 1.0))
    err = max(err, abs(T[3, 0]), abs(T[3, 1]), abs(T[3, 2]), abs(T[3, 3] - 1.0))
    return err
