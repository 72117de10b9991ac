"""A changeover plan (what the arm does, when) and its JSON form, ``plan.json``.

The plan is columnar: one row per point in time. Poses are ``(x, y, z, qx, qy, qz, qw)``
(m, unit quaternion): ``flange_in_robot`` the UR10's ``tool0`` in the robot's base frame,
``platform_pose`` the carried platform in its hexapod's base frame (NaN, ``null`` in JSON,
outside the ``carry`` phase, like ``readings``, the legs' readings in m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..exceptions import InputError

#: the phases of each fixture's changeover, in order
PHASES = ("approach", "couple", "release_brakes", "carry", "lock_brakes", "decouple", "retract")
FORMAT = "hexapod_model/changeover_plan/1"


@dataclass(frozen=True)
class FixtureCell:
    """A fixture as the plan needs it to be drawn and checked.

    Attributes:
        name: the fixture's name.
        hexapod: its preset name or geometry/URDF path (as in ``fixture.toml``).
        base_in_robot: 4x4 hexapod base in the robot's base frame (m).
        coupling: 4x4 coupling (flange) frame in the platform frame (m).
        start: 4x4 platform pose at the start (m, base frame).
        target: 4x4 platform pose to reach (m, base frame).
    """

    name: str
    hexapod: str
    base_in_robot: np.ndarray
    coupling: np.ndarray
    start: np.ndarray
    target: np.ndarray


@dataclass(frozen=True)
class Margins:
    """The smallest margins met over the whole plan.

    Attributes:
        stroke: m, a leg's reading from its stroke limit (certified between samples).
        joint: rad, a Cardan angle from its limit (certified between samples).
        singularity: the hexapod's singularity margin (1 at home, 0 singular).
        arm_joint: rad, a UR10 joint from its position limit.
        arm_wrist: ``|sin q5|`` of the UR10 while carrying (0: wrist singularity).
        arm_elbow: ``|sin q3|`` while carrying (0: elbow stretched).
        arm_shoulder: m, the wrist centre from the axis of joint 1 while carrying.
        clearance: m, the UR10 from the hexapods' bounding cylinders in free space.
    """

    stroke: float
    joint: float
    singularity: float
    arm_joint: float
    arm_wrist: float
    arm_elbow: float
    arm_shoulder: float
    clearance: float


@dataclass(frozen=True)
class Plan:
    """A timed changeover: the arm's joint trajectory, phase by phase.

    Attributes:
        joint_names: the UR10's six joints.
        t: (n,) s from the plan's start, non-decreasing.
        q, qd, qdd: (n, 6) rad, rad/s, rad/s^2.
        phase: (n,) one of :data:`PHASES` per point.
        fixture: (n,) the fixture each point serves.
        flange_in_robot: (n, 7) the flange pose (robot base frame).
        platform_pose: (n, 7) the carried platform (its base frame); NaN outside ``carry``.
        readings: (n, 6) the carried hexapod's leg readings (m); NaN outside ``carry``.
        order: the fixtures in the order visited, and ``order_method`` (``exact`` or ``greedy``).
        margins: the smallest margins met.
        fixtures: the fixtures planned for.
        settings: the limits used (plate speeds, thresholds, acceleration limits).
    """

    joint_names: tuple[str, ...]
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    phase: tuple[str, ...]
    fixture: tuple[str, ...]
    flange_in_robot: np.ndarray
    platform_pose: np.ndarray
    readings: np.ndarray
    order: tuple[str, ...]
    order_method: str
    margins: Margins
    fixtures: tuple[FixtureCell, ...] = ()
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def total_time(self) -> float:
        """Duration of the whole changeover (s)."""
        return float(self.t[-1] - self.t[0]) if len(self.t) else 0.0

    def to_json(self) -> dict[str, Any]:
        """The ``plan.json`` document (``null`` for the NaN of absent values)."""

        def row(a: np.ndarray) -> list[float] | None:
            return None if np.isnan(a).any() else [float(v) for v in a]

        points = [
            {
                "t": float(self.t[k]),
                "q": row(self.q[k]),
                "qd": row(self.qd[k]),
                "qdd": row(self.qdd[k]),
                "phase": self.phase[k],
                "fixture": self.fixture[k],
                "flange_in_robot": row(self.flange_in_robot[k]),
                "platform_pose": row(self.platform_pose[k]),
                "readings": row(self.readings[k]),
            }
            for k in range(len(self.t))
        ]
        m = self.margins
        summary = {
            "total_time": self.total_time,
            "order": list(self.order),
            "order_method": self.order_method,
            "margins": {
                "stroke_mm": m.stroke * 1e3,
                "joint_deg": math.degrees(m.joint),
                "singularity": m.singularity,
                "arm_joint_deg": math.degrees(m.arm_joint),
                "arm_wrist": m.arm_wrist,
                "arm_elbow": m.arm_elbow,
                "arm_shoulder_mm": m.arm_shoulder * 1e3,
                "clearance_mm": m.clearance * 1e3,
            },
            "settings": self.settings,
        }
        fixtures = [
            {
                "name": f.name,
                "hexapod": f.hexapod,
                "base_in_robot": f.base_in_robot.tolist(),
                "coupling": f.coupling.tolist(),
                "start": f.start.tolist(),
                "target": f.target.tolist(),
            }
            for f in self.fixtures
        ]
        return {
            "format": FORMAT,
            "joint_names": list(self.joint_names),
            "pose_keys": ["x", "y", "z", "qx", "qy", "qz", "qw"],
            "summary": summary,
            "fixtures": fixtures,
            "points": points,
        }

    @staticmethod
    def from_json(doc: dict[str, Any]) -> Plan:
        """A plan read back from :meth:`to_json`'s document (to view, plot or play it).

        Raises:
            InputError: not a plan of this format.
        """
        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            raise InputError(
                "plan", str(doc.get("format") if isinstance(doc, dict) else type(doc)), f"expected format {FORMAT}"
            )
        pts = doc["points"]

        def col(key: str, width: int) -> np.ndarray:
            return np.array([p[key] if p[key] is not None else [math.nan] * width for p in pts], dtype=float).reshape(
                len(pts), width
            )

        s, m = doc["summary"], doc["summary"]["margins"]
        margins = Margins(
            m["stroke_mm"] * 1e-3,
            math.radians(m["joint_deg"]),
            m["singularity"],
            math.radians(m["arm_joint_deg"]),
            m["arm_wrist"],
            m["arm_elbow"],
            m["arm_shoulder_mm"] * 1e-3,
            m["clearance_mm"] * 1e-3,
        )
        fixtures = tuple(
            FixtureCell(
                f["name"],
                f["hexapod"],
                *(np.array(f[k], dtype=float) for k in ("base_in_robot", "coupling", "start", "target")),
            )
            for f in doc["fixtures"]
        )
        return Plan(
            tuple(doc["joint_names"]),
            np.array([p["t"] for p in pts], dtype=float),
            col("q", 6),
            col("qd", 6),
            col("qdd", 6),
            tuple(p["phase"] for p in pts),
            tuple(p["fixture"] for p in pts),
            col("flange_in_robot", 7),
            col("platform_pose", 7),
            col("readings", 6),
            tuple(s["order"]),
            s["order_method"],
            margins,
            fixtures,
            dict(s.get("settings", {})),
        )
