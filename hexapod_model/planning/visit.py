"""One fixture's part of a changeover: its checked carry, the arm's joints along it, its stand-offs.

:func:`visit` plans, for one :class:`Move`, the carry path (:mod:`.carry`), the arm's joints at
each of its samples (the flange on ``base_in_robot * pose * coupling``, IK continued from sample
to sample on one branch, away from the arm's singularities), the stand-offs ``APPROACH_HEIGHT``
above the coupling at the start and the target, and the carry's timing (:mod:`.timing`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..exceptions import InputError, UnreachableError
from ..kinematics.hexapod import Hexapod
from .blocked import Blocked
from .carry import CarryPath, carry_path
from .model import FixtureCell
from .robot import Q_READY, Arm, branch, singularity_margins
from .scurve import DEFAULT_CARRY_JERK
from .timing import Timed, carry_curve, carry_timing, refine

APPROACH_HEIGHT = 0.15  # m: the flange's stand-off above the coupling, along its -z
MAX_JOINT_STEP = 0.05  # rad: an arm joint moving more between two carry samples is a branch change
MAX_POINT_DT = 0.02  # s: the carry's points are at most this far apart in time (the slow ends of the S-curve)


@dataclass(frozen=True)
class Move:
    """One fixture's changeover, as plain data.

    Attributes:
        cell: the fixture, its placement, start and target.
        hexapod: its kinematics.
        carry_speed: largest speed (m/s) of the platform's origin while carried.
        carry_rate: largest angular speed (rad/s) of the platform while carried.
        carry_jerk: largest jerk (m/s^3) of the platform's origin and of each leg's reading
            while carried (default :data:`~hexapod_model.planning.scurve.DEFAULT_CARRY_JERK`,
            what the service's tracker of a 50 Hz plate tolerates).
    """

    cell: FixtureCell
    hexapod: Hexapod
    carry_speed: float = 0.05
    carry_rate: float = math.radians(10.0)
    carry_jerk: float = DEFAULT_CARRY_JERK

    def __post_init__(self) -> None:
        for name in ("carry_speed", "carry_rate", "carry_jerk"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise InputError(name, v, "expected a number above 0")


@dataclass(frozen=True)
class Settings:
    """The planner's limits and thresholds.

    Attributes:
        min_singularity_margin: the hexapod's singularity margin kept along a carry (1 at home).
        min_clearance: m kept between the arm and each hexapod's bounding cylinder.
        min_wrist: ``|sin q5|`` kept while carrying (the wrist singularity).
        min_elbow: ``|sin q3|`` kept while carrying (the stretched elbow).
        min_shoulder: m kept between the wrist centre and the axis of joint 1.
        dwell: s spent in each of couple, release_brakes, lock_brakes, decouple.
        arm_start: the arm's joints (rad) at the start and the end of the changeover.
        acceleration: the arm's joint acceleration limits (rad/s^2); default
            :data:`hexapod_model.planning.robot.ACCELERATION_LIMITS`.
    """

    min_singularity_margin: float = 0.2
    min_clearance: float = 0.02
    min_wrist: float = 0.1
    min_elbow: float = 0.1
    min_shoulder: float = 0.1
    dwell: float = 0.5
    arm_start: tuple[float, ...] = tuple(Q_READY)
    acceleration: tuple[float, ...] | None = field(default=None)

    def __post_init__(self) -> None:
        for name in ("min_singularity_margin", "min_clearance", "min_wrist", "min_elbow", "min_shoulder", "dwell"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0.0):
                raise InputError(name, v, "expected a number >= 0")
        if len(self.arm_start) != 6 or (self.acceleration is not None and len(self.acceleration) != 6):
            raise InputError("arm_start/acceleration", (self.arm_start, self.acceleration), "six values each")


@dataclass(frozen=True)
class Visit:
    """One fixture's planned part: its move, carry path, timed carry, the arm's stand-offs (rad).

    ``arm_margins``: the wrist's, elbow's and shoulder's smallest singularity margins along the carry.
    """

    move: Move
    path: CarryPath
    carry: Timed
    pre_start: np.ndarray
    pre_target: np.ndarray
    arm_margins: np.ndarray


def _shift(T: np.ndarray, dz: float) -> np.ndarray:
    D = np.eye(4)
    D[2, 3] = dz
    return T @ D


def _reach(arm: Arm, name: str, fraction: float, what: str, target: np.ndarray, seed: np.ndarray) -> np.ndarray:
    try:
        return arm.reach(target, seed)
    except UnreachableError as exc:
        reason = str(exc).split(": ", 1)[-1]
        raise Blocked(name, fraction, f"the UR10 cannot reach {what}: {reason}") from None


def _seed(arm: Arm, flange: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``start`` turned about joint 1 to face ``flange``'s position."""
    p0 = arm.fk(start)[:3, 3]
    q = np.array(start, dtype=float)
    q[0] += math.atan2(flange[1, 3], flange[0, 3]) - math.atan2(p0[1], p0[0])
    q[0] = math.remainder(q[0], 2.0 * math.pi)
    return q


def _carried_joints(arm: Arm, name: str, path: CarryPath, flanges: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The arm's joints (rad) at each flange pose of the carry, IK continued from ``q`` on its branch."""
    qs = np.empty((len(flanges), 6))
    first = branch(q)
    for k, F in enumerate(flanges):
        q_new = _reach(arm, name, float(path.s[k]), "the coupling while carrying", F, q)
        step = float(np.abs(q_new - q).max())
        if step > MAX_JOINT_STEP or branch(q_new) != first:
            raise Blocked(name, float(path.s[k]), f"the UR10 changes its IK branch (joint step {step:.3f} rad)")
        qs[k] = q = q_new
    return qs


def visit(arm: Arm, move: Move, settings: Settings, home: np.ndarray) -> Visit:
    """Plan ``move``'s carry and the arm's joints along it, starting the IK from ``home`` (rad).

    Raises:
        Blocked: the carry leaves the hexapod's limits, the arm cannot reach a pose, changes its
            IK branch or comes near one of its singularities.
    """
    c, name = move.cell, move.cell.name
    path = carry_path(move.hexapod, c.start, c.target, name, settings.min_singularity_margin)
    flanges = c.base_in_robot @ path.poses @ c.coupling
    pre = _shift(flanges[0], -APPROACH_HEIGHT)
    pre_start = _reach(arm, name, 0.0, "the stand-off above the coupling at the start pose", pre, _seed(arm, pre, home))
    q = _reach(arm, name, 0.0, "the coupling at the start pose", flanges[0], pre_start)
    qs = _carried_joints(arm, name, path, flanges, q)
    xi = path.twist
    plate_time = max(np.linalg.norm(xi[:3]) / move.carry_speed, np.linalg.norm(xi[3:]) / move.carry_rate)
    plate = np.hstack([path.poses[:, :3, 3], path.readings])
    curve = carry_curve(qs, float(plate_time), arm.velocity, arm.acceleration, plate, move.carry_jerk)
    s = refine(curve, path.s, MAX_POINT_DT)
    if len(s) > len(path.s):  # the points as dense in time as a player's interpolation needs
        path = carry_path(move.hexapod, c.start, c.target, name, settings.min_singularity_margin, s)
        flanges = c.base_in_robot @ path.poses @ c.coupling
        qs = _carried_joints(arm, name, path, flanges, q)
    sm = np.array([singularity_margins(q) for q in qs])
    limits = np.array([settings.min_wrist, settings.min_elbow, settings.min_shoulder])
    bad = np.argwhere(sm < limits)
    if bad.size:
        k, j = bad[0]
        what = ("wrist (|sin q5|", "elbow (|sin q3|", "shoulder (wrist centre from axis 1, m")[j]
        raise Blocked(name, float(path.s[k]), f"UR10 {what} = {sm[k, j]:.3f}) below {limits[j]}: near its singularity")
    pre_target = _reach(
        arm, name, 1.0, "the stand-off above the coupling at the target", _shift(flanges[-1], -APPROACH_HEIGHT), qs[-1]
    )
    carry = carry_timing(qs, path.s, curve)
    return Visit(move, path, carry, pre_start, pre_target, sm.min(axis=0))
