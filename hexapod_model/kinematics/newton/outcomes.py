"""Outcome codes of the compiled solves and loops, their statuses and messages, and the :class:`Solution` built fast.

Plain integers shared by the numba code (:mod:`.newton`, :mod:`.batch_kernels`, where they are
compile-time constants) and the Python code that reads their results (:mod:`.batch`), which
must not import numba for a hexapod solved with the NumPy kernels.
"""

from __future__ import annotations

import numpy as np

from .proven import Proof, built
from .solver import SINGULAR_PIVOT_RATIO, Solution

#: codes of one Newton iteration (:func:`.newton.iterate_schur`, :func:`.newton.iterate_blocks`)
CONVERGED, NO_CONVERGENCE, FLIPPED, SINGULAR, START_SINGULAR, UNCERTIFIED = 0, 1, 2, 3, 4, 5
#: further codes of a row of the batch loops (:mod:`.batch_kernels`)
OUT_OF_LIMITS, INVALID_INPUT = 6, 7


def outcome(code: int, tol: float, iterations: int, norm: float, ratio: float) -> tuple[str, str]:
    """Status and message of an iteration's outcome code (the general path's words)."""
    if code == CONVERGED:
        return "converged", ""
    if code == FLIPPED:
        return "max_iterations", "converged to a spurious closure flipped by 180 deg"
    if code == NO_CONVERGENCE:
        return "max_iterations", f"no convergence to {tol:g} in {iterations} iterations (residual {norm:.3g})"
    if code == SINGULAR:
        return "singular", f"constraint Jacobian singular (pivot ratio {ratio:.2g} < {SINGULAR_PIVOT_RATIO:g})"
    if code == START_SINGULAR:
        return "singular", f"start is singular (pivot ratio {ratio:.2g} < {SINGULAR_PIVOT_RATIO:g}), no step taken"
    return "uncertified", "contraction or determinant sign check failed"


def new_solution(
    pose: np.ndarray,
    q: np.ndarray,
    lengths: np.ndarray,
    status: str,
    iterations: int,
    residual: float,
    jacobian: np.ndarray | None = None,
    message: str = "",
    flags: tuple[str, ...] = (),
    candidates: tuple[np.ndarray, ...] = (),
    det_sign: int = 0,
    proof: Proof | None = None,
) -> Solution:
    """``Solution(pose, q, ...)``, the same object, built at a quarter of the frozen dataclass's ``__init__`` cost.

    For the solves' hot paths (a warm solve is tens of microseconds): the fields go into the
    instance's ``__dict__`` at once instead of one frozen ``__setattr__`` each.
    """
    fields = {
        "pose": pose,
        "q": q,
        "lengths": lengths,
        "status": status,
        "iterations": iterations,
        "residual": residual,
        "jacobian": jacobian,
        "message": message,
        "flags": flags,
        "candidates": candidates,
        "det_sign": det_sign,
        "proof": proof,
    }
    return built(Solution, fields)
