"""Many solves in one call: :meth:`.hexapod.Hexapod.forward_batch` and ``inverse_batch``.

Each row gets what :meth:`~.hexapod.Hexapod.forward` (``inverse``) with ``check=False`` would
give it (status, message, flags, iterations, determinant sign), and ``invalid_input`` where
those raise on the row's input (NaN, a reading outside the stroke, a matrix that is not a rigid
transform). On the compiled path (:mod:`.newton`) the loop over rows runs compiled
(:mod:`.batch_kernels`), the readings path of :mod:`.certificate` included; a direct-kinematics
row whose path is blocked (``ambiguous_assembly`` and its candidates), or whose warm result lies
near a singularity (``uncertified``, or ``converged`` only with the Krawczyk proof of its step),
is solved by ``forward`` itself. Other hexapods and held sets
are solved row by row. :mod:`.batch_result` holds the result and how the loops' outputs become it.
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np

from ..exceptions import HexapodError, InputError
from .all_assemblies import review
from .batch_result import FALLBACK, BatchResult, as_rows, batch_result, loop_outputs, poses_of_xyzquat
from .certificate import NEAR_SINGULAR_FACTOR
from .engine import NEAR_SINGULAR, SolveEngine
from .input_checks import MAX_POSITION, POSE_TOLERANCE, check_max_iter, check_tolerance
from .newton.first_compile import announce
from .newton.outcomes import INVALID_INPUT
from .newton.proven import Proof
from .newton.solver import Solution

__all__ = ["PROOF_STEP", "BatchResult", "as_rows", "forward_batch", "inverse_batch", "poses_of_xyzquat"]

#: m: the longest step (largest change of a reading from the row's start) a batch row is proven over
PROOF_STEP = 0.002


def _per_row(engine: SolveEngine, solve, rows, guess, warm: bool, retry, forward: bool) -> BatchResult:
    """The general path: one solve per row (hexapods or held sets without the compiled path)."""
    n = len(rows)
    out = loop_outputs(n, engine.nq)
    out[2][:] = FALLBACK
    fallback: dict[int, Solution] = {}
    for k, x in enumerate(rows):
        try:
            fallback[k] = sol = solve(x, guess)
        except HexapodError:
            out[0][k], out[2][k], out[3][k], out[4][k], out[7][k] = np.nan, INVALID_INPUT, 0, np.nan, 0
            continue
        if warm and sol.converged:
            guess = sol
    return batch_result(engine, out, 0.0, retry, fallback, forward)


def _message_of(call) -> str:
    """The message of the error that ``call()`` raises on an invalid row."""
    try:
        call()
    except HexapodError as exc:
        return str(exc)
    return "invalid input"  # not reached: the compiled checks are the per-row checks


def forward_batch(engine: SolveEngine, readings, guess, warm: bool, tol, max_iter, prove: bool = True) -> BatchResult:
    """:meth:`.hexapod.Hexapod.forward_batch`."""
    rows = as_rows("lengths", readings, (6,))
    tol, max_iter = check_tolerance(tol), check_max_iter(max_iter)

    def solve(x: np.ndarray, g) -> Solution:
        return engine.forward(x, g, tol, max_iter, False, True, NEAR_SINGULAR)  # rows carry the certificate

    def retry(k: int) -> str:
        return _message_of(lambda: solve(rows[k], None))

    solver = engine.solver(engine.held_forward)
    one_call = solver.one_call
    if one_call is None:
        res = _per_row(engine, solve, rows, guess, warm, retry, True)
        return _proven(engine, res, rows, guess, warm, tol, max_iter) if prove else res
    from .newton.batch_kernels import forward_rows  # numba: only for a compiled solver

    announce(forward_rows)

    start = engine.start(guess)  # a bad guess raises, as forward would on every row
    sign = solver.home_sign if guess is None else float(getattr(guess, "det_sign", 0))
    carry = np.array([sign, 0.0, float(guess is not None)])
    joints = rows if engine.encoder is None else engine.joints_of(rows)
    out, fallback = loop_outputs(len(rows), engine.nq), {}
    settings = (tol, max_iter, NEAR_SINGULAR_FACTOR * solver.home_kappa)
    stroke = (engine.stroke_lo, engine.stroke_hi)
    k = 0
    while k < len(rows):
        k = forward_rows(
            k,
            rows,
            joints,
            start,
            carry,
            warm,
            settings,
            stroke,
            one_call.arrays,
            out,
        )
        if k < len(rows):  # the path is blocked, or a warm row is near a singularity: forward() says so (and proves)
            g = (
                guess
                if not carry[1]
                else Solution(engine.pose_of(start), start.copy(), rows[k], "converged", 0, 0.0, det_sign=int(carry[0]))
            )
            fallback[k] = sol = solve(rows[k], g)
            out[2][k] = FALLBACK
            if warm and sol.converged:
                start[:], carry[:2] = sol.q, (sol.det_sign, 1.0)
            k += 1
    res = batch_result(engine, out, tol, retry, fallback, True, max_iter)
    if prove:  # a row the review's redo solves is proven by forward() itself
        solve = functools.partial(_solve_proven, engine, tol, max_iter)
    res, replaced = _reviewed(engine, res, rows, guess, warm, solve, set(fallback))
    return _proven(engine, res, rows, guess, warm, tol, max_iter, replaced) if prove else res


def _solve_proven(engine: SolveEngine, tol: float, max_iter: int, x: np.ndarray, g) -> Solution:
    """``forward(x, g, check=False)`` as a proven batch's row.

    A warm step within :data:`PROOF_STEP` with its proof; a longer one, or a cold row, with the
    certificate's checks (proven near a singularity).
    """
    joints = x if engine.encoder is None else engine.joints_of(x)
    short = g is not None and _short(engine, joints, engine.start(g, copy=False))  # any guess forward takes
    return engine.forward(x, g, tol, max_iter, False, True, True if short else NEAR_SINGULAR)


def _short(engine: SolveEngine, joints: np.ndarray, start: np.ndarray) -> bool:
    """Whether the step from configuration ``start`` to the held joints ``joints`` (m) is within :data:`PROOF_STEP`."""
    from .newton.kernels import largest_step  # numba: loaded already by the compiled solver a proving batch uses

    return bool(largest_step(joints, start, engine.closed_loop.prismatic_q) <= PROOF_STEP)


def _proven(
    engine: SolveEngine,
    res: BatchResult,
    rows: np.ndarray,
    guess,
    warm: bool,
    tol: float,
    max_iter: int,
    replaced: frozenset[int] = frozenset(),
) -> BatchResult:
    """Each ``converged`` row solved from a guess with the Krawczyk proof of its step, as ``forward`` gives it.

    A row's start is ``guess``, or with ``warm`` the last converged row (home, unproven, for
    the rows before the first when ``guess`` is None). A step longer than :data:`PROOF_STEP`
    (a reading's change; rows of unrelated poses) keeps the certificate's checks (``proof``
    None), as the tracker's longer steps do: following it in proven steps would cost tenths of
    a second a row. A shorter step that cannot be proven goes
    the way ``forward``'s does (:meth:`.engine.SolveEngine.proven_warm`: from the guess's
    closure, then in proven steps) and ends ``uncertified`` when that fails too; once a warm
    row's answer changed, the rows after it are solved by ``forward`` one by one (their starts
    changed). A row ``forward`` solved already (a blocked path, near a singularity) keeps its
    proof. A 3-6 hexapod's rows are its review's (every assembly accounted for: the global
    answer, as ``forward`` gives a replaced result), and are proven only where the review kept
    the solve's result (``replaced``: the others).
    """
    prover = engine.prover
    if prover is None:
        return replace(res, proofs=(None,) * len(rows))
    try:
        start_guess = None if guess is None else (guess if isinstance(guess, Solution) else engine.start(guess))
    except HexapodError:  # a bad guess: every row is invalid_input already (the row-by-row path)
        return replace(res, proofs=(None,) * len(rows))
    arrays = _columns(res)
    status, q = arrays[0], arrays[4]
    proofs: list[Proof | None] = list(res.proofs) if res.proofs else [None] * len(rows)
    redo = False
    joints = rows if engine.encoder is None else engine.joints_of(rows)
    # the start: a guess (Solution or array) or the index of the last converged row (its Solution made when needed)
    start: Solution | np.ndarray | int | None = start_guess
    written: dict[int, Solution] = {}  # the rows rewritten here (a later row's start)

    def guess_of(start: Solution | np.ndarray | int | None) -> Solution | np.ndarray | None:
        return (written.get(start) or res.solution(start)) if isinstance(start, int) else start

    for k in range(len(rows)):
        if status[k] == "invalid_input":
            continue
        if redo:  # a start changed: forward() solves and proves the row itself (the same rule)
            written[k] = new = _solve_proven(engine, tol, max_iter, rows[k], guess_of(start))
            _write(new, k, arrays, proofs)
        elif status[k] == "converged" and start is not None and proofs[k] is None and k not in replaced:
            s0 = q[start] if isinstance(start, int) else (start.q if isinstance(start, Solution) else start)
            if _short(engine, joints[k], s0):
                proof = prover.prove(s0, q[k])
                if proof.proven:  # the usual case: nothing to build
                    proofs[k] = proof
                else:  # forward's way on: from the guess's closure, then in proven steps
                    sol, guess_k = res.solution(k), guess_of(start)
                    written[k] = new = engine.proven_warm(sol, guess_k, s0, joints[k], tol, max_iter, False, proof)
                    _write(new, k, arrays, proofs)
                    redo = warm and new.status != "converged"
        if warm and status[k] == "converged":
            start = k
    return _with_columns(res, arrays, proofs)


def _columns(res: BatchResult) -> tuple:
    """Copies of ``res``'s columns to rewrite rows in (:func:`_write`).

    In this order: status (object), messages, flags, det_sign, q, iterations, residual, poses, lengths.
    """
    return (
        res.status.astype(object),
        list(res.messages),
        list(res.flags),
        res.det_sign.copy(),
        res.q.copy(),
        res.iterations.copy(),
        res.residual.copy(),
        res.poses.copy(),
        res.lengths.copy(),
    )


def _with_columns(res: BatchResult, arrays: tuple, proofs: list[Proof | None]) -> BatchResult:
    """``res`` with the columns of :func:`_columns` (rewritten) and ``proofs``."""
    status, messages, flags, signs, q, iterations, residual, poses, lengths = arrays
    return replace(
        res,
        poses=poses,
        lengths=lengths,
        q=q,
        status=status.astype(str),
        iterations=iterations,
        residual=residual,
        messages=tuple(messages),
        flags=tuple(flags),
        det_sign=signs,
        proofs=tuple(proofs),
    )


def _write(new: Solution, k: int, arrays: tuple, proofs: list[Proof | None]) -> None:
    """Row ``k`` of the batch's columns (``arrays``, written in place) from the Solution ``new``."""
    status, messages, flags, signs, q, iterations, residual, poses, lengths = arrays
    status[k], messages[k], flags[k], signs[k], q[k] = new.status, new.message, new.flags, new.det_sign, new.q
    iterations[k], residual[k] = new.iterations, new.residual
    poses[k] = new.pose if new.converged else np.nan
    lengths[k] = new.lengths if new.converged else np.nan
    proofs[k] = new.proof


def _reviewed(
    engine: SolveEngine, res: BatchResult, rows: np.ndarray, guess, warm: bool, solve, done: set[int]
) -> tuple[BatchResult, frozenset[int]]:
    """A 3-6 hexapod's rows checked against every assembly, as :meth:`.hexapod.Hexapod.forward` checks them.

    Each row from its own start (``guess``, or with ``warm`` the last converged row); the rows
    in ``done`` were solved by ``forward`` already. Once a warm row's status changes, the rows
    after it are solved by ``solve`` (``forward``) one by one. Returns the result and the rows
    whose answer the review replaced.
    """
    if engine.finder.exact is None:
        return res, frozenset()
    arrays = _columns(res)
    status = arrays[0]
    start, redo, replaced = guess, False, set()
    proofs: list[Proof | None] = list(res.proofs) if res.proofs else [None] * len(rows)
    for k in range(len(rows)):
        if status[k] == "invalid_input":
            continue
        if redo:  # forward() checks it itself
            new, changed = solve(rows[k], start), True
        elif k in done:
            new, changed = res.solution(k), False
        else:
            sol = res.solution(k)
            new = review(engine.finder, sol, rows[k], start)
            changed, redo = new is not sol, warm and new.status != sol.status
            if changed:
                replaced.add(k)
        if changed:
            _write(new, k, arrays, proofs)
        if warm and new.converged:
            start = new
    return _with_columns(res, arrays, proofs), frozenset(replaced)


def inverse_batch(engine: SolveEngine, poses, guess, warm: bool, tol, max_iter) -> BatchResult:
    """:meth:`.hexapod.Hexapod.inverse_batch`."""
    if np.ndim(poses) == 2 and np.shape(poses)[1:] == (7,):
        xyzquat = as_rows("poses", poses, (7,))
        rows = poses_of_xyzquat(xyzquat, POSE_TOLERANCE)
    else:
        xyzquat, rows = None, as_rows("poses", poses, (4, 4))
    tol, max_iter = check_tolerance(tol), check_max_iter(max_iter)

    def solve(T: np.ndarray, g) -> Solution:
        return engine.inverse(T, g, tol, max_iter, False)

    def retry(k: int) -> str:
        if xyzquat is not None and not np.all(np.isfinite(rows[k])):
            rule = f"x, y, z, qx, qy, qz, qw must be finite, the quaternion of norm 1 within {POSE_TOLERANCE:g}"
            return str(InputError("pose", xyzquat[k], rule))
        return _message_of(lambda: solve(rows[k], None))

    one_call = engine.solver(engine.held_inverse).one_call
    if one_call is None:
        return _per_row(engine, solve, rows, guess, warm, retry, False)
    from .newton.batch_kernels import inverse_rows  # numba: only for a compiled solver

    announce(inverse_rows)

    out = loop_outputs(len(rows), engine.nq)
    settings = (tol, max_iter, POSE_TOLERANCE, MAX_POSITION)
    inverse_rows(rows, engine.start(guess), warm, settings, one_call.arrays, out)
    return batch_result(engine, out, tol, retry, {}, False, max_iter)
