"""Kinematic evaluation: the 6x6 leg-rate / platform-twist relation of the closed-loop model.

For a hexapod with ideal legs (Jakobović and Jelenković (2002) eq. 4) the relation is the textbook one,
``dl_i = w_i . v + (p_i x w_i) . w``. With offset Cardan joints (Bem et al. (2026)) or guideway legs it
is not; here it is derived from the closure constraints of any URDF by eliminating the
passive joints.

Per leg ``i`` the linearised closure (rows 6 for 6-D closures, 3 for 3-D ones) is

    A_i xi + B_i dtheta_i + c_i dl_i = 0,

with ``xi`` the platform free-flyer velocity (Pinocchio LOCAL frame), ``dtheta_i`` the leg's
passive joint rates and ``dl_i`` its reading rate. ``B_i`` has one column fewer than rows, so
a vector ``n_i`` spans its left null space; ``n_i^T A_i xi + (n_i^T c_i) dl_i = 0`` gives row
``i`` of the Jacobian.

Convention exposed (as Jakobović and Jelenković (2002)): ``dl = J @ [v; w]`` where ``v`` (m/s) is the velocity of the
platform frame origin and ``w`` (rad/s) the angular velocity, BOTH EXPRESSED IN THE BASE FRAME;
``dl`` in m/s. Singular values therefore mix units (m/m and m/rad): scale lengths by
``length_unit`` to compare hexapods of different size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.hexapod import Hexapod


@dataclass(frozen=True)
class KinematicEvaluation:
    """The Jakobović and Jelenković (2002) §III figures of one configuration.

    Attributes:
        jacobian: (6, 6) ``dl = J [v; w]`` (base frame, see module doc), in ``length_unit``.
        singular_values: (6,) descending.
        condition_number: ``sigma_max / sigma_min`` (``inf`` when singular).
        sigma_min: smallest singular value.
        abs_det: ``|det J|`` = product of the singular values.
        length_unit: metres per length unit used (1.0 = SI).
    """

    jacobian: np.ndarray
    singular_values: np.ndarray
    condition_number: float
    sigma_min: float
    abs_det: float
    length_unit: float = 1.0


def leg_jacobian_local(hexa: Hexapod, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eliminated leg Jacobian in the platform frame, and a per-leg singularity ratio.

    ``(J_local, null_ratio)``: ``dl = J_local @ xi`` with ``xi`` the free-flyer velocity in the
    platform (LOCAL) frame, and per leg ``|n^T c| / |c|`` (0 when the reading cannot move with
    the platform held, i.e. the leg itself is at a singular configuration).
    """
    clm = hexa.closed_loop
    _, G = hexa.engine.solver(()).evaluate(np.asarray(q, dtype=float))  # every joint free; this thread's buffers
    rows = 6 if clm.kind == "6d" else 3
    m = clm.model
    ff = np.arange(clm.platform_v, clm.platform_v + 6)
    J = np.empty((6, 6))
    ratio = np.empty(6)
    for i, leg in enumerate(clm.legs):
        Gi = G[i * rows : (i + 1) * rows]
        passive = [m.joints[j].idx_v for j in leg.joints if j != leg.prismatic]
        c = Gi[:, clm.prismatic_v[i]]
        U = np.linalg.svd(Gi[:, passive], full_matrices=True)[0]
        n = U[:, -1]
        nc = float(n @ c)
        ratio[i] = abs(nc) / max(float(np.linalg.norm(c)), 1e-300)
        J[i] = -(n @ Gi[:, ff]) / nc if nc != 0.0 else np.inf
    return J, ratio


def leg_jacobian(hexa: Hexapod, q: np.ndarray) -> np.ndarray:
    """(6, 6) ``dl = J [v; w]`` at configuration ``q``; ``v``, ``w`` in the BASE frame (m/s, rad/s)."""
    J_local, _ = leg_jacobian_local(hexa, q)
    R = hexa.pose_of(np.asarray(q, dtype=float))[:3, :3]
    # xi_local = [R^T v; R^T w]
    return np.hstack([J_local[:, :3] @ R.T, J_local[:, 3:] @ R.T])


def evaluate_jacobian(J: np.ndarray, length_unit: float = 1.0) -> KinematicEvaluation:
    """Singular-value figures of ``J`` (SI, base frame) with lengths expressed in ``length_unit`` m.

    A leg rate in units is ``dl / u``, a platform speed ``v / u``, an angular speed unchanged:
    the translational columns keep their values, the rotational ones are divided by ``u``.
    """
    J = np.asarray(J, dtype=float)
    Js = np.hstack([J[:, :3], J[:, 3:] / length_unit])
    if not np.all(np.isfinite(Js)):
        s = np.full(6, np.nan)
        return KinematicEvaluation(Js, s, float("inf"), 0.0, 0.0, length_unit)
    s = np.linalg.svd(Js, compute_uv=False)
    cond = float(s[0] / s[-1]) if s[-1] > 0 else float("inf")
    return KinematicEvaluation(Js, s, cond, float(s[-1]), float(np.prod(s)), length_unit)


def kinematic_evaluation(hexa: Hexapod, q: np.ndarray, length_unit: float = 1.0) -> KinematicEvaluation:
    """Jakobović and Jelenković (2002) §III figures (singular values, condition number, sigma_min, |det J|) at ``q``."""
    return evaluate_jacobian(leg_jacobian(hexa, q), length_unit)


def textbook_jacobian(base_points: np.ndarray, platform_points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Jakobović and Jelenković (2002) eq.

    4 for ideal legs between ``b_i`` (base frame) and ``p_i`` (platform frame): rows ``[w_i^T, (R p_i x w_i)^T]``
    with ``w_i`` the unit leg vector, base frame, SI.
    """
    R, t = pose[:3, :3], pose[:3, 3]
    rp = np.asarray(platform_points) @ R.T
    d = t + rp - np.asarray(base_points)
    w = d / np.linalg.norm(d, axis=1, keepdims=True)
    return np.hstack([w, np.cross(rp, w)])
