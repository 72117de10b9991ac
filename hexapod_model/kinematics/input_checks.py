"""Checks of what a caller hands the solver: readings, poses, configurations, ``tol``, ``max_iter``.

Every check either returns the value as the solver needs it or raises :class:`InputError`
naming the value and the rule; nothing is reshaped, clipped, normalised or cast silently
(a 2x3 list is not six readings, a complex number is not a reading).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin

from ..exceptions import GeometryError, InputError
from .newton import numpy_kernels
from .newton.entries import plain
from .newton.solver import Solution

POSE_TOLERANCE = 1e-6  # max deviation of a pose from a rigid transform, of a start quaternion from unit norm
MAX_POSITION = 1e6  # m: largest platform position coordinate accepted (beyond it the residual loses every digit)
LIMIT_SLACK = 1e-12  # m or rad: how far a reading or joint may pass its limit (rounding)
MAX_TOL = 1e-6  # largest closure residual (m, rad) a caller may accept as converged
RANK_TOL = 1e-9  # singular values below this fraction of the largest count as zero (held sets)


def real_array(name: str, values: Any, expected: str) -> np.ndarray:
    """``values`` as a float array if they are real numbers (any shape), else :class:`InputError`.

    Refuses complex values, text, booleans and ragged nesting rather than converting them. The
    array is the compiled entries' one type (:func:`.newton.entries.plain`): float64,
    C-contiguous, aligned and writeable (a copy when ``values`` is not).
    """
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError):
        raise InputError(name, values, expected) from None
    kind = arr.dtype.kind
    if kind in "iuf":
        return plain(arr)
    if kind == "c":
        raise InputError(name, values, f"{expected}; got complex values")
    if kind == "O":
        try:
            return plain(arr.astype(float))
        except (TypeError, ValueError):
            raise InputError(name, values, expected) from None
    raise InputError(name, values, f"{expected}; got {arr.dtype} data")


def check_vector(name: str, values: Any, n: int) -> np.ndarray:
    """``values`` as a finite float array of shape ``(n,)``, or :class:`InputError`."""
    arr = real_array(name, values, f"expected {n} real numbers")
    if arr.ndim == 1 and arr.size != n:
        raise InputError(name, values, f"expected {n} values, got {arr.size}")
    if arr.shape != (n,):
        raise InputError(name, values, f"expected a flat sequence of {n} values, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(name, values, "values must be finite (found NaN or inf)")
    return arr


def check_pose(pose: Any, rigid_error: Callable[[np.ndarray], float] = numpy_kernels.rigid_error) -> np.ndarray:
    """``pose`` (4x4 array or ``pin.SE3``) as a valid 4x4 rigid transform, or :class:`InputError`.

    The rotation must be orthonormal and the bottom row ``0 0 0 1`` within
    :data:`POSE_TOLERANCE`; the position coordinates at most :data:`MAX_POSITION` metres.
    ``rigid_error`` measures the distance from a rigid transform (a solver passes its compiled kernel).
    """
    if type(pose) is np.ndarray and pose.dtype == np.float64 and pose.shape == (4, 4):
        T = plain(pose)  # the common case: no conversion (a read-only or strided pose: a copy)
    elif isinstance(pose, pin.SE3):
        T = np.array(pose.homogeneous)
    else:
        T = real_array("pose", pose, "expected a 4x4 matrix of real numbers")
        if T.shape != (4, 4):
            raise InputError("pose", pose, f"expected a 4x4 matrix, got shape {T.shape}")
    err = rigid_error(T)  # inf when an entry is NaN or inf
    if err <= POSE_TOLERANCE and abs(T[0, 3]) <= MAX_POSITION and abs(T[1, 3]) <= MAX_POSITION:
        if abs(T[2, 3]) <= MAX_POSITION:
            return T
    if not np.all(np.isfinite(T)):
        raise InputError("pose", pose, "values must be finite (found NaN or inf)")
    if not err <= POSE_TOLERANCE:
        raise InputError(
            "pose",
            pose,
            f"not a rigid transform: orthonormality/det/bottom-row error {err:.2g} exceeds {POSE_TOLERANCE:g}",
        )
    raise InputError("pose", pose, f"position coordinates must be at most {MAX_POSITION:g} m in magnitude")


def check_configuration(name: str, q: Any, nq: int, platform_q: int) -> np.ndarray:
    """A start configuration: ``nq`` finite numbers whose platform quaternion has unit norm."""
    if type(q) is np.ndarray and q.dtype == np.float64 and q.shape == (nq,):  # the trackers' guesses
        arr = q
    else:
        arr = real_array(name, q, f"expected a Solution or a configuration of {nq} real numbers")
        if arr.shape != (nq,):
            raise InputError(name, q, f"expected a Solution or a configuration of {nq} numbers, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError(name, q, "values must be finite (found NaN or inf)")
    norm = math.hypot(*arr[platform_q + 3 : platform_q + 7].tolist())  # no overflow (and no warning) at 1e200
    if not abs(norm - 1.0) <= POSE_TOLERANCE:
        raise InputError(
            name,
            q,
            f"the platform quaternion q[{platform_q + 3}:{platform_q + 7}] has norm {norm:.6g}, not 1 within "
            f"{POSE_TOLERANCE:g} (start from Hexapod.q_home or a Solution)",
        )
    return arr.copy()


def check_guess(guess: Any, nq: int, platform_q: int) -> np.ndarray:
    """The start configuration of ``guess`` (a :class:`Solution` or an array), or :class:`InputError`."""
    if isinstance(guess, Solution):
        raise InputError(
            "guess",
            f"Solution with a configuration of shape {np.shape(guess.q)}",
            f"comes from another hexapod (this one has nq = {nq})",
        )
    if not isinstance(guess, (np.ndarray, list, tuple)):
        raise InputError("guess", guess, f"expected None, a Solution or a configuration of {nq} numbers")
    return check_configuration("guess", guess, nq, platform_q)


def check_home_conditioning(G: np.ndarray, source: str, limit: float) -> float:
    """2-norm condition number of ``G``, the direct-kinematics Jacobian at home.

    Raises:
        GeometryError: the condition number exceeds ``limit`` (or ``G`` is singular).
    """
    s = np.linalg.svd(G, compute_uv=False)
    kappa = float(s[0] / s[-1]) if s[-1] > 0 else float("inf")
    if not kappa <= limit:
        raise GeometryError(
            f"{source}: home condition number",
            kappa,
            f"the direct-kinematics constraint Jacobian at home exceeds the limit {limit:g}: the six readings "
            "do not fix the platform there (parallel, coplanar or coincident legs?)",
        )
    return kappa


def free_directions(G: np.ndarray) -> tuple[int, int]:
    """(free directions, rank) of a closure Jacobian: columns minus numerical rank (:data:`RANK_TOL`)."""
    s = np.linalg.svd(G, compute_uv=False)
    rank = int(np.sum(s > RANK_TOL * s[0])) if s.size and s[0] > 0 else 0
    return G.shape[1] - rank, rank


def check_held_set(names: list[str], free: int, rank: int) -> None:
    """:class:`InputError` when holding ``names`` leaves ``free`` > 0 directions of motion."""
    if free:
        raise InputError(
            "held joints",
            names,
            f"under-determined: {free} free direction{'s' if free > 1 else ''} of motion (closure "
            f"Jacobian rank {rank} < {rank + free} free velocities); hold {free} more independent joint value(s)",
        )


def check_tolerance(tol: Any) -> float:
    """``tol`` as a float in ``(0, MAX_TOL]``, or :class:`InputError`."""
    if isinstance(tol, bool) or not isinstance(tol, numbers.Real):
        raise InputError("tol", tol, f"expected a number in (0, {MAX_TOL:g}] (closure residual, m and rad)")
    value = float(tol)
    if not 0.0 < value <= MAX_TOL:
        raise InputError("tol", tol, f"must lie in (0, {MAX_TOL:g}] (closure residual, m and rad)")
    return value


def check_max_iter(max_iter: Any) -> int:
    """``max_iter`` as an int >= 0, or :class:`InputError`."""
    if isinstance(max_iter, bool) or not isinstance(max_iter, numbers.Integral) or max_iter < 0:
        raise InputError("max_iter", max_iter, "expected a whole number of Newton steps >= 0")
    return int(max_iter)


#: closure residual (m, rad mixed) above which a solve that used its whole step budget stalled:
#: Newton near a closed configuration converges quadratically, so after ``STALL_STEPS`` steps it is
#: far from every one (no real assembly, or none reachable from the start)
STALL_RESIDUAL = 1e-6
STALL_STEPS = 20  # a caller's max_iter below this keeps ``max_iterations`` (it asked for few steps)


def failure_status(
    status: str, message: str, residual: float, max_iter: int, outside: str | None, scale: float = 1.0
) -> tuple[str, str]:
    """The status of a solve that did not converge: what happened, and what the caller can do.

    Args:
        status: the iteration's status (``max_iterations`` is the only one reclassified).
        message: its message.
        residual: the last closure residual (m, rad mixed).
        max_iter: the caller's step limit.
        outside: the limit error of the last iterate (one line), ``None`` when within the limits.
        scale: the hexapod's size ratio (:attr:`.hexapod.Hexapod.scale`) ``STALL_RESIDUAL`` scales by.

    Returns:
        ``out_of_limits`` when the last iterate left the stroke or joint limits (no closed
        configuration was found within them: the :class:`Solution` carries the flag
        ``not_closed``), ``not_found`` when the iteration stalled far from
        any closure (residual above ``STALL_RESIDUAL`` after at least ``STALL_STEPS`` steps),
        else ``status`` unchanged; with the message saying why.
    """
    if status != "max_iterations":
        return status, message
    if outside is not None:
        msg = f"no closed configuration found within the limits ({message}); the iterate left them: {outside}"
        return "out_of_limits", msg
    if residual > STALL_RESIDUAL * scale and max_iter >= STALL_STEPS:
        why = "the readings or pose may admit no real assembly, or none reachable from the start"
        return "not_found", f"no closed configuration found, the iteration stalled ({message}): {why}"
    return status, message
