"""Compiled loops over rows of readings or poses for the batch solves.

Per row: the input checks, the Newton iteration (:func:`.newton.iterate`) and the joint-limit
check of :meth:`.hexapod.Hexapod.forward` / :meth:`~.hexapod.Hexapod.inverse`. Direct kinematics
runs :func:`.certificate.solve_forward`: the certified first attempt, then, for a row it does not
settle, the readings path (:func:`.follow.follow_in`, :func:`_follow_row`). A row whose path is
blocked (the candidates of an ambiguous assembly are looked for in Python), whose warm plain
result is uncertified near a singularity, or whose warm result converged near a singularity
(``converged`` then only with the Krawczyk proof of its step, :meth:`.engine.SolveEngine.proven_near`)
ends the loop, and the caller solves that row with ``forward`` before resuming at the next one.

Each row starts from ``start`` with determinant sign ``carry[0]`` (home or a guess); with
``warm`` from the last row that converged instead (a time series, as ``hexapod fk`` reads its
rows), ``start`` and ``carry`` being updated in place (``carry[1] = 1`` once they were;
``carry[2] = 1`` when the start is a guess: ``forward``'s warm solve). Per
row the loops write ``out = (Q, poses, codes, iterations, residuals, ratios, kappas, signs,
bad)``: the final configuration, the platform pose (NaN unless converged), an outcome code
(:mod:`.newton`'s, :data:`OUT_OF_LIMITS`, :data:`INVALID_INPUT`), iterations, residual norm,
last pivot ratio, condition bound of the last Schur step, determinant sign reported, and the
configuration index of the first joint outside its limits (-1 if none).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...lie.compiled import pose_to_xyzquat, xyzquat_to_pose
from .follow import closure_norm, follow_buffers, follow_in, rescale
from .iteration import iterate_blocks, iterate_schur
from .kernels import BOOLEANS, copy_into, first_outside, first_outside_at, rigid_error
from .outcomes import CONVERGED, INVALID_INPUT, NO_CONVERGENCE, OUT_OF_LIMITS
from .packing import WORK_STATE, unpack, unpack_constants


@njit(cache=True, inline="always")
def _finish_row(k, q, code, it, norm, ratio, kappa, sign, platform_q, constants, out):
    """The packed limit check and the outputs of row ``k`` (``constants``: :func:`.packing.unpack_constants`'s)."""
    _, limited, lo, hi, slack, home = constants
    Q, poses, codes, iterations, residuals, ratios, kappas, signs, bad = out
    bad[k] = -1
    if code == CONVERGED:
        b = first_outside_at(q, limited, lo, hi, slack)
        if b >= 0:
            code, bad[k] = OUT_OF_LIMITS, limited[b]
    codes[k], iterations[k], residuals[k], ratios[k], kappas[k], signs[k] = code, it, norm, ratio, kappa, sign
    copy_into(Q[k], q)
    if code == CONVERGED:
        xyzquat_to_pose(q[platform_q : platform_q + 7], home, poses[k])
    else:
        poses[k] = np.nan
    return code


@njit(cache=True, inline="always")
def _invalid_row(k, out):
    """Outputs of row ``k`` rejected before solving (NaN, out of stroke, not a rigid transform)."""
    Q, poses, codes, iterations, residuals, ratios, kappas, signs, bad = out
    codes[k], iterations[k], residuals[k], ratios[k], kappas[k], signs[k], bad[k] = (
        INVALID_INPUT,
        0,
        np.nan,
        0,
        0,
        0,
        -1,
    )
    Q[k] = np.nan
    poses[k] = np.nan


@njit(cache=True, inline="always")
def _follow_row(
    q0, q, start, closes, target, attempt, tol, max_iter, sign, guessed, near_kappa, packed, views, buffers
):
    """The rest of :func:`.certificate.solve_forward` after a failed certified attempt from ``q0``.

    ``attempt = (iterations, theta)`` of that attempt, whose last iterate is in ``q``;
    ``start`` holds the start's own readings, ``closes`` its closure residual norm (NaN: not
    known). From a guess (``guessed``), first the plain uncertified solve (a result near a
    singularity is left to the caller), then the path from ``start``. ``views``: :func:`.packing.unpack`'s
    of ``packed``; ``buffers``:
    :func:`.follow.follow_buffers` and two more configurations. Returns ``(done, iterations,
    residual)``: done when the path reached its end (in ``q``).
    """
    ints, floats = packed[0], packed[1]
    state = views[2][WORK_STATE]
    it, theta = attempt
    path, first, x = buffers
    copy_into(first, q)  # the first Newton iterate when the attempt took one step
    if guessed:  # near a singularity no path certifies: forward() returns the plain result, flagged
        no = BOOLEANS[0]  # a plain False: one compiled signature of iterate_schur
        code, n, _, _, theta, _, _ = iterate_schur(
            q0, q, tol, max_iter, 0.0, np.zeros(6 * ints[0]), 0.0, no, ints, floats, views
        )
        it += n
        if code == CONVERGED and not state[1] <= near_kappa:
            return False, it, 0.0
    h = rescale(theta, False, 1)
    t, it, norm = follow_in(
        start, closes, target, first, attempt[0] == 1, tol, max_iter, sign, it, h, packed, views, x, q, path
    )
    return t == 1.0, it, norm


@njit(cache=True)
def forward_rows(k0, readings, joints, start, carry, warm, settings, stroke, packed, out):
    """Direct kinematics of rows ``k0:`` of ``readings`` (N, 6) (``joints``: their prismatic values).

    ``settings = (tol, max_iter, near_singular_kappa)``; ``stroke = (lower, upper)`` of the
    readings; ``packed``: the solver's :class:`.packing.Packed` arrays (with the prismatic joints
    and the joint limits). Returns the first row left to the caller (the certified attempt
    failed, or a warm row converged near a singularity), or N.
    """
    tol, max_iter, near_kappa = settings
    ints, floats, work, iwork = packed
    constants = unpack_constants(ints, floats)[0]  # once, as the views
    prismatic_q, slack = constants[0], constants[4]
    views = unpack(ints, floats, work, iwork)  # once: each iteration's call takes them
    state = views[2][WORK_STATE]  # the last Schur step's sign and condition bound
    q0, q, no_offset = start.copy(), start.copy(), np.zeros(6 * ints[0])
    yes = BOOLEANS[1]  # a plain True: one compiled signature of iterate_schur
    nq = start.shape[0]
    buffers = (follow_buffers(nq, ints[1], 6 * ints[0]), np.empty(nq), np.empty(nq))
    closes = np.nan  # the start's closure residual norm: evaluated when a row first follows the path
    for k in range(k0, readings.shape[0]):
        if first_outside(readings[k], stroke[0], stroke[1], slack) >= 0:  # NaN, inf or out of stroke
            _invalid_row(k, out)
            continue
        copy_into(q0, start)
        for i in range(prismatic_q.shape[0]):
            q0[prismatic_q[i]] = joints[k, i]
        code, it, norm, ratio, theta, sign, certified = iterate_schur(
            q0, q, tol, max_iter, carry[0], no_offset, 0.0, yes, ints, floats, views
        )
        if not certified or (code != CONVERGED and code != NO_CONVERGENCE):  # follow the readings path
            attempt, guessed = (it, theta), carry[1] == 1.0 or carry[2] == 1.0
            if not closes == closes:  # NaN: the start's own residual, once while it stays the start
                closes = closure_norm(start, ints, floats, work)
            done, it, norm = _follow_row(
                q0,
                q,
                start,
                closes,
                joints[k],
                attempt,
                tol,
                max_iter,
                carry[0],
                guessed,
                near_kappa,
                packed,
                views,
                buffers,
            )
            if not done:
                return k  # blocked (the candidates) or uncertified near a singularity: forward() solves it
            code, ratio = CONVERGED, 1.0
        kappa, sign = (state[1], state[0]) if code == CONVERGED else (np.inf, 0.0)
        code = _finish_row(k, q, code, it, norm, ratio, kappa, sign, ints[3], constants, out)
        if code == CONVERGED and (carry[1] == 1.0 or carry[2] == 1.0) and not kappa <= near_kappa:
            return k  # warm and near a singularity: converged only with its proof, which forward() runs
        if warm and code == CONVERGED:
            copy_into(start, q)
            carry[0], carry[1] = sign, 1.0
            closes = norm  # the row's last evaluation was at q
    return readings.shape[0]


@njit(cache=True)
def inverse_rows(targets, start, warm, settings, packed, out):
    """Inverse kinematics of every pose of ``targets`` (N, 4, 4); arguments as :func:`forward_rows`.

    ``settings = (tol, max_iter, pose_tolerance, max_position)``: a row whose matrix is not a
    rigid transform within ``pose_tolerance`` (NaN, inf) or lies farther than ``max_position``
    is rejected. ``poses[k]`` is the pose of the final configuration, as ``Solution.pose``.
    """
    tol, max_iter, pose_tolerance, max_position = settings
    ints, floats, work, iwork = packed
    platform_q, constants = ints[3], unpack_constants(ints, floats)[0]
    home = constants[5]
    views = unpack(ints, floats, work, iwork)  # once: each iteration's call takes them
    q0, q, no_offset = start.copy(), start.copy(), np.zeros(6 * ints[0])
    for k in range(targets.shape[0]):
        T = targets[k]
        far = abs(T[0, 3]) > max_position or abs(T[1, 3]) > max_position or abs(T[2, 3]) > max_position
        if not rigid_error(T) <= pose_tolerance or far:
            _invalid_row(k, out)
            continue
        copy_into(q0, start)
        pose_to_xyzquat(T, home, q0[platform_q : platform_q + 7])
        code, it, norm, ratio, _, _, _ = iterate_blocks(
            q0, q, tol, max_iter, 0.0, no_offset, 0.0, False, ints, floats, views
        )
        code = _finish_row(k, q, code, it, norm, ratio, np.inf, 0.0, platform_q, constants, out)
        if warm and code == CONVERGED:
            copy_into(start, q)
