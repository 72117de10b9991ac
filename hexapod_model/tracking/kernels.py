"""Compiled per-sample arithmetic of the stream tracker: reading statistics, motion model, branch residual.

None of it releases the interpreter lock, as NumPy's ``dot`` would (:func:`motion_readings`).

:func:`begin_sample` is what the tracker does before it solves, in one call: the motion model's
readings, the reading statistics that replace a dozen NumPy calls on 6-vectors (finite
readings, frozen runs, normalised innovations, their maximum and sum of squares; the same
floating-point operations, held to NumPy's by a test), the readings ring of the stuck test and
the observed noise scale. :func:`push_trusted` puts a trusted sample first in the motion
model's histories.

The branch check (:meth:`hexapod_model.tracking.tracker.Tracker._branch_check`) compares the
solved platform pose with the motion model's pose plus the reading innovation mapped through
``J^-1``. Only the platform's free-flyer joint enters that comparison, so instead of five
Pinocchio ``difference`` calls, an ``integrate`` and a sixth ``difference`` on the whole
configuration (each a Python call on small arrays), :func:`branch_residual` computes it on the
free-flyer coordinates ``[x, y, z, qx, qy, qz, qw]`` (Pinocchio's order) with the same
formulas Pinocchio's free-flyer joint uses:

* ``difference(q0, q1) = log6(M0^-1 M1)`` (platform frame, ``[v; w]``),
* ``integrate(q0, xi) = M0 exp6(xi)``,
* the motion model's pose ``Mm = M0 exp6(sum_j w_j log6(M0^-1 Mj))`` (``w`` the motion
  model's weights, newest first; :mod:`~hexapod_model.tracking.reading_tests`),
* the residual ``e = log6(Mm^-1 Ms) - J^-1 (l - l^)``.

Rotations are handled as unit quaternions (:mod:`hexapod_model.lie.compiled_quaternion`). The
results agree with Pinocchio's to rounding (a test checks 1e-12), not to the bit: the tracker
uses them only to judge the pose, never as a pose or a Newton guess.

:func:`predict_into` is the predictor's ``pin.integrate(q0, a1 pin.difference(q0, q1) + a2
pin.difference(q0, q2))`` on a model of one-dof joints and one free flyer (the platform), with
the matrix formulas of :mod:`hexapod_model.lie.compiled` (as the compiled readings path's
predictor): the Newton guess of the next sample, to rounding of Pinocchio's (a test checks).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..lie.compiled import difference_free_flyer, integrate_free_flyer
from ..lie.compiled_quaternion import exp6_quat, log6_quat, quat_mul, quat_rotate, relative_free_flyer


@njit(cache=True)
def branch_residual(F, n, w, fs, Jinv, l, lhat, e):
    """The branch check's residual ``e`` (6,) of the solved pose ``fs`` against the motion model.

    Args:
        F: (>= n, 7) free-flyer coordinates of the trusted history, newest first.
        n: trusted samples in the motion model (``w.size``).
        w: (n,) the motion model's weights (newest first; they sum to 1).
        fs: (7,) free-flyer coordinates of the solved configuration.
        Jinv: (6, 6) inverse of the eliminated Jacobian at the solved configuration.
        l: (6,) the readings.
        lhat: (6,) the motion model's readings.
        e: (6,) out: ``log6(Mm^-1 Ms) - Jinv (l - lhat)``, ``Mm`` the motion model's pose.

    Returns:
        ``(|e[:3]|, |e[3:]|)``: the Euclidean norms of the residual's translation (m) and
        rotation (rad) parts.
    """
    p, q, xi = np.empty(3), np.empty(4), np.empty(6)
    dv = np.zeros(6)
    for j in range(1, n):  # sum_j w_j log6(M0^-1 Mj)
        relative_free_flyer(F[0], F[j], p, q)
        log6_quat(p, q, xi)
        for i in range(6):
            dv[i] += w[j] * xi[i]
    exp6_quat(dv, p, q)  # Mm = M0 exp6(dv)
    fm = np.empty(7)
    quat_rotate(F[0, 3:], p, fm[:3], False)
    for i in range(3):
        fm[i] += F[0, i]
    quat_mul(F[0, 3:], q, fm[3:])
    relative_free_flyer(fm, fs, p, q)  # Mm^-1 Ms
    log6_quat(p, q, xi)
    for i in range(6):
        s = 0.0
        for k in range(6):
            s += Jinv[i, k] * (l[k] - lhat[k])
        e[i] = xi[i] - s
    return math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]), math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5])


@njit(cache=True)
def motion_readings(w, L, lhat):
    """The motion model's readings ``lhat = w @ L[:n]`` (``n = w.size``), written into ``lhat``.

    In compiled code because NumPy's ``ndarray.dot`` hands this product to BLAS and releases
    the interpreter lock around it (``@`` does not, at more dispatch): with another thread of the
    process waiting for the lock, each release wakes it, and the tracker's step costs a fifth more.

    Args:
        w: (n,) the motion model's weights (newest first).
        L: (>= n, 6) readings of the trusted samples, newest first (m).
        lhat: (6,) out: the weighted readings (m).
    """
    for k in range(6):
        s = 0.0
        for j in range(w.size):
            s += w[j] * L[j, k]
        lhat[k] = s


#: the layout of :func:`begin_sample`'s ``scalars``: what the sample's statistics read, then the noise scale it updates
SCALARS = ("stuck_tolerance", "innovation_sigma", "jump_sigmas", "scale_rate", "scale_floor", "z2", "scale")
_TOLERANCE, _SIGMA, _JUMP, _RATE, _FLOOR, _Z2, _SCALE = range(len(SCALARS))  # their indices


@njit(cache=True)
def begin_sample(l, ring, ring_state, frozen, stuck, w, L, lhat, z, scalars):
    """A sample's reading statistics, its entry in the readings ring and the observed noise scale, in one call.

    What :meth:`~hexapod_model.tracking.tracker.Tracker.step` does before it solves: the motion
    model's readings (:func:`motion_readings`, when the sample is checked), the reading
    statistics against the ring's newest readings (:func:`_checks`), then, for finite readings, the
    readings pushed into the ring and, for a sample within ``jump_sigmas``, the observed noise
    scale updated (``z2 += scale_rate (min(z . z / 6, 1) - z2)``, ``scale = max(sqrt(z2),
    scale_floor)``). The same floating-point operations as those steps one by one.

    Args:
        l: (6,) the readings (m).
        ring: (m, 6) the readings kept (m), a ring: updated in place.
        ring_state: (2,) int64, the newest row and how many rows are kept: updated in place.
        frozen: (6,) int64, consecutive unchanged samples per leg: updated in place.
        stuck: (6,) bool, the legs latched ``stuck``.
        w: (n,) the motion model's weights, newest first; (0,) when the sample is not checked.
        L: (>= n, 6) readings of the trusted samples, newest first (m).
        lhat: (6,) out: the motion model's readings (m), written when the sample is checked.
        z: (6,) out: ``|l - lhat| / innovation_sigma``, written when the sample is checked.
        scalars: float64, the values :data:`SCALARS` names; ``z2`` and ``scale`` are updated in place.

    Returns:
        ``(finite, zmax, zz, frozen_max, any_stuck)``: every reading finite (when not, nothing
        else is computed or updated), the largest ``z`` and ``z . z`` (``nan`` and 0 when not
        checked), the longest frozen run and whether a leg is latched ``stuck``.
    """
    checked = w.size > 0
    if checked:
        motion_readings(w, L, lhat)
    at, count = ring_state[0], ring_state[1]
    finite, zmax, zz, fmax, any_stuck = _checks(
        l, ring[at], count > 0, scalars[_TOLERANCE], frozen, stuck, lhat, checked, scalars[_SIGMA], z
    )
    if not finite:
        return finite, zmax, zz, fmax, any_stuck
    m = ring.shape[0]
    if count:
        at = (at + 1) % m
    for k in range(6):
        ring[at, k] = l[k]
    ring_state[0], ring_state[1] = at, min(count + 1, m)
    if zmax <= scalars[_JUMP]:  # the observed noise scale, for the branch check (False for NaN)
        z2 = scalars[_Z2]
        z2 += scalars[_RATE] * (min(zz / 6.0, 1.0) - z2)
        scalars[_Z2], scalars[_SCALE] = z2, max(math.sqrt(z2), scalars[_FLOOR])
    return finite, zmax, zz, fmax, any_stuck


@njit(cache=True)
def _checks(l, last, has_last, tol, frozen, stuck, lhat, checked, sd, z):
    """One sample's reading statistics (:func:`begin_sample`'s).

    Args:
        l: (6,) the readings (m).
        last: (6,) the previous sample's readings (read when ``has_last``).
        has_last: whether there is a previous sample.
        tol: largest change (m) that counts as unchanged (``stuck_tolerance``).
        frozen: (6,) int64, consecutive unchanged samples per leg: updated in place.
        stuck: (6,) bool, the legs latched ``stuck``.
        lhat: (6,) the motion model's readings (read when ``checked``).
        checked: whether the sample is checked against the motion model.
        sd: innovation standard deviation (m): ``noise * spread``.
        z: (6,) out: ``|l - lhat| / sd`` (untouched when not checked).

    Returns:
        ``(finite, zmax, zz, frozen_max, any_stuck)``: every reading finite (when not, nothing
        else is computed or updated), the largest ``z`` and ``z . z`` (``nan`` and 0 when not
        checked), the longest frozen run and whether a leg is latched ``stuck``.
    """
    for k in range(6):
        if not math.isfinite(l[k]):
            return False, math.nan, 0.0, 0, False
    if has_last:  # frozen[k] + 1 where |l - last| <= tol, else 0
        for k in range(6):
            frozen[k] = frozen[k] + 1 if abs(l[k] - last[k]) <= tol else 0
    zmax, zz = math.nan, 0.0
    if checked:
        zmax = -math.inf
        for k in range(6):
            z[k] = abs(l[k] - lhat[k]) / sd
            zmax = max(zmax, z[k])
            zz += z[k] * z[k]
    fmax, any_stuck = 0, False
    for k in range(6):
        fmax = max(fmax, frozen[k])
        any_stuck = any_stuck or stuck[k]
    return True, zmax, zz, fmax, any_stuck


@njit(cache=True)
def stuck_checks(ring, count, newest, frozen, z, stuck, first_run, run, bounds, moving, moved):
    """The stuck and jump tests of a sample whose readings froze, jumped or hold a latched leg.

    :func:`~hexapod_model.tracking.reading_tests.stuck_legs` with its inputs
    (:func:`~hexapod_model.tracking.reading_tests.motion_sigmas`, the other legs' largest change
    over each leg's frozen run) in one call, with no array made: a fixture at rest whose
    encoders repeat counts runs it at nearly every sample.

    Args:
        ring: (m, 6) the readings kept (m), a ring: the newest in row ``newest``, ``count`` of them.
        count: readings kept (the sample's own included), at most ``m``.
        newest: the newest's row.
        frozen: (6,) int64, consecutive unchanged samples per leg.
        z: (6,) normalised innovations (NaN when the sample is not checked).
        stuck: (6,) bool, the legs latched ``stuck``: updated in place (latched while unchanged).
        first_run: unchanged samples before a leg's own innovation can make it stuck (``frozen_run``
            with encoder counts, else 1).
        run: unchanged samples before the other legs' motion can (``frozen_run``).
        bounds: (6,) ``stuck_samples``, ``stuck_sigmas``, the other legs' change that is motion (m),
            ``stuck_motion_sigmas``, ``jump_sigmas``, the readings' sigma (m).
        moving: (6,) work: each leg's :func:`motion_sigmas`.
        moved: (6,) work: the other legs' largest change over each leg's frozen run (m).

    Returns:
        ``(jumped, stuck_any, legs)``: a leg's innovation above ``jump_sigmas``, a leg stuck, and
        the legs named (jump or stuck) as bits (leg ``i``: ``1 << i``).
    """
    stuck_samples, stuck_sigmas, moved_bound, motion_bound, jump_sigmas, sigma = (
        bounds[0],
        bounds[1],
        bounds[2],
        bounds[3],
        bounds[4],
        bounds[5],
    )
    m = ring.shape[0]
    fmax = 0
    for i in range(6):
        fmax = max(fmax, frozen[i])
    use_moving = fmax >= stuck_samples
    if use_moving:  # motion_sigmas: each other leg's least-squares rate over the readings kept, in sigmas
        for j in range(6):
            moving[j] = 0.0
        if count >= 3:
            half = (count - 1) / 2.0
            tt = 0.0
            for k in range(count):
                tt += (k - half) * (k - half)
            for j in range(6):
                s = 0.0
                for k in range(count):  # oldest first
                    s += (k - half) * ring[(newest - count + 1 + k) % m, j]
                moved[j] = abs(s) / (sigma * math.sqrt(tt))
            for i in range(6):
                best = -math.inf
                for j in range(6):
                    if j != i:
                        best = max(best, moved[j])
                moving[i] = best
    for i in range(6):  # the other legs' largest change over each leg's frozen run
        moved[i] = 0.0
        if frozen[i] >= stuck_samples:
            back = min(frozen[i], count - 1)
            older = (newest - back) % m
            for j in range(6):
                if j != i:
                    moved[i] = max(moved[i], abs(ring[newest, j] - ring[older, j]))
    jumped, stuck_any, legs = False, False, 0
    for i in range(6):
        evidence = moved[i] > moved_bound or (use_moving and moving[i] > motion_bound)
        now = (
            (frozen[i] >= first_run and z[i] > stuck_sigmas)  # False for a NaN innovation
            or (frozen[i] >= run and evidence)
            or (stuck[i] and frozen[i] > 0)
        )
        stuck[i] = now
        jump = z[i] > jump_sigmas
        jumped = jumped or jump
        stuck_any = stuck_any or now
        if jump or now:
            legs |= 1 << i
    return jumped, stuck_any, legs


@njit(cache=True)
def push_trusted(q, ffq, prismatic_q, F, L, f_top, l_top, replace):
    """Put a trusted configuration first in the tracker's histories; returns their windows' new first rows.

    ``F`` holds the platform's free-flyer coordinates and ``L`` the readings of the trusted
    samples, each in a buffer twice as tall as its window (``w`` rows, newest first, from the
    window's first row): a push writes the row above the window, and only when the buffer's
    first row is reached is the window copied back to the bottom half (one copy every ``w``
    pushes instead of one per push).

    Args:
        q: the configuration.
        ffq: index of the platform's first free-flyer coordinate in ``q``.
        prismatic_q: (6,) int64, the prismatic joints' indices in ``q`` (the readings, m).
        F: (2 w, 7) the free-flyer coordinates' buffer.
        L: (2 w, 6) the readings' buffer.
        f_top: the first row of ``F``'s window.
        l_top: the first row of ``L``'s window.
        replace: overwrite ``F``'s newest row instead of pushing one (the first trusted sample
            replaces the start of the history); ``L`` is pushed either way.

    Returns:
        ``(f_top, l_top)``: the windows' first rows.
    """
    if not replace:
        f_top = _push_row(F, f_top)
    for i in range(7):
        F[f_top, i] = q[ffq + i]
    l_top = _push_row(L, l_top)
    for i in range(prismatic_q.shape[0]):
        L[l_top, i] = q[prismatic_q[i]]
    return f_top, l_top


@njit(cache=True)
def _push_row(buf, top):
    """The first row of ``buf``'s window after a push (the window copied back to the bottom half at the top)."""
    window = buf.shape[0] // 2
    if top == 0:
        for r in range(window):
            for c in range(buf.shape[1]):
                buf[window + r, c] = buf[r, c]
        top = window
    return top - 1


@njit(cache=True)
def _difference_into(q0, q1, q_idx, v_idx, ffq, ffv, dv, R0, R1, Rd, pd):
    """``dv = q1 (-) q0``: the one-dof joints subtract, the free flyer by ``log6(M0^-1 M1)``."""
    for k in range(q_idx.shape[0]):
        dv[v_idx[k]] = q1[q_idx[k]] - q0[q_idx[k]]
    difference_free_flyer(q0[ffq : ffq + 7], q1[ffq : ffq + 7], dv[ffv : ffv + 6], R0, R1, Rd, pd)


@njit(cache=True)
def predict_into(q0, q1, a1, q2, a2, layout, out, work):
    """``out = q0 (+) (a1 (q1 (-) q0) + a2 (q2 (-) q0))``, the second term only when ``a2 != 0``.

    Args:
        q0: the newest configuration (nq,).
        q1: an earlier one, weighted ``a1``.
        a1: its weight (nonzero).
        q2: another, weighted ``a2``.
        a2: its weight (0: no second term).
        layout: ``(q_idx, v_idx, ffq, ffv)``: the one-dof joints' configuration and velocity
            indices (int64 arrays), the free flyer's first configuration and velocity index.
        out: (nq,) written.
        work: ``(dv, d2, R0, R1, Rd, pd)``: (nv,), (nv,), 3 x (3, 3), (3,) scratch.
    """
    q_idx, v_idx, ffq, ffv = layout
    dv, d2, R0, R1, Rd, pd = work
    _difference_into(q0, q1, q_idx, v_idx, ffq, ffv, dv, R0, R1, Rd, pd)
    for i in range(dv.shape[0]):
        dv[i] = dv[i] * a1 + 0.0  # -0.0 becomes +0.0, as the NumPy path's "+= 0.0"
    if a2 != 0.0:
        _difference_into(q0, q2, q_idx, v_idx, ffq, ffv, d2, R0, R1, Rd, pd)
        for i in range(dv.shape[0]):
            dv[i] += d2[i] * a2
    for i in range(out.shape[0]):
        out[i] = q0[i]
    for k in range(q_idx.shape[0]):
        out[q_idx[k]] += dv[v_idx[k]]
    integrate_free_flyer(out[ffq : ffq + 7], dv[ffv : ffv + 6])
