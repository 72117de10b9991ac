"""The whole Newton iteration of the fast path in one compiled call.

For hexapods whose six legs are chains of ``rows`` one-dof joints (6 for ``6d`` closures, 3
for ball joints) and the two structured problems: one joint held per leg, the platform free
(direct kinematics: the Schur elimination of :func:`.structured.schur_solve`), or the platform held
(inverse kinematics: the blocks of :func:`.structured.blocks_solve`). :func:`iterate` is
:meth:`.solver.NewtonSolver.iterate` with Pinocchio replaced by :mod:`.chains`; per iteration:

1. closure frames and WORLD Jacobian columns at ``q`` (:func:`.chains.evaluate_chains`);
2. residual, Bem et al. (2026) eqs. 10-14 (:func:`.kernels.closure_residual`), minus
   ``scale * offset`` on a homotopy path; stop when its norm is at most ``tol`` (a 180-degree
   flipped closure, ``trace(R_tip R_anchor^T) < 1``, is refused; a first step above
   ``one_step`` is followed by a second, to measure a contraction), after ``max_iter`` steps
   or on NaN; a start that closes at once is checked for singularity by one step;
3. Newton step ``G dq = -r`` by the structured solve; singular below ``singular_ratio``
   (smallest / largest pivot); the Schur step also gives the determinant sign and the
   condition bound (``state``);
4. with ``certify``: the step's determinant sign equals the start's, it is not shortened and
   the contraction ``|dx_k+1| / |dx_k|`` stays below ``theta_max`` (the certificate of
   :mod:`.assembly`); otherwise the solve stops, ``UNCERTIFIED``;
5. the step limited to ``max_step`` along its direction (:func:`.kernels.scatter_step`; its size,
   like ``one_step``'s and ``theta_floor``'s, weighted scale-free: the packed step weights) and
   applied on the manifold: ``q_j += dq_j`` for the leg joints, ``M_p <- M_p exp6(v_p)`` for the
   platform (:func:`.lie.integrate_free_flyer`).

The entries called from Python are :func:`solve_schur` and :func:`solve_blocks` (the iteration,
and with ``finish`` the Jacobian, pose and limit check a ``Solution`` needs), four arguments
each: the start, the homotopy offset, the per-call settings and the packed arrays
(:mod:`.packing`); the compiled loops of :mod:`.follow` and :mod:`.batch_kernels` call
:func:`iterate_schur` / :func:`iterate_blocks`. :class:`.compiled.CompiledSolver` is the solver object on top.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .chains import evaluate_chains
from .kernels import (
    closure_residual,
    copy_into,
    first_outside_at,
    jacobian,
    scatter_step,
    shift_residual,
    xyzquat_to_pose,
)
from .lie import integrate_free_flyer
from .outcomes import CONVERGED, FLIPPED, NO_CONVERGENCE, SINGULAR, START_SINGULAR, UNCERTIFIED
from .packing import FHEADER, LENGTH_SCALE, unpack_floats, unpack_ints, unpack_iwork, unpack_work
from .structured import blocks_solve, schur_solve


@njit(cache=True, inline="always")
def _integrate(q, dv, leg_q, leg_v, platform_q, platform_v, Rs, ps, quat):
    """``q <- q (+) dv``: leg joints add their velocity, the platform's free flyer integrates on SE(3)."""
    for i in range(leg_q.shape[0]):
        for k in range(leg_q.shape[1]):
            q[leg_q[i, k]] += dv[leg_v[i, k]]
    v = dv[platform_v[0] : platform_v[0] + 6]
    integrate_free_flyer(q[platform_q : platform_q + 7], v, Rs[0], Rs[1], Rs[2], ps[0], quat)


@njit(cache=True, inline="always")
def _step(schur, rows, held_pos, colmap, leg_v, platform_v, frames, blocks, state, length):
    """Solve ``G x = r`` (Schur elimination or blocks); returns the smallest pivot ratio.

    ``frames = (J, p, E, r, x)``, ``blocks = (LB, PB, A, M, pm, nb, wb)``. The Schur step leaves
    the determinant sign (``-1`` when singular, as the general path) and the condition bound in
    ``state`` (scale-free with the geometry's ``length`` scale).
    """
    J, p, E, r, x = frames
    LB, PB, A, M, pm, nb, wb = blocks
    if schur:
        ratio, kappa = schur_solve(
            J, leg_v, held_pos, platform_v, colmap, rows, p, E, r, x, LB, PB, A, M, pm, nb, wb, length
        )
        state[0], state[1] = (1.0 if ratio > 0.0 else -1.0), kappa
        return abs(ratio)
    return blocks_solve(J, leg_v, colmap, rows, p, E, r, x, LB, PB, wb)


@njit(cache=True, inline="always")
def _iterate(schur, q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork):
    """Newton from ``q0`` into ``q`` (see the module docstring), by the Schur or the block step.

    Returns ``(code, iterations, norm, ratio, theta, sign, certified)``: the outcome code, the
    last residual norm and pivot ratio, the largest contraction, the determinant sign the
    solve kept (``sign``, or the first step's when 0) and whether every check passed.
    """
    rows, platform_q = ints[0], ints[3]
    max_step, singular_ratio, theta_max, theta_floor, one_step = floats[0], floats[1], floats[2], floats[3], floats[4]
    weights = floats[FHEADER : FHEADER + ints[2]]  # the free velocities' step weights (.packing)
    length = floats[LENGTH_SCALE]  # the geometry's length scale
    (leg_q, leg_v, platform_v, held_pos, colmap, free_v, kinds), _ = unpack_ints(ints)
    (placements, motions, closure, home), _ = unpack_floats(ints, floats)
    (oR, op, J, R, p, E, r, x, dv, G, LB, A, M, nb, wb, Rs, ps, quat, state), _ = unpack_work(ints, work)
    (PB, pm), _ = unpack_iwork(ints, iwork)
    frames, blocks = (J, p, E, r, x), (LB, PB, A, M, pm, nb, wb)  # the step's inputs and buffers
    for k in range(q.shape[0]):
        q[k] = q0[k]
    it, ratio, theta, previous, certified = 0, 1.0, 0.0, 0.0, True
    while True:
        evaluate_chains(
            q, placements, kinds, motions, leg_q, leg_v, closure, home, platform_q, platform_v, oR, op, J, R, p
        )
        norm, min_trace = closure_residual(R, p, rows, E, r, length)
        if scale != 0.0:
            norm = shift_residual(r, offset, scale, rows, length)
        if norm <= tol and (it != 1 or previous <= one_step):
            code = CONVERGED
            if min_trace < 1.0:
                code, certified = FLIPPED, False
            elif it == 0:  # no step factored the Jacobian: check the start itself is not singular
                ratio = _step(schur, rows, held_pos, colmap, leg_v, platform_v, frames, blocks, state, length)
                if ratio < singular_ratio:
                    code, certified = START_SINGULAR, False
            break
        if it >= max_iter or not norm < np.inf:  # also stops on NaN
            code = NO_CONVERGENCE
            break
        ratio = _step(schur, rows, held_pos, colmap, leg_v, platform_v, frames, blocks, state, length)
        if ratio < singular_ratio:
            code, certified = SINGULAR, False
            break
        biggest = scatter_step(x, free_v, dv, max_step, weights)
        if certify:
            certified = sign == 0.0 or state[0] == sign  # the sign is only known on the Schur path
            sign = sign if sign != 0.0 else state[0]
            if previous > theta_floor and biggest > theta * previous:
                theta = biggest / previous
            previous = biggest
            if not (certified and biggest <= max_step and theta <= theta_max):
                code, certified = UNCERTIFIED, False
                break
        _integrate(q, dv, leg_q, leg_v, platform_q, platform_v, Rs, ps, quat)
        it += 1
    return code, it, norm, ratio, theta, sign, certified


# For the compiled loops of .follow and .batch_kernels, ``schur`` a constant in each. The loops pass
# ``certify`` read from an array, never as a constant: a constant types as a literal,
# and numba would compile the whole iteration once more per literal value.
@njit(cache=True)
def iterate_schur(q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork):
    """:func:`_iterate` with the Schur step (one joint held per leg, the platform free)."""
    return _iterate(True, q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork)


@njit(cache=True)
def iterate_blocks(q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork):
    """:func:`_iterate` with the block step (the platform held)."""
    return _iterate(False, q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork)


@njit(cache=True, inline="always")
def _solve(schur, start, offset, settings, arrays):
    """:func:`_iterate` from ``start`` (prismatic joints from ``settings`` if given), and a ``Solution``'s arrays.

    ``settings = (tol, max_iter, sign, scale, certify, finish, given, joints...)``
    (:data:`.packing.SETTINGS`); ``arrays = (ints, floats, work, iwork, q_solver, q, pose, G)``:
    the packed tables and buffers, the solver's iterate and the outputs. The iteration runs from
    ``q`` (``start``'s copy) and leaves its last iterate in ``q_solver``, as :func:`_iterate` does.
    With ``finish``, unless a ``certify``-ing solve did not converge certified, it also writes
    the configuration into ``q``, the platform pose ``home * X(q_p)`` into ``pose``, the reduced
    Jacobian (:func:`.kernels.jacobian`) into ``G`` and, when converged, finds the first joint
    outside the packed limits. Returns :func:`_iterate`'s
    tuple and that joint (-1 if none or not looked for).
    """
    ints, floats, work, iwork, q_solver, q, pose, G = arrays
    tol, max_iter, sign, scale = settings[0], settings[1], settings[2], settings[3]  # max_iter: a whole float
    certify, finish = settings[4] != 0.0, settings[5] != 0.0
    # .packing.unpack_constants written out: a called function would compile once more at the first solve
    nl, oc, fc = ints[5], ints[6], ints[7]
    prismatic_q, limited = ints[oc : oc + 6], ints[oc + 6 : oc + 6 + nl]
    lower, upper, slack = floats[fc : fc + nl], floats[fc + nl : fc + 2 * nl], floats[fc + 2 * nl]
    home = floats[fc - 16 : fc].reshape((4, 4))
    for k in range(q.shape[0]):
        q[k] = start[k]
    if settings[6] != 0.0:
        for i in range(prismatic_q.shape[0]):
            q[prismatic_q[i]] = settings[7 + i]
    code, it, norm, ratio, theta, sign, certified = _iterate(
        schur, q, q_solver, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork
    )
    bad = -1
    if finish and (not certify or (code == CONVERGED and certified)):
        (_, leg_v, platform_v, _, colmap, _, _), _ = unpack_ints(ints)
        views = unpack_work(ints, work)[0]
        copy_into(q, q_solver)
        jacobian(views[2], leg_v, platform_v, colmap, ints[0], views[4], views[5], G)
        xyzquat_to_pose(q[ints[3] : ints[3] + 7], home, pose)
        if code == CONVERGED:
            bad = first_outside_at(q, limited, lower, upper, slack)
    return code, it, norm, ratio, theta, sign, certified, bad


# The entry points from Python: one per step, the iteration inlined in each (numba re-optimises
# a called compiled function in every caller's unit, so a second entry would compile it again).
# Four arguments (.packing): numba's dispatch costs per argument unboxed.
@njit(cache=True)
def solve_schur(start, offset, settings, arrays):
    """:func:`_solve` with the Schur step (direct kinematics: the certified first attempt, plain solves)."""
    return _solve(True, start, offset, settings, arrays)


@njit(cache=True)
def solve_blocks(start, offset, settings, arrays):
    """:func:`_solve` with the block step (inverse kinematics)."""
    return _solve(False, start, offset, settings, arrays)
