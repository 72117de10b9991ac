"""The result of a batch solve: :class:`BatchResult`, and how the compiled loops' outputs become one.

The compiled loops (:mod:`.newton.batch_kernels`) write per row an outcome code and numbers
(:func:`loop_outputs`); :func:`batch_result` turns them, and the rows solved one by one by
``forward`` / ``inverse``, into the statuses, messages and flags the per-row API gives. It
works on whole columns: a row costs Python time only when it has something to say (a failure,
a flag). :func:`as_rows` and :func:`poses_of_xyzquat` check and convert the batch inputs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import SupportsIndex

import numpy as np

from ..exceptions import InputError
from ..lie import quaternion_to_matrix
from .body_check import BodyCheck, message_of
from .certificate import NEAR_SINGULAR_FACTOR
from .engine import SolveEngine
from .input_checks import failure_status
from .newton.entries import plain
from .newton.outcomes import INVALID_INPUT, OUT_OF_LIMITS, outcome
from .newton.proven import Proof
from .newton.solver import Solution

FALLBACK = -1  # code of a row solved by forward() itself
_NEAR = "near a singularity: condition bound of the eliminated Jacobian {:.3g} times its home value (flag above {:g}); "
_NEAR += "another assembly may be close"
#: the status names of the loops' codes, and the index of each code's name (FALLBACK, -1, the last)
_NAMES = ("converged", "max_iterations", "singular", "uncertified", "out_of_limits", "invalid_input")
_NAME_OF_CODE = np.array([0, 1, 1, 2, 2, 3, 4, 5, 0])
_NEAR_FLAG: tuple[str, ...] = ("near_singular",)


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
        flags: (N,) each row's ``Solution.flags`` (``("near_singular",)``, ``("connected",)``, ... or ``()``).
        det_sign: (N,) each row's ``Solution.det_sign``.
        proofs: (N,) each row's ``Solution.proof``: the Krawczyk proof of a ``converged`` row
            solved from a guess (the batch's ``guess``, or with ``warm`` the last converged
            row; docs/solver.md), None for a row from home or one not proven because it is not
            ``converged``. With ``prove=False`` empty, or None but for the rows ``forward``
            solved itself (near a singularity: proven as ``forward`` proves them).
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
    proofs: tuple[Proof | None, ...] = ()

    @property
    def converged(self) -> np.ndarray:
        """(N,) True where the row is a valid closed configuration within all joint limits."""
        return self.status == "converged"

    def solution(self, k: int) -> Solution:
        """Row ``k`` as a :class:`Solution` (no Jacobian, no candidates): a guess for the next solve."""
        pose = self.poses[k] if self.status[k] == "converged" else np.full((4, 4), np.nan)
        row = (self.q[k].copy(), self.lengths[k].copy(), str(self.status[k]), int(self.iterations[k]))
        proof = self.proofs[k] if self.proofs else None
        return Solution(
            pose.copy(),
            *row,
            float(self.residual[k]),
            None,
            self.messages[k],
            self.flags[k],
            (),
            int(self.det_sign[k]),
            proof,
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
    return plain(arr)  # the compiled loops' one type (a read-only array: a copy)


def poses_of_xyzquat(x: np.ndarray, tolerance: float) -> np.ndarray:
    """(N, 4, 4) poses of rows ``x, y, z, qx, qy, qz, qw``.

    NaN where the quaternion's norm is not 1 within ``tolerance`` (or an entry is not finite).
    """
    with np.errstate(invalid="ignore"):
        norm = np.linalg.norm(x[:, 3:], axis=1)
        ok = np.abs(norm - 1.0) <= tolerance
    T = np.tile(np.eye(4), (len(x), 1, 1))
    T[:, :3, :3] = quaternion_to_matrix(x[:, 3:])
    T[:, :3, 3] = x[:, :3]
    T[~ok] = np.nan
    return T


def loop_outputs(n: int, nq: int) -> tuple:
    """The compiled loops' output arrays (see :mod:`.newton.batch_kernels`)."""
    ints = [np.empty(n, dtype=np.int64) for _ in range(2)]
    floats = [np.empty(n) for _ in range(4)]
    return (np.empty((n, nq)), np.empty((n, 4, 4)), *ints, *floats, np.empty(n, dtype=np.int64))


def _message(engine: SolveEngine, code: int, k: int, out: tuple, tol: float, retry) -> str:
    """The per-row API's message of row ``k`` solved in the compiled loop."""
    Q, _, _, iterations, residuals, ratios, kappas, _, bad = out
    if code == INVALID_INPUT:
        return retry(k)
    if code == OUT_OF_LIMITS:
        return str(engine.limit_error(int(bad[k]), Q[k, bad[k]]))
    ratio = kappas[k] / engine.solver(engine.held_forward).home_kappa
    if code == 0:
        return _NEAR.format(ratio, NEAR_SINGULAR_FACTOR) if ratio > NEAR_SINGULAR_FACTOR else ""
    return outcome(code, tol, int(iterations[k]), float(residuals[k]), float(ratios[k]))[1]


class _Statuses:
    """A column of status names kept as indices into a list of names (a name per row costs nothing)."""

    def __init__(self, codes: np.ndarray):
        self.names = list(_NAMES)
        self.index = _NAME_OF_CODE[codes]  # FALLBACK (-1) reads the last entry: "converged" until replaced

    def __getitem__(self, k: SupportsIndex) -> str:
        return self.names[self.index[k]]

    def __setitem__(self, k: SupportsIndex, name: str) -> None:
        if name not in self.names:
            self.names.append(name)
        self.index[k] = self.names.index(name)

    def column(self) -> np.ndarray:
        """The names as a string array (``<U`` as wide as the longest name present, as ``astype(str)`` gives)."""
        present = np.flatnonzero(np.bincount(self.index, minlength=len(self.names)))
        width = max((len(self.names[i]) for i in present), default=1)
        return np.array(self.names, dtype=f"<U{width}")[self.index]  # a name not present may be cut: never read


def batch_result(
    engine: SolveEngine, out: tuple, tol: float, retry, fallback: dict[int, Solution], forward: bool, max_iter: int = 0
) -> BatchResult:
    """The :class:`BatchResult` of the compiled loops' outputs and the rows solved one by one.

    A row that used its ``max_iter`` steps is named as :meth:`.hexapod.Hexapod.forward` names it
    (:func:`.input_checks.failure_status`).
    """
    Q, poses, codes, iterations, residuals, _, kappas, signs, _ = out
    home_kappa = engine.solver(engine.held_forward).home_kappa
    near = ~(kappas <= NEAR_SINGULAR_FACTOR * home_kappa) & ((codes == 0) | (codes == OUT_OF_LIMITS)) & forward
    status = _Statuses(codes)
    flags: list[tuple[str, ...]] = [()] * len(Q)
    for k in np.flatnonzero(near):
        flags[k] = _NEAR_FLAG
    messages = [""] * len(Q)
    for k in np.flatnonzero((codes != 0) | near):
        messages[k] = "" if codes[k] == FALLBACK else _message(engine, int(codes[k]), int(k), out, tol, retry)
        if status[k] == "max_iterations":
            outside = engine.outside(Q[k])
            stalled = failure_status("max_iterations", messages[k], residuals[k], max_iter, outside, engine.scale)
            status[k], messages[k] = stalled
            flags[k] = ("not_closed",) if status[k] == "out_of_limits" else flags[k]
    for j, sol in fallback.items():
        Q[j], poses[j], iterations[j], residuals[j] = sol.q, sol.pose, sol.iterations, sol.residual
        status[j], messages[j], flags[j], signs[j] = sol.status, sol.message, sol.flags, sol.det_sign
    if engine.body is not None:
        _judge_rows(engine.body, Q, status, messages, flags, set(fallback), forward)
    failed = status.index != 0
    lengths = engine.readings_of(Q[:, engine.closed_loop.prismatic_q])  # row by row as readings_of(Q[ok][:, pq])
    if failed.any():  # a boolean assignment costs tens of microseconds even when it selects nothing
        poses[failed] = np.nan
        lengths[failed] = np.nan
    proofs: list[Proof | None] = []  # the proofs of rows forward() solved, when it proved one
    if any(sol.proof is not None for sol in fallback.values()):
        proofs = [None] * len(Q)
        for j, sol in fallback.items():
            proofs[j] = sol.proof
    column, messages_, flags_ = status.column(), tuple(messages), tuple(flags)
    return BatchResult(poses, lengths, Q, column, iterations, residuals, messages_, flags_, signs, tuple(proofs))


def _judge_rows(
    body: BodyCheck,
    Q: np.ndarray,
    status: _Statuses,
    messages: list[str],
    flags: list[tuple[str, ...]],
    judged: set[int],
    forward: bool,
) -> None:
    """The body check of each converged row not in ``judged``: a flag (``forward``) or the status, as per row."""
    for k in np.flatnonzero(status.index == 0):
        if int(k) in judged:
            continue
        found = body.violations(Q[k])
        if found:
            msg = message_of(found, forward)
            messages[k] = f"{messages[k]}; {msg}" if messages[k] else msg
            if forward:
                flags[k] = flags[k] + tuple(name for name, _ in found)
            else:
                status[k] = found[0][0]
