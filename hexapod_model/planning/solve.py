"""Planning a changeover: the arm couples to each plate, carries it to its target, lets go (``plan_changeover``).

Per fixture, in the visiting order (:mod:`.order`): **approach** (a joint-space line from where
the arm is to the stand-off above the coupling, :mod:`.visit`, then down onto it), **couple**,
**release_brakes**, **carry** (the flange on ``base_in_robot * pose * coupling`` of the checked
geodesic, :mod:`.carry`; the arm's joints continued from sample to sample, on one IK branch),
**lock_brakes**, **decouple**, **retract** (up, and after the last fixture back to the arm's
start). The arm's clearance from every other hexapod is checked on its free-space moves
(:mod:`.clearance`); the descent onto and the rise from a plate ignore that plate's own cylinder.
A free move blocked on its straight line is tried once through the arm's start configuration.
"""

from __future__ import annotations

import math

import numpy as np

from .blocked import Blocked
from .carry import CarryPath
from .clearance import Clearance, bounding_cylinder
from .model import Margins, Plan
from .order import best_order
from .robot import Arm
from .timing import Timed, line, line_duration
from .visit import Move, Settings, visit


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
        MissingExtraError: example-robot-data or coal is missing (the ``plan`` extra).
    """
    from ..exceptions import InputError

    settings = Settings() if settings is None else settings
    if not moves:
        raise InputError("fixtures", 0, "no fixture with a target to move")
    arm = Arm.load(None if settings.acceleration is None else np.array(settings.acceleration))
    home = np.array(settings.arm_start, dtype=float)
    visits = [visit(arm, m, settings, home) for m in moves]
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
        "carry_jerk_m_s3": {m.cell.name: m.carry_jerk for m in moves},
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
