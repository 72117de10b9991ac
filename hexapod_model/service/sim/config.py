"""The simulation file ``sim.toml``: simulated encoders per fixture, validated like ``fixture.toml``.

Per fixture: a pose sequence (Jakobović and Jelenković's trajectory A or B played there and back, a CSV of poses
played one row per set, or a held pose), the set rate, the reading noise, optional lock phases
(the plate slows down, stays still with the brakes on, speeds up again) and injected faults.
A ``[plan]`` table plays a changeover plan (:mod:`~hexapod_model.service.sim.plan_player`).
Every field is documented in ``docs/service.md``; an example is ``docs/examples/sim.toml``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...analysis.trajectories import DURATION_S, trajectory_coordinates
from ...exceptions import HexapodError
from ...io.tables import poses_from_table, read_table
from ...lie import rpy_to_matrix, xyz_rpy_to_pose
from ..config.settings import ServiceConfig, read_toml
from ..config.table import Table
from ..errors import ConfigError
from .changeover import ChangeoverScript
from .plan_player import PlanPlay, plan_from_table

FAULTS = (
    "dropped_frames",
    "silent_leg",
    "stuck_leg",
    "error_bit",
    "warning_bit",
    "spike",
    "step",
    "late_frame",
    "duplicate_id",
    "held_brake",
    "lost_sets",
    "repeated_frames",
    "ahead_stamp",
    "gateway_burst",
    "late_reading",
    "creep",
    "replay",
    "bit_flip",
    "intruder",
)
VALUE_FAULTS = ("stuck_leg", "spike", "step", "late_reading", "creep", "replay")  # act on a reading, any sensor


@dataclass(frozen=True)
class Fault:
    """An injected fault.

    A ``held_brake`` leg keeps the reading it had at ``start`` for ``duration`` (its brake did not
    release): the plate goes where the readings put it
    (:class:`~hexapod_model.service.sim.plan_player.HeldBrakes`). Faults that six readings cannot
    reveal (docs/redundancy.md): ``late_reading`` (the frames carry the reading of ``sets`` sets
    earlier with fresh stamps: a gateway buffering one sensor), ``creep`` (the reading drifts by
    ``size`` per second from ``start``), a constant offset (``step`` from ``start`` 0) and
    ``replay`` (a device on the sensor's CAN id whose frames replace the genuine ones: it replays
    the readings of ``sets`` sets earlier plus ``size``). An ``intruder`` is a second sender on a
    leg's id whose frames are plausible to the layout's counter and checksum. Reading faults (:data:`VALUE_FAULTS`) act
    on any reading, an extra sensor's too; frame faults on the frame that carries it.

    Attributes:
        kind: one of :data:`FAULTS`.
        legs: affected readings (0-based, the hexapod's reading order: the legs, then ``tilt_x``,
            ``tilt_y``).
        start: seconds after the simulation starts.
        duration: seconds (a ``spike`` affects the first set at or after ``start`` only; a
            ``step``, ``held_brake``, ``late_reading``, ``creep`` and ``replay`` last to the end
            unless given, the others 1 s).
        probability: chance that a frame is lost (``dropped_frames``), a whole set (``lost_sets``),
            or that one random bit of a frame's payload is flipped after the encoder sent it
            (``bit_flip``: a gateway or driver corrupting frames past CAN's own CRC).
        size: reading offset (m, rad for a tilt) of a ``spike``, a ``step`` (an encoder that
            slipped, for ``duration``), a ``replay``'s frames, the second sender's frame of a
            ``duplicate_id`` (sent on the leg's CAN id just before the genuine frame) or an
            ``intruder``'s frames (a sender on the leg's id, ``seconds`` after each set, whose
            rolling counter copies the encoder's next value and whose checksum is right:
            plausible frames); a ``creep``'s rate (m/s, rad/s for a tilt).
        sets: a ``late_frame`` leg sends its frame of this many sets earlier, with that set's
            timestamp, last in the set, instead of the current one; ``repeated_frames``: every
            frame is sent this many times in a row, stamp and all (a gateway's repeats);
            ``gateway_burst``: this many sets are held, then sent in order with the stamp of the
            last frame (a gateway that batches and stamps a burst once); ``late_reading`` and
            ``replay``: how many sets old the readings sent are.
        seconds: an ``ahead_stamp`` leg's frames carry stamps this much later (s) than its set's;
            an ``intruder`` sends this long (s) after each set.
    """

    kind: str
    legs: tuple[int, ...]
    start: float
    duration: float = 0.0
    probability: float = 1.0
    size: float = 0.0
    sets: int = 1
    seconds: float = 0.0

    def active(self, t: float) -> bool:
        """True while the fault acts at simulation time ``t`` (s)."""
        return self.start <= t < self.start + self.duration


@dataclass(frozen=True)
class SimFixture:
    """Simulated encoders of one fixture.

    Attributes:
        name: the fixture (of ``fixture.toml``).
        rate: reading sets per second (six frames each).
        noise: 1-sigma Gaussian reading noise of a leg (m; default 10 um, a redundant hexapod's
            own ``encoder_sigma``).
        tilt_noise: 1-sigma Gaussian noise of an inclinometer angle (rad; default its ``sigma``).
        poses: (n, 4, 4) pose sequence (base -> platform, m): one held pose, CSV rows (one per
            set), or the trajectory sampled at ``rate`` over one there-and-back ``period``.
        move, lock: seconds of motion, then seconds still (``lock = 0``: always moving).
        ramp: seconds to slow down before and speed up after a lock phase.
        faults: injected faults.
        changeover: follow the fixture's target when it changes (``None``: never).
    """

    name: str
    rate: float
    noise: float
    poses: np.ndarray
    move: float = 1.0
    lock: float = 0.0
    ramp: float = 0.2
    faults: tuple[Fault, ...] = ()
    changeover: ChangeoverScript | None = None
    tilt_noise: float = 2e-5

    def speed(self, t: float) -> float:
        """Playback speed (0..1) of the pose sequence at simulation time ``t`` (s)."""
        if self.lock <= 0.0:
            return 1.0
        p = t % (self.move + self.lock)
        if p >= self.move:
            return 0.0
        x = min(p, self.move - p) / self.ramp if self.ramp > 0 else 1.0
        return 1.0 if x >= 1.0 else 0.5 * (1.0 - np.cos(np.pi * x))


@dataclass(frozen=True)
class SimConfig:
    """The whole ``sim.toml``; ``plan``: the changeover plan it plays (``[plan]``), or None."""

    fixtures: tuple[SimFixture, ...]
    seed: int = 0
    source: str = "<dict>"
    plan: PlanPlay | None = None


def trajectory_sequence(name: str, home: np.ndarray, scale: float, rate: float, period: float) -> np.ndarray:
    """Trajectory ``name`` (Jakobović and Jelenković (2002) eqs. 20-21) there and back in ``period`` s, at ``rate`` Hz.

    The trajectory's time runs as ``2 (1 - cos(2 pi t / period))`` (0 -> 4 s -> 0), so the
    turns are smooth; positions are scaled by ``scale`` (m per paper unit) about ``home``.
    """
    t = np.arange(0.0, period, 1.0 / rate)
    tau = 0.5 * DURATION_S * (1.0 - np.cos(2.0 * np.pi * t / period))
    c = trajectory_coordinates(name, tau)
    poses = np.tile(np.eye(4), (len(t), 1, 1))
    poses[:, :3, :3] = home[:3, :3] @ rpy_to_matrix(*np.radians(c[:, 3:6]).T)
    poses[:, :3, 3] = home[:3, 3] + scale * c[:, :3]
    return poses


def load_simulation(path: str | Path, service: ServiceConfig, plan: str | Path | None = None) -> SimConfig:
    """Read and validate ``sim.toml`` against the service configuration; ``plan``: a ``plan.json`` to play."""
    path = Path(path)
    return simulation_from_dict(read_toml(path), service, str(path), path.parent, plan)


def simulation_from_dict(
    data: dict,
    service: ServiceConfig,
    source: str = "<dict>",
    folder: Path | None = None,
    plan: str | Path | None = None,
) -> SimConfig:
    """Validate a parsed ``sim.toml``; CSV and plan paths are relative to ``folder``.

    ``plan`` (a ``plan.json``) is played instead of the ``[plan]`` table's ``file``, with the
    table's other fields when there is one.
    """
    top = Table(data, "", source)
    seed = top.integer("seed", 0, 0, 2**63)
    play = None
    if "plan" in data or plan is not None:
        given = None if plan is None else str(Path(plan).resolve())
        play = plan_from_table(top.table("plan", {}), service, folder or Path("."), given)
    items = top.take("fixtures")
    if not isinstance(items, list) or not items:
        raise top.error("fixtures", items, "expected one or more [[fixtures]] tables")
    fixtures = tuple(
        _fixture(Table(f, f"fixtures[{i}]", source), service, folder or Path(".")) for i, f in enumerate(items)
    )
    top.finish()
    names = [f.name for f in fixtures]
    for i, n in enumerate(names):
        if n in names[:i]:
            raise ConfigError(f"fixtures[{i}].name", n, "simulated twice", source)
    missing = [] if play is None else [n for n in play.fixtures() if n not in names]
    if play is not None and missing:
        raise ConfigError("plan.file", play.file, f"fixture {missing[0]!r} of the plan is not simulated", source)
    return SimConfig(fixtures, seed, source, play)


def _fixture(t: Table, service: ServiceConfig, folder: Path) -> SimFixture:
    name = t.text("name")
    try:
        fc = service.fixture(name)
    except KeyError:
        raise t.error("name", name, f"no such fixture in {service.source}") from None
    rate = t.number("rate", 100.0, 0.1, 20_000.0)
    sources = [k for k in ("trajectory", "csv", "hold") if k in t.data]
    if len(sources) != 1:
        raise t.error("trajectory", sources, "give exactly one pose source: trajectory, csv or hold")
    hexa = fc.load_hexapod()
    if "trajectory" in t.data:
        poses = trajectory_sequence(
            t.text("trajectory", choices=("A", "B")),
            hexa.home_pose,
            t.number("scale", 0.01, 0.0, 1.0),
            rate,
            t.number("period", 8.0, 0.1, 3600.0),
        )
    elif "csv" in t.data:
        p = folder / t.text("csv")
        try:
            poses, invalid = poses_from_table(*read_table(p))
        except (HexapodError, OSError) as exc:
            raise t.error("csv", str(p), f"cannot read poses: {exc}") from None
        bad = next((k for k, why in enumerate(invalid) if why), None)
        if bad is not None:
            raise t.error("csv", str(p), f"pose row {bad + 1}: {invalid[bad]}")
    else:
        v = t.take("hold")
        if not isinstance(v, list) or len(v) != 6 or not all(isinstance(x, (int, float)) for x in v):
            raise t.error("hold", v, "expected [x, y, z, roll, pitch, yaw] in m and degrees")
        poses = xyz_rpy_to_pose(v)[None]
    faults = t.take("faults", [])
    if not isinstance(faults, list):
        raise t.error("faults", faults, "expected [[fixtures.faults]] tables")
    # a hexapod with redundant sensors: by default the noise its consistency test assumes (else
    # nearly every set would be a false alarm); without them 10 um, a typical encoder's
    sigmas = None if hexa.redundancy is None else hexa.redundancy.sigmas
    noise = 10e-6 if sigmas is None else float(sigmas[0])
    tilt_noise = 2e-5 if sigmas is None or "tilt_x" not in hexa.reading_names else float(sigmas[-1])
    sim = SimFixture(
        name=name,
        rate=rate,
        noise=t.number("noise", noise, 0.0, 0.01),
        poses=poses,
        move=t.number("move", 1.0, 0.01, 3600.0),
        lock=t.number("lock", 0.0, 0.0, 3600.0),
        ramp=t.number("ramp", 0.2, 0.0, 60.0),
        faults=tuple(_fault(Table(f, t.name(f"faults[{k}]"), t.source), hexa) for k, f in enumerate(faults)),
        changeover=_changeover(t.table("changeover")) if "changeover" in t.data else None,
        tilt_noise=t.number("tilt_noise", tilt_noise, 0.0, 0.1),
    )
    if 2 * sim.ramp > sim.move and sim.lock > 0:
        raise t.error("ramp", sim.ramp, f"two ramps must fit in move = {sim.move:g} s")
    t.finish()
    _check_reachable(t, sources[0], hexa, poses)
    return sim


def _changeover(t: Table) -> ChangeoverScript:
    script = ChangeoverScript(
        move=t.number("move", 4.0, 0.01, 3600.0),
        overshoot=t.number("overshoot", 0.0, 0.0, 1.0),
        settle=t.number("settle", 1.0, 0.01, 3600.0),
    )
    t.finish()
    return script


UNTIL_THE_END = {"spike": 0.0, "step": 1e6, "held_brake": 1e6, "late_reading": 1e6, "creep": 1e6, "replay": 1e6}
SETS = {"late_frame": 1, "repeated_frames": 10, "gateway_burst": 5, "late_reading": 1, "replay": 100}


def _fault(t: Table, hexa) -> Fault:
    kind = t.text("kind", choices=FAULTS)
    names = hexa.reading_names
    n_legs = sum(n.startswith("leg") for n in names)
    leg = t.take("leg", 0)
    every = kind in ("lost_sets", "repeated_frames", "gateway_burst") or (
        leg == 0 and kind in ("dropped_frames", "bit_flip")
    )
    if "reading" in t.data:  # any reading by name: leg7, tilt_x, ...
        if "leg" in t.data:
            raise t.error("reading", t.data["reading"], "give leg or reading, not both")
        legs: tuple[int, ...] = (names.index(t.text("reading", choices=names)),)
    else:
        legs = tuple(range(len(names))) if every else (t.integer("leg", lo=1, hi=n_legs) - 1,)
    if kind == "held_brake" and (legs[0] >= 6 or hexa.redundancy is not None):
        raise t.error(
            "kind", kind, "a held brake is simulated on the six braked legs of a hexapod without extra sensors"
        )
    fault = Fault(
        kind=kind,
        legs=legs,
        start=t.number("start", 0.0, 0.0, 1e6),
        duration=t.number("duration", UNTIL_THE_END.get(kind, 1.0), 0.0, 1e6),
        probability=t.number("probability", 0.01 if kind == "bit_flip" else 0.2, 0.0, 1.0)
        if kind in ("dropped_frames", "lost_sets", "bit_flip")
        else 1.0,
        size=t.number("size", {"creep": 1e-4, "replay": 0.0}.get(kind, 0.002), -0.5, 0.5)
        if kind in ("spike", "step", "duplicate_id", "creep", "replay", "intruder")
        else 0.0,
        sets=t.integer("sets", SETS.get(kind, 1), 1, 1000) if kind in SETS else 1,
        seconds=t.number("seconds", 0.05, -10.0, 10.0)
        if kind == "ahead_stamp"
        else t.number("seconds", 0.005, 0.0, 10.0)
        if kind == "intruder"
        else 0.0,
    )
    t.finish()
    return fault


def _check_reachable(t: Table, key: str, hexa, poses: np.ndarray) -> None:
    """Every pose of the sequence (at most 200 spread over it) solves by inverse kinematics."""
    guess = None
    for k in np.unique(np.linspace(0, len(poses) - 1, min(len(poses), 200)).astype(int)):
        try:
            guess = hexa.inverse(poses[k], guess=guess)
        except HexapodError as exc:
            raise t.error(key, t.data[key], f"pose {k} of {len(poses)} is outside the workspace: {exc}") from None
