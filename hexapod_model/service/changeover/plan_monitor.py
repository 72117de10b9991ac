"""A changeover plan monitored while it plays: the flange the plan commands against the plate the encoders give.

While the robot holds a plate (from its fixture's ``couple`` phase to its ``decouple`` phase of
``plan.json``, docs/planning.md), the tool changer's frame on the plate is where the plan puts the
flange. Each record of that fixture carries ``pose_in_robot``, the coupling's pose in the robot's
frame from the encoders (``base_in_robot * pose * coupling``); the monitor compares it with the
flange the plan commands at the record's time (interpolated between the plan's points) and raises
``coupling_mismatch`` when they differ by more than the tolerance in :data:`PERSIST` records in
a row: the tool changer slipped, or a brake did not release (the plate did not follow).

>>> monitor = PlanMonitor(read_plan("plan.json"), {f.name: f.cell for f in config.fixtures})  # doctest: +SKIP
>>> monitor.begin(time.time() + 1.0)   # the Unix time of the plan's t = 0
>>> service.watch(monitor)             # every record checked; /events, /health and the log say it

A mismatch stays raised (the first one is kept, with the largest seen since) until the monitor
begins again.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...exceptions import InputError
from ...planning.model import Plan
from ..config.cell import Cell
from ..record.pose_record import PoseRecord

log = logging.getLogger(__name__)

#: the phases of a fixture's changeover in which the flange holds its plate
COUPLED = ("couple", "release_brakes", "carry", "lock_brakes", "decouple")
PERSIST = 3  # compared records in a row beyond the tolerance that raise coupling_mismatch
PLACEMENT_TOL = 1e-9  # m (and rotation matrix entries): a plan's cell must be the configuration's


@dataclass(frozen=True)
class Mismatch:
    """The flange the plan commands and the coupling the encoders give differ.

    Attributes:
        fixture: the fixture.
        t: the plan's time (s) of the record.
        phase: the plan's phase then.
        translation_mm: distance between the two frames' origins (mm).
        rotation_deg: angle between them (deg).
    """

    fixture: str
    t: float
    phase: str
    translation_mm: float
    rotation_deg: float

    def to_json(self) -> dict:
        """JSON-ready form."""
        return {
            "fixture": self.fixture,
            "t": self.t,
            "phase": self.phase,
            "translation_mm": self.translation_mm,
            "rotation_deg": self.rotation_deg,
        }


class PlanMonitor:
    """Watch a playing plan's coupled phases against the served records.

    Args:
        plan: the plan (``plan.json``).
        cells: each fixture's :class:`~hexapod_model.service.config.cell.Cell` (of ``fixture.toml``).
        translation_mm: largest distance (mm) between the commanded flange and the coupling.
        rotation_deg: largest angle (deg) between them.
        clock: Unix time (s), for the progress.

    Raises:
        InputError: a fixture of the plan has no cell here, or the plan was made with another
            ``base_in_robot`` or ``coupling``, or a tolerance is not above 0.
    """

    def __init__(
        self,
        plan: Plan,
        cells: dict[str, Cell | None],
        translation_mm: float = 2.0,
        rotation_deg: float = 0.5,
        clock: Callable[[], float] = time.time,
    ):
        for key, v in (("translation_mm", translation_mm), ("rotation_deg", rotation_deg)):
            if not (math.isfinite(v) and v > 0.0):
                raise InputError(key, v, "expected a tolerance above 0")
        for f in plan.fixtures:
            cell = cells.get(f.name)
            if cell is None:
                raise InputError("plan", f.name, "a fixture of the plan without [fixtures.cell] in the configuration")
            for key, planned, here in (
                ("base_in_robot", f.base_in_robot, cell.base_in_robot),
                ("coupling", f.coupling, cell.coupling),
            ):
                if not np.allclose(planned, here, rtol=0.0, atol=PLACEMENT_TOL):
                    raise InputError("plan", f.name, f"planned with another {key} than the configuration's: plan again")
        self.plan, self.clock = plan, clock
        self.tolerance = (translation_mm, rotation_deg)
        self._spans = {}  # fixture -> (first, last) point index of its coupled phases
        for name in {f.name for f in plan.fixtures}:
            rows = [k for k in range(len(plan.t)) if plan.fixture[k] == name and plan.phase[k] in COUPLED]
            if rows:
                self._spans[name] = (rows[0], rows[-1])
        self.t0: float | None = None
        self.mismatch: Mismatch | None = None
        self.worst: Mismatch | None = None
        self.checked = 0  # records compared
        self.unchecked = 0  # records of a held plate without a pose to compare (a failed set, a fault)
        self._over: dict[str, int] = {}

    def begin(self, t0: float) -> None:
        """The plan starts: its ``t = 0`` is at Unix time ``t0`` (s); a raised mismatch is cleared."""
        self.t0, self.mismatch, self.worst, self._over = t0, None, None, {}
        self.checked = self.unchecked = 0

    def commanded(self, name: str, t: float) -> np.ndarray | None:
        """The flange's 4x4 pose (robot frame) commanded at plan time ``t`` (s), holding ``name``'s plate."""
        span = self._spans.get(name)
        plan = self.plan
        if span is None or not plan.t[span[0]] <= t <= plan.t[span[1]]:
            return None
        k = int(np.clip(np.searchsorted(plan.t, t, side="right") - 1, span[0], max(span[0], span[1] - 1)))
        a = pin.XYZQUATToSE3(plan.flange_in_robot[k])
        if k + 1 > span[1] or plan.t[k + 1] <= plan.t[k]:
            return a.homogeneous
        b = pin.XYZQUATToSE3(plan.flange_in_robot[k + 1])
        s = (t - plan.t[k]) / (plan.t[k + 1] - plan.t[k])
        return (a * pin.exp6(s * pin.log6(a.inverse() * b))).homogeneous

    def check(self, rec: PoseRecord) -> None:
        """Compare one record (a service subscriber: on the cycle thread)."""
        if self.t0 is None:
            return
        t = rec.t - self.t0
        flange = self.commanded(rec.fixture, t)
        if flange is None:
            return
        if rec.pose_in_robot is None:
            self.unchecked += 1
            return
        p = rec.pose_in_robot["pose"]
        coupling = pin.XYZQUATToSE3(np.array([p["x"], p["y"], p["z"], p["qx"], p["qy"], p["qz"], p["qw"]]))
        err = pin.SE3(flange).inverse() * coupling
        found = Mismatch(
            rec.fixture,
            t,
            self.phase(t),
            float(np.linalg.norm(err.translation)) * 1e3,
            math.degrees(float(np.linalg.norm(pin.log3(err.rotation)))),
        )
        self.checked += 1
        beyond = found.translation_mm > self.tolerance[0] or found.rotation_deg > self.tolerance[1]
        self._over[rec.fixture] = self._over.get(rec.fixture, 0) + 1 if beyond else 0
        if self.worst is None or found.translation_mm > self.worst.translation_mm:
            self.worst = found
        if self._over[rec.fixture] >= PERSIST and self.mismatch is None:
            self.mismatch = found
            log.warning("fixture %s: %s", rec.fixture, self.describe(found))

    def describe(self, m: Mismatch) -> str:
        """One line: ``coupling_mismatch`` at the plan's time and phase, the difference and the tolerance."""
        return (
            f"coupling_mismatch at t = {m.t:.2f} s of the plan ({m.phase}): the plate's coupling is "
            f"{m.translation_mm:.3f} mm / {m.rotation_deg:.3f} deg from the flange the plan commands "
            f"(tolerance {self.tolerance[0]:g} mm / {self.tolerance[1]:g} deg)"
        )

    def phase(self, t: float) -> str:
        """The plan's phase at plan time ``t`` (s): ``waiting`` before, ``done`` after."""
        plan = self.plan
        if not len(plan.t) or t < plan.t[0]:
            return "waiting"
        if t > plan.t[-1]:
            return "done"
        return plan.phase[min(int(np.searchsorted(plan.t, t, side="left")), len(plan.t) - 1)]

    def progress(self) -> dict:
        """What the dashboard shows: the plan's time, phase, fixture and the mismatch (``GET /events``' ``plan``)."""
        plan, total = self.plan, self.plan.total_time
        t = None if self.t0 is None else self.clock() - self.t0
        phase = "waiting" if t is None else self.phase(t)
        k = None if t is None else min(int(np.searchsorted(plan.t, max(t, 0.0), side="left")), len(plan.t) - 1)
        m, worst = self.mismatch, self.worst
        return {
            "t_s": t,
            "total_s": total,
            "fraction": None if t is None else min(max(t / total, 0.0), 1.0) if total > 0 else 1.0,
            "phase": phase,
            "fixture": None if k is None or phase in ("waiting", "done") else plan.fixture[k],
            "order": list(plan.order),
            "tolerance": {"translation_mm": self.tolerance[0], "rotation_deg": self.tolerance[1]},
            "checked": self.checked,
            "unchecked": self.unchecked,
            "coupling_mismatch": None if m is None else m.to_json(),
            "largest": None if worst is None else worst.to_json(),
        }

    def health(self) -> dict:
        """``/health``'s ``plan`` section: its ``error`` names a raised mismatch (the service is then ``degraded``)."""
        m = self.mismatch
        return {**self.progress(), "error": None if m is None else f"fixture {m.fixture}: {self.describe(m)}"}
