"""Many solves in one call: :meth:`.hexapod.Hexapod.forward_batch` and ``inverse_batch``.

Each row gets what :meth:`~.hexapod.Hexapod.forward` (``inverse``) with ``check=False`` would
give it (status, message, flags, iterations, determinant sign), and ``invalid_input`` where
those raise on the row's input (NaN, a reading outside the stroke, a matrix that is not a rigid
transform). On the compiled path (:mod:`.newton`) the loop over rows runs compiled
(:mod:`.batch_kernels`), the readings path of :mod:`.assembly` included; a direct-kinematics
row whose path is blocked (``ambiguous_assembly`` and its candidates) or whose warm result is
uncertified near a singularity is solved by ``forward`` itself. Other hexapods and held sets
are solved row by row.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..exceptions import HexapodError, InputError
from .assemblies import review
from .assembly import NEAR_SINGULAR_FACTOR
from .checks import MAX_POSITION, POSE_TOLERANCE, check_max_iter, check_tolerance, failure_status
from .newton.first_compile import announce
from .newton.outcomes import INVALID_INPUT, OUT_OF_LIMITS, outcome
from .newton.solver import Solution

Hexapod = Any  # a hexapod.Hexapod (this module is below it: hexapod.py imports it)

_FALLBACK = -1  # code of a row solved by forward() itself
_NEAR = "near a singularity: condition bound of the eliminated Jacobian {:.3g} times its home value (flag above {:g}); "
_NEAR += "another assembly may be close"


@dataclass(frozen=True)
class BatchResult:
    """Per-row results of a batch solve (N rows). Check :attr:`status` before using a row.

    Attributes:
        poses: (N, 4, 4) base -> platform (m); NaN rows where the status is not ``converged``.
        lengths: (N, 6) leg readings (m); NaN rows where the status is not ``converged``.
        q: (N, nq) final configurations (NaN rows for ``invalid_input``).
        status: (N,) status names (``STATUSES``).
        iterations: (N,) Newton steps taken.
        residual: (N,) final closure residual norm (NaN for ``invalid_input``).
        messages: (N,) each row's ``Solution.message`` (or the error a per-row call raises).
        flags: (N,) each row's ``Solution.flags`` (``("near_singular",)``, ``("not_closed",)`` or ``()``).
        det_sign: (N,) each row's ``Solution.det_sign``.
    """

    poses: np.ndarray
    lengths: np.ndarray
    q: np.ndarray
    status: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray
    messages: tuple[str, ...]
    flags: tuple[tuple[str, ...], ...]
    det_sign: np.ndarray

    @property
    def converged(self) -> np.ndarray:
        """(N,) True where the row is a valid closed configuration within all joint limits."""
        return self.status == "converged"

    def solution(self, k: int) -> Solution:
        """Row ``k`` as a :class:`Solution` (no Jacobian, no candidates): a guess for the next solve."""
        pose = self.poses[k] if self.status[k] == "converged" else np.full((4, 4), np.nan)
        row = (self.q[k].copy(), self.lengths[k].copy(), str(self.status[k]), int(self.iterations[k]))
        return Solution(
            pose.copy(), *row, float(self.residual[k]), None, self.messages[k], self.flags[k], (), int(self.det_sign[k])
        )


def as_rows(name: str, values, width: tuple[int, ...]) -> np.ndarray:
    """``values`` as a float array of shape (N, *width), or :class:`InputError` (NaN entries are kept)."""
    shape = f"(N, {', '.join(map(str, width))})"
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, values, f"expected an array of shape {shape}") from None
    if arr.ndim != 1 + len(width) or arr.shape[1:] != width:
        raise InputError(name, values, f"expected shape {shape}, got {arr.shape}")
    return np.ascontiguousarray(arr)


def poses_of_xyzquat(x: np.ndarray, tolerance: float) -> np.ndarray:
    """(N, 4, 4) poses of rows ``x, y, z, qx, qy, qz, qw``.

    NaN where the quaternion's norm is not 1 within ``tolerance`` (or an entry is not finite).
    """
    T = np.tile(np.eye(4), (len(x), 1, 1))
    with np.errstate(invalid="ignore"):
        norm = np.linalg.norm(x[:, 3:], axis=1)
        ok = np.abs(norm - 1.0) <= tolerance
    qx, qy, qz, qw = (x[:, 3 + a] / np.where(ok, norm, 1.0) for a in range(4))
    T[:, 0, 0], T[:, 0, 1], T[:, 0, 2] = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)
    T[:, 1, 0], T[:, 1, 1], T[:, 1, 2] = 2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)
    T[:, 2, 0], T[:, 2, 1], T[:, 2, 2] = 2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)
    T[:, :3, 3] = x[:, :3]
    T[~ok] = np.nan
    return T


def _outputs(n: int, nq: int) -> tuple:
    """The compiled loops' output arrays (see :mod:`.batch_kernels`)."""
    ints = [np.empty(n, dtype=np.int64) for _ in range(2)]
    floats = [np.empty(n) for _ in range(4)]
    return (np.empty((n, nq)), np.empty((n, 4, 4)), *ints, *floats, np.empty(n, dtype=np.int64))


def _message(hexa: Hexapod, code: int, k: int, out: tuple, tol: float, retry) -> str:
    """The per-row API's message of row ``k`` solved in the compiled loop."""
    Q, _, _, iterations, residuals, ratios, kappas, _, bad = out
    if code == INVALID_INPUT:
        return retry(k)
    if code == OUT_OF_LIMITS:
        return str(hexa._limit_error(int(bad[k]), Q[k, bad[k]]))
    ratio = kappas[k] / hexa._solver(hexa._held_forward).home_kappa
    if code == 0:
        return _NEAR.format(ratio, NEAR_SINGULAR_FACTOR) if ratio > NEAR_SINGULAR_FACTOR else ""
    return outcome(code, tol, int(iterations[k]), float(residuals[k]), float(ratios[k]))[1]


def _result(
    hexa: Hexapod, out: tuple, tol: float, retry, fallback: dict[int, Solution], forward: bool, max_iter: int = 0
) -> BatchResult:
    """The :class:`BatchResult` of the compiled loops' outputs and the rows solved one by one.

    A row that used its ``max_iter`` steps is named as :meth:`.hexapod.Hexapod.forward` names it
    (:func:`.checks.failure_status`).
    """
    Q, poses, codes, iterations, residuals, _, kappas, signs, _ = out
    home_kappa = hexa._solver(hexa._held_forward).home_kappa
    near = ~(kappas <= NEAR_SINGULAR_FACTOR * home_kappa) & ((codes == 0) | (codes == OUT_OF_LIMITS)) & forward
    names = np.array(["converged", "max_iterations", "max_iterations", "singular", "singular", "uncertified"])
    status = np.where(codes == INVALID_INPUT, "invalid_input", np.where(codes == OUT_OF_LIMITS, "out_of_limits", ""))
    status = np.where(status == "", names[np.clip(codes, 0, 5)], status).astype(object)
    flags: list[tuple[str, ...]] = [("near_singular",) if f else () for f in near]
    messages = [""] * len(Q)
    for k in np.flatnonzero((codes != 0) | near):
        messages[k] = "" if codes[k] == _FALLBACK else _message(hexa, int(codes[k]), int(k), out, tol, retry)
        if status[k] == "max_iterations":
            outside = hexa._outside(Q[k])
            stalled = failure_status("max_iterations", messages[k], residuals[k], max_iter, outside, hexa.scale)
            status[k], messages[k] = stalled
            flags[k] = ("not_closed",) if status[k] == "out_of_limits" else flags[k]
    for j, sol in fallback.items():
        Q[j], poses[j], status[j], iterations[j], residuals[j] = (
            sol.q,
            sol.pose,
            sol.status,
            sol.iterations,
            sol.residual,
        )
        messages[j], flags[j], signs[j] = sol.message, sol.flags, sol.det_sign
    ok = status == "converged"
    poses[~ok] = np.nan
    lengths = np.full((len(Q), 6), np.nan)
    lengths[ok] = hexa.readings_of(Q[ok][:, hexa.closed_loop.prismatic_q])
    return BatchResult(
        poses, lengths, Q, status.astype(str), iterations, residuals, tuple(messages), tuple(flags), signs
    )


def _per_row(hexa: Hexapod, solve, rows, guess, warm: bool, retry, forward: bool) -> BatchResult:
    """The general path: one solve per row (hexapods or held sets without the compiled path)."""
    n = len(rows)
    out = _outputs(n, hexa.nq)
    out[2][:] = _FALLBACK
    fallback: dict[int, Solution] = {}
    for k, x in enumerate(rows):
        try:
            fallback[k] = sol = solve(x, guess)
        except HexapodError:
            out[0][k], out[2][k], out[3][k], out[4][k], out[7][k] = np.nan, INVALID_INPUT, 0, np.nan, 0
            continue
        if warm and sol.converged:
            guess = sol
    return _result(hexa, out, 0.0, retry, fallback, forward)


def _message_of(call) -> str:
    """The message of the error that ``call()`` raises on an invalid row."""
    try:
        call()
    except HexapodError as exc:
        return str(exc)
    return "invalid input"  # not reached: the compiled checks are the per-row checks


def forward_batch(hexa: Hexapod, readings, guess, warm: bool, tol, max_iter) -> BatchResult:
    """:meth:`.hexapod.Hexapod.forward_batch`."""
    rows = as_rows("lengths", readings, (6,))
    tol, max_iter = check_tolerance(tol), check_max_iter(max_iter)

    def solve(x: np.ndarray, g) -> Solution:
        return hexa.forward(x, g, tol=tol, max_iter=max_iter, check=False)

    def retry(k: int) -> str:
        return _message_of(lambda: solve(rows[k], None))

    solver = hexa._solver(hexa._held_forward)
    if not solver.compiled_loop:
        return _per_row(hexa, solve, rows, guess, warm, retry, True)
    from .newton.batch_kernels import forward_rows  # numba: only for a compiled solver

    announce(forward_rows)

    start = hexa._start(guess)  # a bad guess raises, as forward would on every row
    sign = solver.home_sign if guess is None else float(getattr(guess, "det_sign", 0))
    carry = np.array([sign, 0.0, float(guess is not None)])
    joints = rows if hexa._encoder is None else hexa.joints_of(rows)
    out, fallback = _outputs(len(rows), hexa.nq), {}
    settings = (tol, max_iter, NEAR_SINGULAR_FACTOR * solver.home_kappa)
    stroke = (hexa._stroke_lo, hexa._stroke_hi)
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
            solver.arrays,
            out,
        )
        if k < len(rows):  # the path is blocked, or a warm row is near a singularity: forward() says so
            g = (
                guess
                if not carry[1]
                else Solution(hexa.pose_of(start), start.copy(), rows[k], "converged", 0, 0.0, det_sign=int(carry[0]))
            )
            fallback[k] = sol = solve(rows[k], g)
            out[2][k] = _FALLBACK
            if warm and sol.converged:
                start[:], carry[:2] = sol.q, (sol.det_sign, 1.0)
            k += 1
    res = _result(hexa, out, tol, retry, fallback, True, max_iter)
    return _reviewed(hexa, res, rows, guess, warm, solve, set(fallback))


def _reviewed(
    hexa: Hexapod, res: BatchResult, rows: np.ndarray, guess, warm: bool, solve, done: set[int]
) -> BatchResult:
    """A 3-6 hexapod's rows checked against every assembly, as :meth:`.hexapod.Hexapod.forward` checks them.

    Each row from its own start (``guess``, or with ``warm`` the last converged row); the rows
    in ``done`` were solved by ``forward`` already. Once a warm row's status changes, the rows
    after it are solved by ``solve`` (``forward``) one by one.
    """
    if hexa._finder.exact is None:
        return res
    status, messages, flags = res.status.astype(object), list(res.messages), list(res.flags)
    poses, lengths, q, signs = res.poses.copy(), res.lengths.copy(), res.q.copy(), res.det_sign.copy()
    start, redo = guess, False
    for k in range(len(rows)):
        if status[k] == "invalid_input":
            continue
        if redo:  # forward() checks it itself
            new, changed = solve(rows[k], start), True
        elif k in done:
            new, changed = res.solution(k), False
        else:
            sol = res.solution(k)
            new = review(hexa._finder, sol, rows[k], start)
            changed, redo = new is not sol, warm and new.status != sol.status
        if changed:
            status[k], messages[k], flags[k], signs[k], q[k] = new.status, new.message, new.flags, new.det_sign, new.q
            res.iterations[k], res.residual[k] = new.iterations, new.residual
            poses[k] = new.pose if new.converged else np.nan
            lengths[k] = new.lengths if new.converged else np.nan
        if warm and new.converged:
            start = new
    return replace(
        res,
        poses=poses,
        lengths=lengths,
        q=q,
        status=status.astype(str),
        messages=tuple(messages),
        flags=tuple(flags),
        det_sign=signs,
    )


def inverse_batch(hexa: Hexapod, poses, guess, warm: bool, tol, max_iter) -> BatchResult:
    """:meth:`.hexapod.Hexapod.inverse_batch`."""
    if np.ndim(poses) == 2 and np.shape(poses)[1:] == (7,):
        xyzquat = as_rows("poses", poses, (7,))
        rows = poses_of_xyzquat(xyzquat, POSE_TOLERANCE)
    else:
        xyzquat, rows = None, as_rows("poses", poses, (4, 4))
    tol, max_iter = check_tolerance(tol), check_max_iter(max_iter)

    def solve(T: np.ndarray, g) -> Solution:
        return hexa.inverse(T, g, tol=tol, max_iter=max_iter, check=False)

    def retry(k: int) -> str:
        if xyzquat is not None and not np.all(np.isfinite(rows[k])):
            rule = f"x, y, z, qx, qy, qz, qw must be finite, the quaternion of norm 1 within {POSE_TOLERANCE:g}"
            return str(InputError("pose", xyzquat[k], rule))
        return _message_of(lambda: solve(rows[k], None))

    solver = hexa._solver(hexa._held_inverse)
    if not solver.compiled_loop:
        return _per_row(hexa, solve, rows, guess, warm, retry, False)
    from .newton.batch_kernels import inverse_rows  # numba: only for a compiled solver

    announce(inverse_rows)

    out = _outputs(len(rows), hexa.nq)
    settings = (tol, max_iter, POSE_TOLERANCE, MAX_POSITION)
    inverse_rows(rows, hexa._start(guess), warm, settings, solver.arrays, out)
    return _result(hexa, out, tol, retry, {}, False, max_iter)
