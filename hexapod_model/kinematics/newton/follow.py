"""The readings path of :mod:`.certificate`, followed in compiled code.

:func:`follow` is :func:`.certificate._follow` on the compiled path (:mod:`.newton`): the path of
solutions for the readings ``l(t) = l0 + t (l - l0)`` from the start, in substeps, each accepted
only when its certified Newton corrector (:func:`.newton.iterate_schur` with ``certify``)
converges: no shortened step (``MAX_STEP``), every contraction at most ``THETA_MAX``, the
determinant sign kept. Same rules as the Python follower:

* substep ``h`` from :func:`rescale` (aim at ``0.8 THETA_MAX``), no sliver of a last substep
  (``t + 1.2 h >= 1`` goes to 1), down to ``MIN_STEP`` and at most ``MAX_SUBSTEPS``;
* predictor: the secant of the last two path points, or the plain attempt's first Newton step
  before the first accepted substep (``pin.interpolate`` / ``pin.integrate`` on the manifold:
  leg joints add, the platform's free flyer moves by ``exp6`` of ``log6``, :mod:`hexapod_model.lie.compiled`);
* closure residual ``INTERMEDIATE_TOL`` (times the geometry's length scale, packed) before the
  last substep; a start that does not close at its own readings follows ``r - (1 - t) r_start``.

What the path's end leaves is the caller's: a certified end (``t == 1``, the solver's buffers
hold the last Schur step) or the last certified point ``x`` at ``t < 1``, where
:func:`.certificate._ambiguous` looks for candidates (rare rows, in Python).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...lie.compiled import difference_free_flyer
from . import path_rules
from .chains import evaluate_chains
from .iteration import CONVERGED, integrate_configuration, iterate_schur
from .kernels import BOOLEANS, closure_residual, copy_into
from .packing import LENGTH_SCALE, WORK_R, unpack, unpack_constants, unpack_floats, unpack_ints, unpack_work
from .path_rules import INTERMEDIATE_TOL, MAX_SUBSTEPS, MIN_STEP

rescale = njit(cache=True)(path_rules.rescale)  # the Python follower's rule, compiled


@njit(cache=True)
def _difference(q0, q1, dv, platform_q, tables, scratch):
    """``dv = q1 (-) q0`` (Pinocchio's ``difference``): leg joints subtract, the platform by ``log6``."""
    leg_q, leg_v, platform_v = tables[0], tables[1], tables[2]
    for i in range(leg_q.shape[0]):
        for k in range(leg_q.shape[1]):
            dv[leg_v[i, k]] = q1[leg_q[i, k]] - q0[leg_q[i, k]]
    x0, x1 = q0[platform_q : platform_q + 7], q1[platform_q : platform_q + 7]
    difference_free_flyer(x0, x1, dv[platform_v[0] : platform_v[0] + 6], scratch[0], scratch[1], scratch[2], scratch[3])


@njit(cache=True)
def _predict(x, a, b, u, q0, dv, platform_q, views, scratch):
    """``q0 = x (+) u (b (-) a)``: ``pin.integrate(x, u * pin.difference(a, b))``.

    ``views``: :func:`.packing.unpack`'s of the solver's arrays.
    """
    tables = views[0]
    leg_q, leg_v, platform_v = tables[0], tables[1], tables[2]
    _difference(a, b, dv, platform_q, tables, scratch)
    for i in range(dv.shape[0]):
        dv[i] *= u
    copy_into(q0, x)
    integrate_configuration(q0, dv, leg_q, leg_v, platform_q, platform_v)


@njit(cache=True)
def closure_norm(q, ints, floats, work):
    """The closure residual norm at ``q``, left in the work buffer ``r`` (``iterate(q, inf, 0)``'s)."""
    (leg_q, leg_v, platform_v, _, _, _, kinds), _ = unpack_ints(ints)
    (placements, motions, closure, home), _ = unpack_floats(ints, floats)
    J, R, p, E, r = unpack_work(ints, work)[0][:5]
    evaluate_chains(q, placements, kinds, motions, leg_q, leg_v, closure, home, ints[3], platform_v, J, R, p)
    return closure_residual(R, p, ints[0], E, r, floats[LENGTH_SCALE])[0]


@njit(cache=True, inline="always")
def follow_buffers(nq, nv, nr):
    """The work arrays of :func:`follow_in`: ``nq`` configuration entries, ``nv`` velocities, ``nr`` residual rows."""
    scratch = (np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty(3))
    return np.empty(nq), np.empty(nq), np.empty(nv), scratch, np.empty(nr)


@njit(cache=True)
def follow(start, target, first, predicted, tol, max_iter, sign, total, h, packed, x, q):
    """Follow the readings path from ``start`` to ``target`` in certified substeps, the first of ``h``.

    Args:
        start: configuration to start from; its prismatic entries are its own readings ``l0``.
        target: the prismatic joint values to reach (leg order).
        first: the plain attempt's first iterate, the first predictor when ``predicted``.
        predicted: the plain attempt took one step (``first`` is meaningful).
        tol: closure residual of the last substep.
        max_iter: Newton steps per substep.
        sign: determinant sign of the start's assembly (0 when unknown).
        total: Newton steps taken so far (the count goes on).
        h: the first substep.
        packed: the solver's :class:`.packing.Packed` arrays (with each leg's prismatic joint).
        x: output, the last certified point of the path (``start`` when none).
        q: output, the last corrector's final iterate (the result when ``t == 1``).

    Returns:
        ``(t, total, residual)``: how far the path was followed (1: certified end), the Newton
        steps counted and the last corrector's residual norm.
    """
    ints = packed[0]
    buffers = follow_buffers(start.shape[0], ints[1], 6 * ints[0])
    views = unpack(packed[0], packed[1], packed[2], packed[3])
    return follow_in(
        start, np.nan, target, first, predicted, tol, max_iter, sign, total, h, packed, views, x, q, buffers
    )


@njit(cache=True, inline="always")  # inlined into follow and batch_kernels.forward_rows: one compiled unit each
def follow_in(start, closes, target, first, predicted, tol, max_iter, sign, total, h, packed, views, x, q, buffers):
    """:func:`follow` with its work arrays (:func:`follow_buffers`) and the start's residual if known.

    ``views``: :func:`.packing.unpack`'s of ``packed``, made once by the caller (each substep's
    Newton call takes them).

    ``closes``: the closure residual norm at ``start`` when the caller knows it (the start is
    the batch's first start or a row's result, whose last evaluation it is), NaN when not. A
    known residual within the intermediate tolerance is not evaluated again; any other is.
    """
    ints, floats, work = packed[0], packed[1], packed[2]
    r = views[2][WORK_R]
    prismatic_q = unpack_constants(ints, floats)[0][0]
    n = prismatic_q.shape[0]
    q0, before, dv, scratch, offset = buffers
    yes = BOOLEANS[1]  # a plain True: one compiled signature of iterate_schur
    intermediate = INTERMEDIATE_TOL * floats[LENGTH_SCALE]  # m, rad: scaled as the tolerance
    # the start's own closure residual: a start off the manifold follows r - (1 - t) r_start
    res = closes if closes <= intermediate else closure_norm(start, ints, floats, work)
    shifted = res > intermediate
    if shifted:
        copy_into(offset, r)
    copy_into(x, start)
    t, t_before, substeps, has_before = 0.0, 0.0, 0, False
    while t < 1.0 and substeps < MAX_SUBSTEPS and h >= MIN_STEP:
        tn = 1.0 if t + 1.2 * h >= 1.0 else t + h  # no sliver of a last substep
        if has_before:  # predictor: along the secant of the last two path points
            _predict(x, before, x, (tn - t) / (t - t_before), q0, dv, ints[3], views, scratch)
        elif predicted:  # along the plain attempt's first Newton step (the tangent, to first order)
            _predict(x, x, first, tn, q0, dv, ints[3], views, scratch)  # pin.interpolate(x, first, tn)
        else:
            copy_into(q0, x)
        for i in range(n):
            l0 = start[prismatic_q[i]]
            q0[prismatic_q[i]] = l0 + tn * (target[i] - l0)
        scale = 1.0 - tn if shifted else 0.0
        tol_n = tol if tn == 1.0 else intermediate
        code, it, res, _, theta, kept, certified = iterate_schur(
            q0, q, tol_n, max_iter, sign, offset, scale, yes, ints, floats, views
        )
        total += it
        substeps += 1
        accepted = code == CONVERGED and certified
        h = (tn - t) * rescale(theta, accepted, 2 if predicted else 1)  # from the substep tried
        if accepted:
            copy_into(before, x)
            copy_into(x, q)
            t_before, t, sign, predicted, has_before = t, tn, kept, True, True
    return t, total, res
