"""A changeover plan played by the simulated encoders: each plate follows its carried path at the planned times.

``sim.toml`` (or ``hexapod serve ... --simulate sim.toml --plan plan.json``)::

    [plan]
    file = "plan.json"     # written by hexapod changeover plan (relative to sim.toml)
    start = 1.0            # s of simulation before the plan's t = 0
    translation_mm = 2.0   # the monitor's tolerance: commanded flange against the coupling served
    rotation_deg = 0.5

A fixture the plan carries takes its poses from the plan (its pose source and ``changeover``
script in ``sim.toml`` are not played): its start pose until its carry, the carried
``platform_pose`` (interpolated on SE(3) between the plan's points) during it, its last carried
pose after. Its reading noise and faults act as on any other pose; a ``held_brake`` fault keeps
one leg's reading where it was when the fault started (a brake that did not release): the plate
then goes where the six readings put it (forward kinematics), no longer where the plan carries it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator

from ...exceptions import HexapodError
from ...kinematics.hexapod import Hexapod
from ...kinematics.newton.solver import Solution
from ...planning.model import Plan
from ...planning.writers import read_plan
from ..changeover.plan_monitor import PlanMonitor
from ..config.settings import ServiceConfig
from ..config.table import Table


@dataclass(frozen=True)
class PlanPlay:
    """A plan to play and how it is monitored.

    Attributes:
        plan: the plan.
        file: where it was read (for the messages).
        start: simulation time (s) of the plan's ``t = 0``.
        translation_mm, rotation_deg: the coupling monitor's tolerance
            (:class:`~hexapod_model.service.changeover.plan_monitor.PlanMonitor`).
    """

    plan: Plan
    file: str
    start: float = 1.0
    translation_mm: float = 2.0
    rotation_deg: float = 0.5

    def fixtures(self) -> tuple[str, ...]:
        """The fixtures the plan carries."""
        return tuple(f.name for f in self.plan.fixtures)

    def monitor(self, service: ServiceConfig) -> PlanMonitor:
        """This plan's monitor for the fixtures' cells of ``service`` (``InputError``: planned for another cell)."""
        cells = {f.name: f.cell for f in service.fixtures}
        return PlanMonitor(self.plan, cells, self.translation_mm, self.rotation_deg)


def plan_from_table(t: Table, service: ServiceConfig, folder, file: str | None = None) -> PlanPlay:
    """``[plan]`` of ``sim.toml`` (``file`` given: instead of the table's ``file``, e.g. ``--plan``)."""
    name = file if file is not None else t.text("file")
    if file is not None:
        t.take("file", None)
    path = folder / name
    try:
        plan = read_plan(path)
    except HexapodError as exc:
        raise t.error("file", str(path), str(exc)) from None
    for f in plan.fixtures:
        try:
            service.fixture(f.name)
        except KeyError:
            raise t.error("file", str(path), f"fixture {f.name!r} of the plan is not in {service.source}") from None
    play = PlanPlay(
        plan,
        str(path),
        start=t.number("start", 1.0, 0.0, 3600.0),
        translation_mm=t.number("translation_mm", 2.0, 1e-6, 1000.0),
        rotation_deg=t.number("rotation_deg", 0.5, 1e-6, 180.0),
    )
    t.finish()
    try:
        play.monitor(service)
    except HexapodError as exc:
        raise t.error("file", str(path), str(exc)) from None
    return play


class PlatePath:
    """One fixture's plate along a plan: where the plan puts it at each simulation time.

    The carried poses are passed at the plan's times exactly; between them the plate moves as a
    robot's controller interpolates, with a continuous velocity: the poses as twists from the
    first carried one, a cubic Hermite curve in time through them (the slopes of a monotone
    cubic, zero at both ends where the plan is at rest). A straight line between the points
    would change the velocity at once at each point (the plan's points are 0.5 mm apart, 5 to
    20 ms at the carry's start), which the service rightly takes for a discontinuity.

    Args:
        play: the plan and its start.
        name: the fixture.
    """

    def __init__(self, play: PlanPlay, name: str):
        plan = play.plan
        cell = next(f for f in plan.fixtures if f.name == name)
        rows = [k for k in range(len(plan.t)) if plan.fixture[k] == name and plan.phase[k] == "carry"]
        self.start = play.start
        self.t = plan.t[rows]
        self.first = pin.SE3(cell.start)
        poses = [pin.XYZQUATToSE3(plan.platform_pose[k]) for k in rows]
        self.last = poses[-1] if rows else self.first
        self._path = None
        if len(rows) > 1:  # the poses as twists from the first one, C1 in time, at rest at both ends
            xi = np.array([pin.log6(poses[0].inverse() * T).vector for T in poses])
            rates = PchipInterpolator(self.t, xi).derivative()(self.t)
            rates[0] = rates[-1] = 0.0
            self._path = CubicHermiteSpline(self.t, xi, rates)
            self.first_carried = poses[0]

    def pose(self, t_sim: float) -> np.ndarray:
        """The plate's 4x4 pose (base frame, m) at simulation time ``t_sim`` (s)."""
        t = t_sim - self.start
        if not len(self.t) or t < self.t[0]:
            return self.first.homogeneous
        if t >= self.t[-1] or self._path is None:
            return self.last.homogeneous
        return (self.first_carried * pin.exp6(self._path(t))).homogeneous


class HeldBrakes:
    """The ``held_brake`` faults of one fixture: legs whose readings stay put, the plate where they put it.

    Args:
        faults: the fixture's faults (only ``held_brake`` ones act here).
        hexa: the hexapod (forward kinematics of the held readings).
    """

    def __init__(self, faults, hexa: Hexapod):
        self.faults = [f for f in faults if f.kind == "held_brake"]
        self.hexa = hexa
        self._held: dict[int, float] = {}
        self._sol: Solution | None = None

    def apply(
        self, t_sim: float, pose: np.ndarray, readings: np.ndarray, guess: Solution | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The true pose and readings at ``t_sim`` of a plate moved to ``pose`` with the held legs kept.

        ``guess``: the solution of ``pose`` (the forward kinematics starts there).
        """
        active = {k for f in self.faults if f.active(t_sim) for k in f.legs}
        for k in list(self._held):
            if k not in active:
                del self._held[k]
        if not active:
            self._sol = None
            return pose, readings
        for k in active:
            self._held.setdefault(k, float(readings[k]))
        held = readings.copy()
        for k, v in self._held.items():
            held[k] = v
        if np.array_equal(held, readings):
            return pose, readings
        self._sol = self.hexa.forward(held, guess=self._sol if self._sol is not None else guess)
        return self._sol.pose, held


def carried(play: PlanPlay | None, name: str) -> PlatePath | None:
    """The plate path of fixture ``name`` when ``play`` carries it, else None."""
    if play is None or name not in play.fixtures():
        return None
    return PlatePath(play, name)
