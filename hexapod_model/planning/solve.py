"""Planning a changeover: the arm couples to each plate, carries it to its target, lets go (``plan_changeover``).

Per fixture, in the visiting order (:mod:`.order`): **approach** (a joint-space line from where
the arm is to ``APPROACH_HEIGHT`` above the coupling, then down onto it), **couple**,
**release_brakes**, **carry** (the flange on ``base_in_robot * pose * coupling`` of the checked
geodesic, :mod:`.carry`; the arm's joints continued from sample to sample, on one IK branch),
**lock_brakes**, **decouple**, **retract** (up, and after the last fixture back to the arm's
start). The arm's clearance from every other hexapod is checked on its free-space moves
(:mod:`.clearance`); the descent onto and the rise from a plate ignore that plate's own cylinder.
A free move blocked on its straight line is tried once through the arm's start configuration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..exceptions import UnreachableError
from ..kinematics.hexapod import Hexapod
from .blocked import Blocked
from .carry import CarryPath, carry_path
from .clearance import Clearance, bounding_cylinder
from .model import FixtureCell, Margins, Plan
from .order import best_order
from .robot import Q_READY, Arm, branch, singularity_margins
from .timing import Timed, carry_timing, line, line_duration

APPROACH_HEIGHT = 0.15  # m: the flange's stand-off above the coupling, along its -z
MAX_JOINT_STEP = 0.05  # rad: an arm joint moving more between two carry samples is a branch change


@dataclass(frozen=True)
class Move:
    """One fixture's changeover, as plain data.

    Attributes:
        cell: the fixture, its placement, start and target.
        hexapod: its kinematics.
        carry_speed: largest speed (m/s) of the platform's origin while carried.
        carry_rate: largest angular speed (rad/s) of the platform while carried.
    """

    cell: FixtureCell
    hexapod: Hexapod
    carry_speed: float = 0.05
    carry_rate: float = math.radians(10.0)


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


@dataclass(frozen=True)
class _Visit:
    move: Move
    path: CarryPath
    carry: Timed
    pre_start: np.ndarray
    pre_target: np.ndarray
    arm_margins: np.ndarray  # wrist, elbow, shoulder minima over the carry


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


def _visit(arm: Arm, move: Move, settings: Settings, home: np.ndarray) -> _Visit:
    c, name = move.cell, move.cell.name
    path = carry_path(move.hexapod, c.start, c.target, name, settings.min_singularity_margin)
    flanges = c.base_in_robot @ path.poses @ c.coupling
    pre = _shift(flanges[0], -APPROACH_HEIGHT)
    pre_start = _reach(arm, name, 0.0, "the stand-off above the coupling at the start pose", pre, _seed(arm, pre, home))
    q = _reach(arm, name, 0.0, "the coupling at the start pose", flanges[0], pre_start)
    qs = np.empty((len(flanges), 6))
    first = branch(q)
    for k, F in enumerate(flanges):
        q_new = _reach(arm, name, float(path.s[k]), "the coupling while carrying", F, q)
        step = float(np.abs(q_new - q).max())
        if step > MAX_JOINT_STEP or branch(q_new) != first:
            raise Blocked(name, float(path.s[k]), f"the UR10 changes its IK branch (joint step {step:.3f} rad)")
        qs[k] = q = q_new
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
    xi = path.twist
    plate_time = max(np.linalg.norm(xi[:3]) / move.carry_speed, np.linalg.norm(xi[3:]) / move.carry_rate)
    carry = carry_timing(qs, float(plate_time), arm.velocity, arm.acceleration)
    return _Visit(move, path, carry, pre_start, pre_target, sm.min(axis=0))


class _Timeline:
    """The plan's columns, appended segment by segment."""

    def __init__(self) -> None:
        self.t: list[np.ndarray] = []
        self.q: list[np.ndarray] = []
        self.qd: list[np.ndarray] = []
        self.qdd: list[np.ndarray] = []
        self.platform: list[np.ndarray] = []
        self.readings: list[np.ndarray] = []
        self.phase: list[str] = []
        self.fixture: list[str] = []
        self.now = 0.0

    def add(self, seg: Timed, phase: str, fixture: str, path: CarryPath | None = None) -> None:
        n = len(seg.t)
        self.t.append(self.now + seg.t)
        self.q.append(seg.q)
        self.qd.append(seg.qd)
        self.qdd.append(seg.qdd)
        if path is None:
            self.platform.append(np.full((n, 7), np.nan))
            self.readings.append(np.full((n, 6), np.nan))
        else:
            self.platform.append(np.array([_xyzquat(path.poses[i]) for i in seg.index]))
            self.readings.append(path.readings[seg.index])
        self.phase += [phase] * n
        self.fixture += [fixture] * n
        self.now += float(seg.t[-1])

    def dwell(self, q: np.ndarray, seconds: float, phase: str, fixture: str) -> None:
        z = np.zeros((2, 6))
        self.add(Timed(np.array([0.0, seconds]), np.array([q, q]), z, z.copy(), np.full(2, -1)), phase, fixture)


def _xyzquat(T: np.ndarray) -> np.ndarray:
    import pinocchio as pin

    return pin.SE3ToXYZQUAT(pin.SE3(T))


def _free(clear: Clearance, arm: Arm, qa, qb, home, required: float, name: str, phase: str, ignore=frozenset()):
    """The free move ``qa -> qb`` as one or two checked straight lines (via ``home`` when blocked)."""
    ok, d, where, link, fixture = clear.walk(qa, qb, required, ignore)
    if ok:
        return [(qa, qb)], d
    first = (d, where, link, fixture)
    ok1, d1, *_ = clear.walk(qa, home, required, ignore)
    ok2, d2, *_ = clear.walk(home, qb, required, ignore)
    if ok1 and ok2:
        return [(qa, home), (home, qb)], min(d1, d2)
    d, where, link, fixture = first
    raise Blocked(
        name,
        where,
        f"{phase}: the UR10's {link} comes {d * 1e3:.1f} mm from fixture '{fixture}' (at least {required * 1e3:g} mm)",
    )


def plan_changeover(moves: list[Move], settings: Settings | None = None) -> Plan:
    """Plan the arm's changeover of every fixture in ``moves`` (see the module doc).

    Raises:
        Blocked: no valid path: which constraint blocks it, for which fixture, how far along.
        InputError: no fixture to move.
        MissingExtraError: example-robot-data, toppra or coal are missing (the ``plan`` extra).
    """
    from ..exceptions import InputError

    settings = Settings() if settings is None else settings
    if not moves:
        raise InputError("fixtures", 0, "no fixture with a target to move")
    arm = Arm.load(None if settings.acceleration is None else np.array(settings.acceleration))
    home = np.array(settings.arm_start, dtype=float)
    visits = [_visit(arm, m, settings, home) for m in moves]
    clear = Clearance(
        [
            bounding_cylinder(
                m.cell.name, m.hexapod, m.cell.base_in_robot, max(m.cell.start[2, 3], m.cell.target[2, 3])
            )
            for m in moves
        ]
    )
    v, a, req = arm.velocity, arm.acceleration, settings.min_clearance
    d0, link, fixture = clear.distance(home)
    if d0 < req:
        raise Blocked(
            moves[0].cell.name, 0.0, f"the arm's start: its {link} is {d0 * 1e3:.1f} mm from fixture '{fixture}'"
        )
    order, method = best_order(
        np.array([line_duration(home, x.pre_start, v, a)[0] for x in visits]),
        np.array([[line_duration(x.pre_target, y.pre_start, v, a)[0] for y in visits] for x in visits]),
        np.array([line_duration(x.pre_target, home, v, a)[0] for x in visits]),
    )
    tl, q_now, clearance = _Timeline(), home, d0
    for i, k in enumerate(order):
        x, name = visits[k], visits[k].move.cell.name
        own = frozenset({name})
        lines, d = _free(clear, arm, q_now, x.pre_start, home, req, name, "approach")
        clearance = min(clearance, d)
        q_couple = x.carry.q[0]
        ok, d, where, link, other = clear.walk(x.pre_start, q_couple, req, own)
        if not ok:
            raise Blocked(name, where, f"approach: the UR10's {link} comes {d * 1e3:.1f} mm from fixture '{other}'")
        for qa, qb in [*lines, (x.pre_start, q_couple)]:
            tl.add(line(qa, qb, v, a), "approach", name)
        tl.dwell(q_couple, settings.dwell, "couple", name)
        tl.dwell(q_couple, settings.dwell, "release_brakes", name)
        ok, d, where, link, other = clear.walk_path(x.carry.q, req, own)
        if not ok:
            raise Blocked(
                name, float(x.path.s[where]), f"carry: the UR10's {link} comes {d * 1e3:.1f} mm from fixture '{other}'"
            )
        clearance = min(clearance, d)
        tl.add(x.carry, "carry", name, x.path)
        q_end = x.carry.q[-1]
        tl.dwell(q_end, settings.dwell, "lock_brakes", name)
        tl.dwell(q_end, settings.dwell, "decouple", name)
        ok, d, where, link, other = clear.walk(q_end, x.pre_target, req, own)
        if not ok:
            raise Blocked(name, where, f"retract: the UR10's {link} comes {d * 1e3:.1f} mm from fixture '{other}'")
        tl.add(line(q_end, x.pre_target, v, a), "retract", name)
        q_now = x.pre_target
        if i == len(order) - 1:
            lines, d = _free(clear, arm, q_now, home, home, req, name, "retract")
            clearance = min(clearance, d)
            for qa, qb in lines:
                tl.add(line(qa, qb, v, a), "retract", name)
    q = np.vstack(tl.q)
    arm_joint = float(np.min(np.minimum(q - arm.lower, arm.upper - q)))
    sm = np.min([x.arm_margins for x in visits], axis=0)
    margins = Margins(
        min(x.path.stroke_margin for x in visits),
        min(x.path.joint_margin for x in visits),
        min(x.path.singularity_margin for x in visits),
        arm_joint,
        float(sm[0]),
        float(sm[1]),
        float(sm[2]),
        float(clearance),
    )
    recorded = {
        "min_singularity_margin": settings.min_singularity_margin,
        "min_clearance_mm": settings.min_clearance * 1e3,
        "acceleration_limits": [float(x) for x in arm.acceleration],
        "velocity_limits": [float(x) for x in arm.velocity],
        "carry_speed_mm_s": {m.cell.name: m.carry_speed * 1e3 for m in moves},
        "carry_rate_deg_s": {m.cell.name: math.degrees(m.carry_rate) for m in moves},
        "dwell_s": settings.dwell,
    }
    return Plan(
        arm.joint_names,
        np.concatenate(tl.t),
        q,
        np.vstack(tl.qd),
        np.vstack(tl.qdd),
        tuple(tl.phase),
        tuple(tl.fixture),
        np.array([_xyzquat(F) for F in arm.fk_many(q)]),
        np.vstack(tl.platform),
        np.vstack(tl.readings),
        tuple(visits[k].move.cell.name for k in order),
        method,
        margins,
        tuple(m.cell for m in moves),
        recorded,
    )
