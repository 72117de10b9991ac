"""Which assembly direct kinematics returns, and the check (a heuristic, not a proof) that it is that one.

Six readings usually admit several platform poses (assemblies). :func:`solve_forward` returns
as ``converged`` only **the assembly connected to the start**: the end of the path of
solutions ``x(t)`` for the readings ``l(t) = l0 + t (l - l0)``, ``0 <= t <= 1``, that begins at
the start configuration and its own readings ``l0`` (home and zero readings for a cold solve,
the guess otherwise). The path is followed in substeps; a substep is accepted only when its
Newton corrector

* takes no shortened step (``MAX_STEP``),
* contracts: every ``|dx_k+1| / |dx_k| <= THETA_MAX`` = 1/4 (Deuflhard's estimate of the
  affine-covariant Kantorovich quantity ``h0``; were ``h0 <= 1/2`` *bounded*, the solution
  would be unique in a ball around the substep's start), and
* keeps the sign of the constraint Jacobian's determinant (the 36x36 or 18x18 direct-kinematics
  system, ``prod_i det L_i * det M`` from the Schur step) equal to the start's at every iterate
  (home's for a cold solve, the guess :class:`Solution`'s ``det_sign`` for a warm one).

**What this is not.** The contraction ratio is measured at the iterates only: it estimates the
Kantorovich quantity from below, where a proof needs a bound from above (a Lipschitz bound of
the closure Jacobian over a ball); a solve that closes in one step measures no contraction (a
first step above ``ONE_STEP`` is followed by a second); the determinant's sign is sampled at
the iterates, not between them. So "certified" here names these checks passing, not a proof
that the result is the connected assembly: what they achieve is measured by
``benchmarks/robustness.py`` (converged results that are not the generating pose, per preset)
and their cost and refusals by ``benchmarks/certificate.py``; docs/solver.md states what
``converged`` guarantees. On a 3-6 hexapod every assembly is known
(:mod:`.all_assemblies`), which is what makes its ``converged`` exact up to its stated rule.

The first attempt is the whole path in one substep, i.e. the plain Newton solve: warm starts
and most cold starts pass at no extra cost. Otherwise the path is followed in substeps (a
predictor along the first Newton step, then along the secant of the last two path points),
down to ``MIN_STEP`` and at most ``MAX_SUBSTEPS`` of them. A warm start whose certified
attempt fails but whose plain Newton result lies near a singularity (condition bound above
``NEAR_SINGULAR_FACTOR`` times home's) is returned as ``uncertified`` with the flag
``near_singular``: a closed configuration, but perhaps across a fold from the start (another
assembly), so never ``converged``. When the path cannot be followed (it
meets a singularity or a fold of the readings map), the result is ``ambiguous_assembly`` with
the assemblies found (the plain solve's, and Newton's from the last certified point) as
candidates, never ``converged``. On the compiled path the path is followed in compiled code
(:func:`.follow.follow`, the same rules); the candidates are always looked for here. Where
the path goes on past the block (near a singularity, not at a fold), :func:`.connected.connected_end`
follows it again in steps each proven by the Krawczyk test, and :func:`with_connected` puts
the assembly it ends at first among the candidates, flagged ``connected``: the one the
readings path from the start reaches.

A certified result whose eliminated 6x6 Jacobian ``M`` (leg-reading rates per platform twist)
has a condition-number bound (:func:`~hexapod_model.kinematics.newton.structured.schur_solve`) above
``NEAR_SINGULAR_FACTOR`` times its home value carries the flag ``near_singular``: it is the
connected assembly, but another one may lie close by.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple, cast

import numpy as np
import pinocchio as pin

from .newton.first_compile import announce
from .newton.path_rules import INTERMEDIATE_TOL, MAX_SUBSTEPS, MIN_STEP, rescale
from .newton.solver import NewtonSolver

if TYPE_CHECKING:
    from .newton.compiled import CompiledSolver

__all__ = ["INTERMEDIATE_TOL", "MAX_SUBSTEPS", "MIN_STEP", "NEAR_SINGULAR_FACTOR", "Outcome", "solve_forward"]

NEAR_SINGULAR_FACTOR = 30.0  # flag when the condition bound of M exceeds this times its home value
_DISTINCT = 1e-7  # configurations farther apart than this (rad, m per length scale) are different assemblies


class Outcome(NamedTuple):
    """A solve's result before the :class:`Solution` is built: configurations, not poses.

    The first six fields are ``NewtonSolver.run``'s; the others come from the certificate.
    """

    q: np.ndarray
    status: str
    iterations: int
    residual: float
    jacobian: np.ndarray | None
    message: str
    flags: tuple[str, ...] = ()
    candidates: tuple[np.ndarray, ...] = ()
    det_sign: int = 0


def solve_forward(
    solver: NewtonSolver,
    start: np.ndarray,
    lengths: np.ndarray,
    tol: float,
    max_iter: int,
    sign: float,
    warm: bool,
    attempt: tuple[str, int, float, str] | None = None,
) -> Outcome:
    """Certified direct kinematics: the assembly connected to ``start`` for readings ``lengths``.

    Args:
        solver: the direct-kinematics solver (the six prismatic joints held).
        start: URDF configuration to start from; its prismatic entries are its own readings
            ``l0`` (overwritten here).
        lengths: the six readings (m).
        tol: closure residual of the result.
        max_iter: Newton steps per substep (the outcome counts them all).
        sign: determinant sign of the start's assembly (0 when unknown).
        warm: the start is a guess, not home: an uncertified result of plain Newton that is
            near a singularity is returned as ``uncertified``, flagged ``near_singular``, before
            the path is tried.
        attempt: the certified first attempt's ``(status, iterations, residual, message)``
            when the caller made it already (the solver's state is that attempt's):
            :meth:`.compiled_solver.CompiledSolver.certified_forward`, which returns it when the attempt
            did not converge certified.

    Returns:
        ``converged`` (certified, maybe flagged ``near_singular``), ``uncertified`` (warm, near
        a singularity), ``ambiguous_assembly`` with candidates, or the plain solve's failure.
    """
    pq = solver.clm.prismatic_q
    l0 = start[pq]
    start[pq] = lengths
    status, it, res, msg = solver.iterate(start, tol, max_iter, sign, certify=True) if attempt is None else attempt
    if status == "converged" and solver.certified:
        return _certified(solver, it, res)
    if status == "max_iterations" and solver.certified:  # contracting, but max_iter too small
        solver.kernels.jacobian(*solver.jac_args)
        return Outcome(solver.q_aug[: solver.clm.nq].copy(), status, it, res, solver.G.copy(), msg)
    plain = start.copy()  # for the candidates, should the path be blocked
    first = solver.q_aug[: solver.clm.nq].copy() if it == 1 else None  # after the first Newton step
    if warm:  # near a singularity no path certifies (its balls shrink): the plain result, not converged
        status, n, res, msg = solver.iterate(plain, tol, max_iter)
        it += n
        if status == "converged" and not solver.kappa <= NEAR_SINGULAR_FACTOR * solver.home_kappa:
            return _uncertified(solver, it, res)
    start[pq] = l0
    h = rescale(solver.theta, False, 1)
    if solver.one_call is not None:  # a compiled.CompiledSolver
        return _follow_compiled(
            cast("CompiledSolver", solver), start, l0, lengths, tol, max_iter, sign, (plain, first), it, h
        )
    return _follow(solver, start, l0, lengths, tol, max_iter, sign, (plain, first), it, h)


def _follow(
    solver: NewtonSolver,
    start: np.ndarray,
    l0: np.ndarray,
    lengths: np.ndarray,
    tol: float,
    max_iter: int,
    sign: float,
    tried: tuple[np.ndarray, np.ndarray | None],
    total: int,
    h: float,
) -> Outcome:
    """Follow the readings path from ``start`` in certified substeps, the first of ``h``.

    ``tried`` holds the plain attempt's start and, when it took one step, its first iterate.
    A start that does not close at its own readings follows ``r - (1 - t) r_start`` instead.
    """
    model, nq, pq = solver.clm.model, solver.clm.nq, solver.clm.prismatic_q
    intermediate = INTERMEDIATE_TOL * solver.length_scale  # m, rad: scaled as the tolerance
    _, _, res, _ = solver.iterate(start, np.inf, 0)  # the start's own closure residual
    offset = solver.r.copy() if res > intermediate else None
    x, t, substeps, it, before = start, 0.0, 0, 0, None
    predicted = tried[1] is not None
    while t < 1.0 and substeps < MAX_SUBSTEPS and h >= MIN_STEP:
        tn = 1.0 if t + 1.2 * h >= 1.0 else t + h  # no sliver of a last substep
        if before is not None:  # predictor: along the secant of the last two path points
            q0 = pin.integrate(model, x, pin.difference(model, before[0], x) * ((tn - t) / (t - before[1])))
        elif predicted:  # along the plain attempt's first Newton step (the tangent, to first order)
            q0 = pin.interpolate(model, x, tried[1], tn)
        else:
            q0 = x.copy()
        q0[pq] = l0 + tn * (lengths - l0)
        scale = 0.0 if offset is None else 1.0 - tn
        tol_n = tol if tn == 1.0 else intermediate
        status, it, res, _ = solver.iterate(q0, tol_n, max_iter, sign, offset, scale, certify=True)
        total += it
        substeps += 1
        accepted = status == "converged" and solver.certified
        h = (tn - t) * rescale(solver.theta, accepted, 2 if predicted else 1)  # from the substep tried
        if accepted:
            before, x, t, sign, predicted = (x, t), solver.q_aug[:nq].copy(), tn, solver.det_sign, True
    if t == 1.0:
        return _certified(solver, total, res)
    return _ambiguous(solver, x, t, lengths, tol, max_iter, tried[0], total)


def _follow_compiled(
    solver: CompiledSolver,
    start: np.ndarray,
    l0: np.ndarray,
    lengths: np.ndarray,
    tol: float,
    max_iter: int,
    sign: float,
    tried: tuple[np.ndarray, np.ndarray | None],
    total: int,
    h: float,
) -> Outcome:
    """:func:`_follow` on the compiled path (:func:`.follow.follow`); the candidates, if any, here."""
    from .newton.follow import follow  # numba: a compiled solver's

    announce(follow)

    first = tried[1] if tried[1] is not None else start
    x = np.empty_like(start)
    args = (float(tol), int(max_iter), float(sign), int(total), float(h), solver.arrays, x, solver.last_q)
    t, total, res = follow(start, lengths, first, tried[1] is not None, *args)
    solver.sign, solver.kappa = solver.state.tolist()  # the last Schur step's, as iterate() leaves them
    if t == 1.0:
        return _certified(solver, total, res)
    return _ambiguous(solver, x, t, lengths, tol, max_iter, tried[0], total)


def certified_outcome(
    solver: NewtonSolver, q: np.ndarray, jac: np.ndarray, total: int, res: float, note: str = ""
) -> Outcome:
    """The converged result ``q`` (Jacobian ``jac``) of the solver's last solve, with its determinant sign and flag.

    ``near_singular`` (and its message, after ``note``) when the last Schur step's condition
    bound exceeds ``NEAR_SINGULAR_FACTOR`` times home's.
    """
    kappa = solver.kappa
    flags: tuple[str, ...] = ()
    msg = ""
    if not kappa <= NEAR_SINGULAR_FACTOR * solver.home_kappa:
        flags = ("near_singular",)
        msg = (
            f"{note}near a singularity: condition bound of the eliminated Jacobian {kappa / solver.home_kappa:.3g} "
            f"times its home value (flag above {NEAR_SINGULAR_FACTOR:g}); another assembly may be close"
        )
    return Outcome(q, "converged", total, res, jac, msg, flags, (), int(solver.sign))


def _certified(solver: NewtonSolver, total: int, res: float, note: str = "") -> Outcome:
    """The result in the solver's buffers with its determinant sign and flag (certified unless ``note``)."""
    solver.kernels.jacobian(*solver.jac_args)
    q = solver.q_aug[: solver.clm.nq].copy()  # the last Schur step (iterate() takes one even at once)
    return certified_outcome(solver, q, solver.kernels.copied(solver.G), total, res, note)


def _uncertified(solver: NewtonSolver, total: int, res: float) -> Outcome:
    """The plain Newton result in the solver's buffers, near a singularity: status ``uncertified``.

    It closes the loops, but nothing shows that it is the assembly connected to the start: the
    readings may have moved it across a fold (another assembly), so it is never ``converged``.
    """
    out = _certified(solver, total, res)
    msg = (
        "the assembly connected to the start could not be certified (the plain Newton result is near a "
        f"singularity, another assembly may be the one connected to the start): {out.message}"
    )
    return out._replace(status="uncertified", message=msg)


def _ambiguous(
    solver: NewtonSolver,
    x: np.ndarray,
    t: float,
    lengths: np.ndarray,
    tol: float,
    max_iter: int,
    plain: np.ndarray,
    total: int,
) -> Outcome:
    """The candidates when the path is blocked at ``t`` (last certified point ``x``).

    The assemblies found by plain Newton from the start and from ``x``, within the joint limits.
    """
    clm = solver.clm
    found: list[np.ndarray] = []
    status, res, msg = "max_iterations", float("inf"), ""
    q_end = x.copy()
    q_end[clm.prismatic_q] = lengths
    for q0 in (plain, q_end) if t > 0.0 else (plain,):
        st, it, r, m = solver.iterate(q0, tol, max_iter)
        total += it
        if st == "converged":
            found.append(solver.q_aug[: clm.nq].copy())
        elif not found:
            status, res, msg = st, r, m
    distinct: list[np.ndarray] = []
    for q in found:
        if all(_distinct(solver, q, c) for c in distinct):
            distinct.append(q)
    idx = clm.limited_q()
    inside = [q for q in distinct if solver.kernels.first_outside_at(q, idx, clm.lower[idx], clm.upper[idx], 1e-12) < 0]
    where = f"the readings path from the start is blocked at {t:.4f} of the way (a singularity or fold)"
    if not inside:
        q = distinct[0] if distinct else solver.q_aug[: clm.nq].copy()
        _, G = solver.evaluate(q)
        if distinct:
            return Outcome(q, "out_of_limits", total, 0.0, G, f"{where}; every assembly found is outside the limits")
        return Outcome(q, status, total, res, G, f"{msg}; {where}")
    residual, G = solver.evaluate(inside[0])
    residual *= solver.residual_weights  # rotation rows times the length scale: the iteration's norm
    msg = f"cannot certify the assembly connected to the start: {where}; {len(inside)} candidate assemblies"
    return Outcome(inside[0], "ambiguous_assembly", total, float(np.linalg.norm(residual)), G, msg, (), tuple(inside))


def _distinct(solver: NewtonSolver, q: np.ndarray, c: np.ndarray) -> bool:
    """Whether configurations ``q`` and ``c`` are different assemblies (``_DISTINCT`` apart)."""
    return bool((np.abs(pin.difference(solver.clm.model, q, c)) * solver.weights).max() > _DISTINCT)


def with_connected(solver: NewtonSolver, out: Outcome, end: np.ndarray) -> Outcome:
    """The ``ambiguous_assembly`` outcome ``out`` with ``end``, the proven path's end, as its first candidate.

    ``end`` (closed for the readings, :func:`.connected.connected_end`) is the assembly connected
    to the start: flagged ``connected``, and the outcome's configuration. Outside the joint
    limits it is no candidate (``out`` unchanged).
    """
    clm = solver.clm
    idx = clm.limited_q()
    if solver.kernels.first_outside_at(end, idx, clm.lower[idx], clm.upper[idx], 1e-12) >= 0:
        return out
    rest = tuple(c for c in out.candidates if _distinct(solver, end, c))
    residual, G = solver.evaluate(end)
    residual *= solver.residual_weights
    msg = (
        f"{out.message}; the path goes on past the block, each step proven (Krawczyk): "
        f"the first of {1 + len(rest)} candidates is the assembly connected to the start"
    )
    flags = (*out.flags, "connected")
    return out._replace(
        q=end, residual=float(np.linalg.norm(residual)), jacobian=G, message=msg, flags=flags, candidates=(end, *rest)
    )


def restricted(solver: NewtonSolver, out: Outcome, keep: list[bool], why: str) -> Outcome:
    """The ``ambiguous_assembly`` outcome ``out`` with only the candidates ``keep`` marks.

    The first kept one becomes the outcome's configuration; ``connected`` stays only while the
    first candidate is kept. None kept: ``out_of_limits``. ``why`` says where the others lie.
    """
    kept = tuple(c for c, k in zip(out.candidates, keep) if k)
    if len(kept) == len(out.candidates):
        return out
    flags = out.flags if keep[0] else tuple(f for f in out.flags if f != "connected")
    if not kept:
        msg = f"{out.message}; every assembly found lies {why}"
        return out._replace(status="out_of_limits", message=msg, flags=flags, candidates=())
    residual, G = solver.evaluate(kept[0])
    residual *= solver.residual_weights
    dropped = len(out.candidates) - len(kept)
    msg = f"{out.message}; {dropped} of {len(out.candidates)} candidates {'lies' if dropped == 1 else 'lie'} {why}"
    return out._replace(
        q=kept[0], residual=float(np.linalg.norm(residual)), jacobian=G, message=msg, flags=flags, candidates=kept
    )
