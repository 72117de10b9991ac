"""The whole Newton iteration of the fast path in one compiled call.

For hexapods whose six legs are chains of ``rows`` one-dof joints (6 for ``6d`` closures, 3
for ball joints) and the two structured problems: one joint held per leg, the platform free
(direct kinematics: the Schur elimination of :func:`.structured.schur_solve`), or the platform held
(inverse kinematics: the blocks of :func:`.structured.blocks_solve`). :func:`_newton` is
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
   :mod:`.certificate`); otherwise the solve stops, ``UNCERTIFIED``;
5. the step limited to ``max_step`` along its direction (:func:`.kernels.scatter_step`; its size,
   like ``one_step``'s and ``theta_floor``'s, weighted scale-free: the packed step weights) and
   applied on the manifold: ``q_j += dq_j`` for the leg joints, ``M_p <- M_p exp6(v_p)`` for the
   platform (:func:`hexapod_model.lie.compiled.integrate_free_flyer`).

The entries called from Python are :func:`solve_schur` and :func:`solve_blocks` (the iteration,
and with ``finish`` the Jacobian, pose and limit check a ``Solution`` needs), four arguments
each: the start, the homotopy offset, the per-call settings and the packed arrays
(:mod:`.packing`); the compiled loops of :mod:`.follow` and :mod:`.batch_kernels` call
:func:`iterate_schur` / :func:`iterate_blocks`. :class:`.compiled.CompiledSolver` is the solver
object on top. Each entry holds the iteration once (:func:`_entries`): numba copies an inlined
function's IR at each call site and compiles a called one into every caller's unit again, so
the first solve after installation compiles what it runs once.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...lie.compiled import integrate_free_flyer, xyzquat_to_pose
from .chains import evaluate_chains
from .kernels import (
    closure_residual,
    copy_into,
    first_outside,
    first_outside_at,
    jacobian,
    scatter_step,
    shift_residual,
)
from .outcomes import CONVERGED, FLIPPED, INVALID_INPUT, NO_CONVERGENCE, SINGULAR, START_SINGULAR, UNCERTIFIED
from .packing import FHEADER, LENGTH_SCALE, unpack
from .structured import blocks_solve, schur_solve
from .views import view


@njit(cache=True, inline="always")
def integrate_configuration(q, dv, leg_q, leg_v, platform_q, platform_v):
    """``q <- q (+) dv``: leg joints add their velocity, the platform's free flyer integrates on SE(3)."""
    for i in range(leg_q.shape[0]):
        for k in range(leg_q.shape[1]):
            q[leg_q[i, k]] += dv[leg_v[i, k]]
    v = dv[platform_v[0] : platform_v[0] + 6]
    integrate_free_flyer(q[platform_q : platform_q + 7], v)


@njit(cache=True, inline="always")
def _newton(schur, q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, tables, frames, buffers, pivots):
    """Newton from ``q0`` into ``q`` (see the module docstring), by the Schur or the block step.

    ``tables``, ``frames``, ``buffers``, ``pivots``: the views of :func:`.packing.unpack` (the
    entry, or the loop that calls it, makes them once). The Schur step leaves the determinant
    sign (``-1`` when singular, as the general path) and the condition bound in ``state``
    (scale-free with the geometry's length scale).

    Returns ``(code, iterations, norm, ratio, theta, sign, certified)``: the outcome code, the
    last residual norm and pivot ratio, the largest contraction, the determinant sign the
    solve kept (``sign``, or the first step's when 0) and whether every check passed.
    """
    rows, platform_q = ints[0], ints[3]
    max_step, singular_ratio, theta_max, theta_floor, one_step = floats[0], floats[1], floats[2], floats[3], floats[4]
    weights = floats[FHEADER : FHEADER + ints[2]]  # the free velocities' step weights (.packing)
    length = floats[LENGTH_SCALE]  # the geometry's length scale
    leg_q, leg_v, platform_v, held_pos, colmap, free_v, kinds = tables
    placements, motions, closure, home = frames
    J, R, p, E, r, x, dv, G, LB, A, M, nb, wb, state = buffers
    PB, pm = pivots
    for k in range(q.shape[0]):
        q[k] = q0[k]
    it, ratio, theta, previous, certified = 0, 1.0, 0.0, 0.0, True
    while True:
        evaluate_chains(q, placements, kinds, motions, leg_q, leg_v, closure, home, platform_q, platform_v, J, R, p)
        norm, min_trace = closure_residual(R, p, rows, E, r, length)
        if scale != 0.0:
            norm = shift_residual(r, offset, scale, rows, length)
        closed = False  # converged at the start: one step checks the start itself is not singular
        if norm <= tol and (it != 1 or previous <= one_step):
            code = CONVERGED
            if min_trace < 1.0:
                code, certified = FLIPPED, False
                break
            if it != 0:
                break
            closed = True
        elif it >= max_iter or not norm < np.inf:  # also stops on NaN
            code = NO_CONVERGENCE
            break
        # the step G x = r: one call site, so that the step compiles once in each entry
        if schur:
            ratio, kappa = schur_solve(
                J, leg_v, held_pos, platform_v, colmap, rows, p, E, r, x, LB, PB, A, M, pm, nb, wb, length
            )
            state[0], state[1] = (1.0 if ratio > 0.0 else -1.0), kappa
            ratio = abs(ratio)
        else:
            ratio = blocks_solve(J, leg_v, colmap, rows, p, E, r, x, LB, PB, wb)
        if ratio < singular_ratio:
            code, certified = (START_SINGULAR if closed else SINGULAR), False
            break
        if closed:
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
        integrate_configuration(q, dv, leg_q, leg_v, platform_q, platform_v)
        it += 1
    return code, it, norm, ratio, theta, sign, certified


def _entries(schur: bool, step: str) -> tuple:
    """The two compiled entries of one step (``schur``: the Schur step, else the blocks), named for ``step``.

    Each entry holds the iteration once (:func:`_newton`, inlined); ``schur`` is a constant of the
    entry, so the other step's branch is pruned before it is typed. Written once here rather than
    as two functions inlining a shared one: numba's inlining copies the inlined function's IR,
    and an inlined function that itself inlines the iteration doubled the copies on a first run.
    """

    def iterate(q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, views):
        tables, frames, buffers, pivots = views
        return _newton(
            schur, q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, tables, frames, buffers, pivots
        )

    def solve(start, offset, settings, arrays):
        ints, floats, work, iwork, q_solver, q, pose, G = arrays
        tol, max_iter, sign, scale = settings[0], settings[1], settings[2], settings[3]  # max_iter: a whole float
        certify, finish = settings[4] != 0.0, settings[5] != 0.0
        # .packing.unpack_constants written out: a called function would compile once more at the first solve
        nl, oc, fc = ints[5], ints[6], ints[7]
        prismatic_q, limited = ints[oc : oc + 6], ints[oc + 6 : oc + 6 + nl]
        lower, upper, slack = floats[fc : fc + nl], floats[fc + nl : fc + 2 * nl], floats[fc + 2 * nl]
        home = view(floats, fc - 16, (4, 4))
        given = settings[6]
        if given == 2.0:  # the readings are `offset`: outside the stroke (or NaN), no solve
            k = first_outside(offset, settings[13:19], settings[19:25], settings[25])
            if k >= 0:
                return INVALID_INPUT, 0, np.nan, np.nan, 0.0, 0.0, False, k
        for k in range(q.shape[0]):
            q[k] = start[k]
        if given == 2.0:
            for i in range(prismatic_q.shape[0]):
                q[prismatic_q[i]] = offset[i]
        elif given != 0.0:
            for i in range(prismatic_q.shape[0]):
                q[prismatic_q[i]] = settings[7 + i]
        tables, frames, buffers, pivots = unpack(ints, floats, work, iwork)
        code, it, norm, ratio, theta, sign, certified = _newton(
            schur,
            q,
            q_solver,
            tol,
            max_iter,
            sign,
            offset,
            scale,
            certify,
            ints,
            floats,
            tables,
            frames,
            buffers,
            pivots,
        )
        bad = -1
        if finish and (not certify or (code == CONVERGED and certified)):
            copy_into(q, q_solver)
            J, p, E = buffers[0], buffers[2], buffers[3]
            jacobian(J, tables[1], tables[2], tables[4], ints[0], p, E, G)
            xyzquat_to_pose(q[ints[3] : ints[3] + 7], home, pose)
            if code == CONVERGED:
                bad = first_outside_at(q, limited, lower, upper, slack)
        return code, it, norm, ratio, theta, sign, certified, bad

    iterate.__doc__ = f""":func:`_newton` with the {step}.

    For the compiled loops of :mod:`.follow` and :mod:`.batch_kernels`: ``views`` are
    :func:`.packing.unpack`'s views of the solver's arrays ``(ints, floats, work, iwork)``, made
    once by the loop (in each call they would cost a tenth of a warm solve).

    The loops pass ``certify`` read from an array, never as a constant: a constant types as a
    literal, and numba would compile the whole iteration once more per literal value.
    """
    solve.__doc__ = f""":func:`_newton` with the {step} from ``start``, and a ``Solution``'s arrays.

    The prismatic joints are set from ``settings`` if given.

    ``settings = (tol, max_iter, sign, scale, certify, finish, given, joints...)``
    (:data:`.packing.SETTINGS`; with ``given`` 2 the joints are ``offset``, six readings checked
    against the stroke bounds that follow in ``settings``: one outside, or NaN, returns
    ``INVALID_INPUT`` and its index, with no solve); ``arrays = (ints, floats, work, iwork, q_solver, q, pose, G)``:
    the packed tables and buffers, the solver's iterate and the outputs. The iteration runs from
    ``q`` (``start``'s copy) and leaves its last iterate in ``q_solver``. With ``finish``, unless
    a ``certify``-ing solve did not converge certified, it also writes the configuration into
    ``q``, the platform pose ``home * X(q_p)`` into ``pose``, the reduced Jacobian
    (:func:`.kernels.jacobian`) into ``G`` and, when converged, finds the first joint outside the
    packed limits. Returns :func:`_newton`'s tuple and that joint (-1 if none or not looked for).
    """
    name = "schur" if schur else "blocks"
    for fn, prefix in ((iterate, "iterate_"), (solve, "solve_")):
        fn.__name__ = fn.__qualname__ = prefix + name  # numba's cache files are named by the qualified name
    return njit(cache=True)(iterate), njit(cache=True)(solve)


# The entry points: one per step, the iteration inlined in each (numba re-optimises a called
# compiled function in every caller's unit, so a second entry would compile it again). The
# solves take four arguments (.packing): numba's dispatch costs per argument unboxed.
iterate_schur, solve_schur = _entries(True, "Schur step (one joint held per leg, the platform free: direct kinematics)")
iterate_blocks, solve_blocks = _entries(False, "block step (the platform held: inverse kinematics)")
