"""Statics of the locked fixture: leg (brake) forces and Cardan reaction moments under a platform wrench.

Model (docs/statics.md): rigid, massless links, frictionless passive joints, the six measured
prismatic joints held by their brakes, small deflections. Each leg is a serial chain whose only
loaded joint is the prismatic one, so the wrench it exerts on the platform is reciprocal to its
passive joints: one wrench per leg, known up to its magnitude. That wrench is the row of the
eliminated closure Jacobian (:func:`~hexapod_model.analysis.jacobian.leg_jacobian`,
``dl = J [v; w]``, base frame, platform origin): by virtual work, a leg whose prismatic joint
carries the force ``tau_i`` (N, pushing the leg longer) does the power ``tau_i dl_i = tau_i J_i . xi``
on any platform twist ``xi``, so it exerts the wrench ``tau_i J_i^T`` on the platform. Equilibrium
with an external wrench ``W`` (force and moment about the platform origin, base frame) gives

    J^T tau + W = 0,   tension t = -tau = J^-T W   (N, positive when the leg is pulled).

With intersecting Cardan axes the row is ``[u_i; r_i x u_i]``: a force along the leg through both
joint centres (a two-force member). With offset axes (Bem et al. (2026)) it is not: the leg's force
has a transverse part and a moment about each Cardan centre, which the joints carry.

The same Jacobian gives the stiffness of the locked fixture when each leg is an axial spring
``k_i`` (N/m) and everything else is rigid: ``K = J^T diag(k) J`` (N/m, N, N m/rad blocks; the
load-dependent geometric stiffness is neglected).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..description.plausibility import check_pose_position
from ..exceptions import InputError, SingularityError
from ..kinematics.hexapod import Hexapod
from ..kinematics.input_checks import check_vector
from .jacobian import leg_jacobian

FRAMES = ("platform", "base")
#: condition number of the leg Jacobian (m, rad) above which the legs cannot hold every wrench: singular
SINGULAR_CONDITION = 1e12


@dataclass(frozen=True)
class LegLoads:
    """Loads of the locked fixture at one pose under one platform wrench (SI, base frame).

    Attributes:
        pose: (4, 4) platform pose (base frame, m).
        wrench: (6,) the applied wrench as force (N) and moment about the platform origin (N m), base frame.
        axial_force: (6,) force in each leg's prismatic joint, what its brake holds (N, positive in tension).
        leg_force: (6, 3) force each leg exerts on the platform (N, base frame).
        platform_moment: (6, 3) moment of that force system about the leg's platform joint centre (N m, base
            frame): what the platform Cardan (or ball) joint carries; zero for intersecting axes and balls.
        base_moment: (6, 3) the same about the leg's base joint centre (N m, base frame).
        leg_axis: (6, 3) unit vectors from each leg's base to its platform joint centre (base frame).
        jacobian: (6, 6) the eliminated leg Jacobian ``dl = J [v; w]`` at the pose (m/m, m/rad).
    """

    pose: np.ndarray
    wrench: np.ndarray
    axial_force: np.ndarray
    leg_force: np.ndarray
    platform_moment: np.ndarray
    base_moment: np.ndarray
    leg_axis: np.ndarray
    jacobian: np.ndarray

    @property
    def largest_axial_force(self) -> float:
        """Largest ``|axial_force|`` over the legs (N)."""
        return float(np.abs(self.axial_force).max())

    @property
    def transverse_force(self) -> np.ndarray:
        """(6,) magnitude of each leg's force perpendicular to :attr:`leg_axis` (N); zero for two-force members."""
        return np.linalg.norm(np.cross(self.leg_force, self.leg_axis), axis=1)

    def margin(self, brake_capacity: float) -> float:
        """Load margin of the brakes (N): ``brake_capacity`` minus the largest ``|axial_force|``; < 0: slips."""
        return float(brake_capacity) - self.largest_axial_force


def wrench_at_origin(
    pose: np.ndarray, wrench: ArrayLike, frame: str = "platform", point: ArrayLike | None = None
) -> np.ndarray:
    """A wrench as force and moment about the platform origin, base frame.

    Args:
        pose: (4, 4) platform pose (base frame, m).
        wrench: ``(fx, fy, fz, mx, my, mz)`` (N, N m) acting at ``point``.
        frame: ``"platform"``: the wrench and ``point`` are in platform coordinates (a tool point fixed to
            the platform); ``"base"``: both in base coordinates.
        point: where the force acts (m, in ``frame``); default the platform origin.

    Raises:
        InputError: a wrench or point that is not 6 (3) finite numbers, or an unknown frame.
    """
    w = check_vector("wrench", wrench, 6)
    if frame not in FRAMES:
        raise InputError("frame", frame, f"expected one of {FRAMES}")
    R, o = pose[:3, :3], pose[:3, 3]
    force, moment = w[:3], w[3:]
    if point is None:
        at = o
    else:
        p = check_vector("point", point, 3)
        at = o + R @ p if frame == "platform" else p
    if frame == "platform":
        force, moment = R @ force, R @ moment
    return np.r_[force, moment + np.cross(at - o, force)]


def joint_centres(hexa: Hexapod, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(6, 3) platform and (6, 3) base joint centres of the legs at ``q`` (base frame, m).

    Platform: the closure's tip frame (the platform Cardan centre, the midpoint of the common normal of
    its axes, or the ball's centre). Base: the midpoint of the origins of the leg's first two passive
    joints, the base Cardan's two axes (for guideway legs the slider's Cardan, wherever the slider is).
    The same for a geometry, a URDF or an MJCF.
    """
    m = hexa.model
    d = m.createData()
    pin.framesForwardKinematics(m, d, np.asarray(q, dtype=float))
    legs = hexa.closed_loop.legs
    platform = np.array([d.oMf[leg.tip_frame].translation for leg in legs])
    base = np.empty((6, 3))
    for i, leg in enumerate(legs):
        a, b = [j for j in leg.joints if j != leg.prismatic][:2]
        base[i] = (d.oMi[a].translation + d.oMi[b].translation) / 2
    return platform, base


def loads_at(
    hexa: Hexapod, q: np.ndarray, wrench: ArrayLike, frame: str = "platform", point: ArrayLike | None = None
) -> LegLoads:
    """:class:`LegLoads` at a solved configuration ``q`` (see :func:`leg_forces` for the wrench).

    Raises:
        SingularityError: the leg Jacobian's condition number exceeds :data:`SINGULAR_CONDITION` (or is
            infinite): at a singularity some wrench needs unbounded leg forces.
    """
    q = np.asarray(q, dtype=float)
    pose = hexa.pose_of(q)
    W = wrench_at_origin(pose, wrench, frame, point)
    J = leg_jacobian(hexa, q)
    cond = float(np.linalg.cond(J)) if np.all(np.isfinite(J)) else float("inf")
    if not cond <= SINGULAR_CONDITION:
        raise SingularityError(
            None,
            f"singular: the leg Jacobian's condition number {cond:.3g} exceeds {SINGULAR_CONDITION:g} at this pose: "
            "the locked legs cannot hold every wrench there",
        )
    tension = np.linalg.solve(J.T, W)
    # the wrench leg i exerts on the platform: -t_i J_i (force; moment about the platform origin)
    on_platform = -tension[:, None] * J
    force = on_platform[:, :3]
    platform_c, base_c = joint_centres(hexa, q)
    o = pose[:3, 3]
    m_platform = on_platform[:, 3:] - np.cross(platform_c - o, force)
    m_base = m_platform + np.cross(platform_c - base_c, force)
    axis = (platform_c - base_c) / np.linalg.norm(platform_c - base_c, axis=1, keepdims=True)
    return LegLoads(pose, W, tension, force, m_platform, m_base, axis, J)


def leg_forces(
    hexa: Hexapod,
    pose: np.ndarray,
    wrench: ArrayLike,
    *,
    frame: str = "platform",
    point: ArrayLike | None = None,
) -> LegLoads:
    """Leg (brake) forces and Cardan reaction moments of the locked fixture at ``pose`` under ``wrench``.

    Args:
        hexa: the hexapod.
        pose: (4, 4) platform pose (base frame, m); solved by inverse kinematics.
        wrench: ``(fx, fy, fz, mx, my, mz)`` applied to the platform (N, N m).
        frame: ``"platform"`` or ``"base"``: the coordinates of ``wrench`` and ``point``.
        point: where the force acts (m, in ``frame``); default the platform origin.

    Raises:
        InputError: a bad pose (one whose position is 100 base radii away: in mm?), wrench, frame or point.
        WorkspaceError, ConvergenceError, SingularityError: the pose cannot be reached, or is singular.
    """
    sol = hexa.inverse(check_pose_position("pose", pose, hexa.base_radius))
    return loads_at(hexa, sol.q, wrench, frame, point)


def force_per_unit_wrench(J: np.ndarray) -> tuple[float, float]:
    """Largest leg force per unit force (N/N) and per unit moment (N per N m) at the platform origin.

    The rows of ``J^-T`` split into force and moment columns: the largest 2-norm of a row's force part is
    the largest ``|t_i|`` a force of 1 N in the worst direction causes; the same for a moment of 1 N m.
    ``inf`` for a singular ``J``.
    """
    try:
        G = np.linalg.inv(J.T)
    except np.linalg.LinAlgError:
        return float("inf"), float("inf")
    return float(np.linalg.norm(G[:, :3], axis=1).max()), float(np.linalg.norm(G[:, 3:], axis=1).max())


@dataclass(frozen=True)
class Stiffness:
    """Stiffness of the locked fixture at one pose (legs as axial springs, all else rigid; base frame).

    Attributes:
        matrix: (6, 6) ``K = J^T diag(k) J``: wrench (N, N m about the platform origin) per
            ``[dx; dtheta]`` (m, rad).
        translational: smallest stiffness against a force at the platform origin, the platform free to
            turn (N/m): ``1 / largest eigenvalue`` of the force block of ``K^-1``.
        rotational: smallest stiffness against a moment, the origin free to move (N m/rad).
    """

    matrix: np.ndarray
    translational: float
    rotational: float


def stiffness_of(J: np.ndarray, leg_stiffness: ArrayLike) -> Stiffness:
    """:class:`Stiffness` of the Jacobian ``J`` (``dl = J [v; w]``) with leg stiffnesses (N/m, one or six)."""
    k = np.broadcast_to(np.asarray(leg_stiffness, dtype=float), (6,))
    if not np.all(np.isfinite(k)) or np.any(k <= 0):
        raise InputError("leg_stiffness", leg_stiffness, "expected positive finite N/m")
    K = J.T @ (k[:, None] * J)
    try:
        C = np.linalg.inv(K)
    except np.linalg.LinAlgError:
        return Stiffness(K, 0.0, 0.0)  # singular: no stiffness in some direction
    return Stiffness(
        K, 1.0 / float(np.linalg.eigvalsh(C[:3, :3]).max()), 1.0 / float(np.linalg.eigvalsh(C[3:, 3:]).max())
    )


def fixture_stiffness(hexa: Hexapod, pose: np.ndarray, leg_stiffness: ArrayLike) -> Stiffness:
    """:class:`Stiffness` of the locked fixture at ``pose`` (4x4, base frame) with leg stiffnesses (N/m)."""
    q = hexa.inverse(check_pose_position("pose", pose, hexa.base_radius)).q
    return stiffness_of(leg_jacobian(hexa, q), leg_stiffness)
