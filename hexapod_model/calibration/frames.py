"""The measurement model of a calibration: what a measuring device sees of a platform pose.

A measured pose ``M`` (motion capture, laser tracker, the robot moving the plate) is the pose
of a marker (or tool) frame in the device's frame:

    M = T_mb @ P @ T_pm,

``T_mb`` the base frame in the measuring frame (the *measuring frame* transform), ``P`` the
platform pose in the base frame (the kinematic model), ``T_pm`` the marker frame in the
platform frame (the *marker frame* transform). Neither transform is known exactly: both are
unknowns of the calibration, fitted here alone for a fixed model (:func:`fit_frames`, also a
rigid alignment for any model) or with the geometry (``calibration.identify``).

Residual of pose ``k`` (6 rows): ``(p_model - p_measured) / sigma_p`` and
``vex(skew(R_model R_measured^T)) / sigma_r`` (the rotation error in the measuring frame,
``sin(angle) * axis``), so that each row is in units of its stated noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import InputError
from ..lie import log3, rotation_angle

ERROR_KEYS = (
    "translation_mean_mm",
    "translation_std_mm",
    "translation_max_mm",
    "rotation_mean_deg",
    "rotation_std_deg",
    "rotation_max_deg",
)


@dataclass(frozen=True)
class Noise:
    """Stated measurement noise of the measured poses.

    Sigma of each position coordinate (m) and of each rotation component (rad).
    """

    position_m: float = 1e-4
    rotation_rad: float = float(np.radians(0.05))

    def __post_init__(self) -> None:
        for name, v in (("position noise", self.position_m), ("rotation noise", self.rotation_rad)):
            if not (np.isfinite(v) and v > 0):
                raise InputError(name, v, "must be a positive standard deviation")

    @property
    def weights(self) -> np.ndarray:
        """(6,) row weights ``1 / sigma``."""
        return np.array([1 / self.position_m] * 3 + [1 / self.rotation_rad] * 3)


def predict(T_mb: np.ndarray, P: np.ndarray, T_pm: np.ndarray) -> np.ndarray:
    """(N, 4, 4) measured-frame poses ``T_mb @ P @ T_pm`` of platform poses ``P`` (N, 4, 4)."""
    return T_mb @ P @ T_pm


def pose_errors(predicted: np.ndarray, measured: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Translation (mm) and rotation (deg) error of each pose (the paper's eqs. 26-27)."""
    dp = np.linalg.norm(predicted[:, :3, 3] - measured[:, :3, 3], axis=1) * 1e3
    return dp, np.degrees(rotation_angle(measured[:, :3, :3], predicted[:, :3, :3]))


def error_stats(errors: tuple[np.ndarray, np.ndarray]) -> dict:
    """Mean, standard deviation (n-1) and maximum of translation (mm) and rotation (deg) errors."""
    out = {}
    for values, unit in ((errors[0], "translation"), (errors[1], "rotation")):
        suffix = "mm" if unit == "translation" else "deg"
        out[f"{unit}_mean_{suffix}"] = float(np.mean(values))
        out[f"{unit}_std_{suffix}"] = float(np.std(values, ddof=1)) if values.size > 1 else 0.0
        out[f"{unit}_max_{suffix}"] = float(np.max(values))
    return out


def residual(M: np.ndarray, measured: np.ndarray, noise: Noise) -> np.ndarray:
    """(N, 6) weighted residuals of predicted poses ``M`` against ``measured``."""
    E = M[:, :3, :3] @ np.swapaxes(measured[:, :3, :3], 1, 2)
    rot = 0.5 * np.stack([E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], axis=1)
    return np.hstack([M[:, :3, 3] - measured[:, :3, 3], rot]) * noise.weights


def twist_jacobian(A: np.ndarray, B: np.ndarray, measured: np.ndarray, noise: Noise) -> np.ndarray:
    """(N, 6, 6) derivative of :func:`residual` of ``M = A exp(d) B`` w.r.t. the twist ``d``.

    ``d = [v; w]``, taken at ``d = 0``, for (N, 4, 4) ``A`` and ``B``.
    """
    RA, tB = A[:, :3, :3], B[:, :3, 3]
    M = A @ B
    E = M[:, :3, :3] @ np.swapaxes(measured[:, :3, :3], 1, 2)
    H = 0.5 * (np.trace(E, axis1=1, axis2=2)[:, None, None] * np.eye(3) - E)
    skew = np.zeros((len(A), 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -tB[:, 2], tB[:, 1], -tB[:, 0]
    skew -= np.swapaxes(skew, 1, 2)
    out = np.zeros((len(A), 6, 6))
    out[:, :3, :3] = RA
    out[:, :3, 3:] = -RA @ skew
    out[:, 3:, 3:] = H @ RA
    return out * noise.weights[None, :, None]


def least_squares_step(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``argmin |J x - r|`` for a tall, well-conditioned ``J`` (the 12 frame columns).

    By the normal equations: a 12 x 12 solve instead of a factorisation of the tall matrix.
    """
    return np.linalg.solve(J.T @ J, J.T @ r)


def initial_frames(P: np.ndarray, measured: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form estimate of ``(T_mb, T_pm)`` from model poses ``P`` and ``measured`` (N, 4, 4).

    The marker rotation from the relative rotations between consecutive poses (their rotation
    vectors differ by it), the measuring rotation as the mean of ``R_M R_pm^T R_P^T``, then both
    translations by linear least squares. Needs poses that rotate about different axes.
    """
    RP, RM = P[:, :3, :3], measured[:, :3, :3]
    a = log3(np.swapaxes(RP[:-1], 1, 2) @ RP[1:])
    b = log3(np.swapaxes(RM[:-1], 1, 2) @ RM[1:])
    R_pm = np.eye(3)
    if len(a) >= 2 and np.linalg.matrix_rank(a, tol=1e-3) >= 2:
        U, _, Vt = np.linalg.svd(a.T @ b)  # b = R_pm^T a
        D = np.diag([1.0, 1.0, np.linalg.det(U @ Vt)])
        R_pm = U @ D @ Vt
    U, _, Vt = np.linalg.svd(np.sum(RM @ R_pm.T @ np.swapaxes(RP, 1, 2), axis=0))
    R_mb = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    n = len(P)
    A = np.zeros((3 * n, 6))
    A[:, :3] = np.tile(np.eye(3), (n, 1))
    A[:, 3:] = (R_mb @ RP).reshape(3 * n, 3)
    rhs = (measured[:, :3, 3] - P[:, :3, 3] @ R_mb.T).reshape(-1)
    t = np.linalg.lstsq(A, rhs, rcond=None)[0]
    T_mb, T_pm = np.eye(4), np.eye(4)
    T_mb[:3, :3], T_mb[:3, 3] = R_mb, t[:3]
    T_pm[:3, :3], T_pm[:3, 3] = R_pm, t[3:]
    return T_mb, T_pm


def frame_jacobian(T_mb: np.ndarray, P: np.ndarray, T_pm: np.ndarray, measured: np.ndarray, noise: Noise):
    """(N, 6, 12) derivative of the residuals w.r.t. right perturbations of ``T_mb`` then ``T_pm``."""
    n = len(P)
    eye = np.broadcast_to(np.eye(4), (n, 4, 4))
    J_mb = twist_jacobian(np.broadcast_to(T_mb, (n, 4, 4)), P @ T_pm, measured, noise)
    J_pm = twist_jacobian(T_mb @ P @ T_pm, eye, measured, noise)
    return np.concatenate([J_mb, J_pm], axis=2)


def fit_frames(
    P: np.ndarray, measured: np.ndarray, noise: Noise, start: tuple[np.ndarray, np.ndarray] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares ``(T_mb, T_pm)`` for fixed model poses ``P``.

    A rigid alignment of the measuring device to the model (Gauss-Newton from
    :func:`initial_frames` or ``start``).
    """
    T_mb, T_pm = initial_frames(P, measured) if start is None else start
    for _ in range(50):
        r = residual(predict(T_mb, P, T_pm), measured, noise).reshape(-1)
        J = frame_jacobian(T_mb, P, T_pm, measured, noise).reshape(-1, 12)
        step = -least_squares_step(J, r)
        T_mb = T_mb @ pin.exp6(step[:6]).homogeneous
        T_pm = T_pm @ pin.exp6(step[6:]).homogeneous
        if np.max(np.abs(step)) < 1e-12:
            break
    return T_mb, T_pm
