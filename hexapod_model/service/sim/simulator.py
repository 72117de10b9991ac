"""Simulated encoders: poses -> inverse kinematics -> noisy readings -> the fixture's own frames.

Each simulated fixture plays its pose sequence (:mod:`hexapod_model.service.sim.config`) at a
playback speed that slows to 0 in lock phases; a pose between two samples of the sequence is
interpolated on SE(3). Its leg readings come from the hexapod's inverse kinematics (warm
started), the readings of its redundant sensors (measuring legs, inclinometer) from the same
pose through their sensor model
(:meth:`~hexapod_model.kinematics.redundant.RedundantSensing.extra_readings`); all get Gaussian
noise, then the faults act, and every leg's reading is encoded with the fixture's frame layout,
CAN id and home count (the inclinometer's two angles in its own frame) and sent on the bus: with
the layout's rolling counter (one up per frame of a leg, lost frames included) and checksum, and
a CANopen SYNC with its counter (1..240). Every sent set is kept in :attr:`Simulator.truth` (the
poses the service should report).
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import can
import numpy as np
import pinocchio as pin

from ...exceptions import HexapodError
from ...kinematics.hexapod import Hexapod
from ...kinematics.newton.solver import Solution
from ..changeover.plan_monitor import PlanMonitor
from ..config.settings import FixtureConfig, ServiceConfig
from ..cycle.canopen_link import master_frames
from ..errors import FrameError
from ..threads import NamedThread
from .changeover import Follower
from .config import SimConfig, SimFixture
from .plan_player import HeldBrakes, PlatePath, carried

log = logging.getLogger(__name__)
FRAME_TIME = 130e-6  # s: one 8-byte frame on a 1 Mbit/s bus, the spacing of a set's stamps


@dataclass(frozen=True)
class SentSet:
    """One simulated reading set as sent.

    Attributes:
        fixture: its name.
        t_sim: simulation time (s).
        t_first, t_last: time (s, Unix) of the set: its stamp and that of its last frame, or the
            wall-clock time just before the first and after the last frame when not stamped.
        pose: the true pose (4x4, base -> platform, m).
        readings: the true readings (m, rad for tilts; reading order), before noise and faults.
        sent: which frames went on the bus (one per leg, then the inclinometer's).
        faults: kinds of the faults active on this set.
    """

    fixture: str
    t_sim: float
    t_first: float
    t_last: float
    pose: np.ndarray
    readings: np.ndarray
    sent: tuple[bool, ...]
    faults: tuple[str, ...]


class _Encoders:
    """The simulated encoders of one fixture: its legs' and its inclinometer's."""

    def __init__(
        self, sim: SimFixture, cfg: FixtureConfig, hexa: Hexapod, rng: np.random.Generator, targets=None, path=None
    ):
        self.sim, self.cfg, self.hexa, self.rng = sim, cfg, hexa, rng
        self.n = cfg.channels  # frames of a set
        names = hexa.reading_names
        #: the frame that carries each reading (the tilts share the inclinometer's)
        self.channel = [min(k, len(cfg.legs)) for k in range(len(names))]
        self.sigma = np.array([sim.tilt_noise if n.startswith("tilt") else sim.noise for n in names])
        self.noisy: deque[np.ndarray] = deque(maxlen=1001)  # sent readings before faults (late_reading, replay)
        self.path: PlatePath | None = path  # a plan carries this plate: it follows that, nothing else
        self.brakes = HeldBrakes(sim.faults, hexa)
        script = sim.changeover if targets is not None and path is None else None
        self.follower = None if script is None else Follower(script, sim.ramp)
        self._targets = targets
        self.tau = 0.0  # position in the pose sequence (samples)
        self.next_beat = 0.0  # s of simulation: the CANopen nodes' next heartbeat
        self._key: float | None = None
        self._sol: Solution | None = None
        self._stuck: dict[int, float] = {}
        self._spiked: set[int] = set()
        #: sent sets, newest last (for late_frame)
        self.past: deque[list[can.Message | None]] = deque(maxlen=1001)
        self.late: dict[int, int] = {}
        self.duplicate: dict[int, np.ndarray] = {}  # frame -> readings of a second sender (duplicate_id)
        self.ahead: dict[int, float] = {}  # leg -> seconds its stamps run ahead (ahead_stamp)
        self.repeats = 1  # times each frame is sent (repeated_frames)
        self.burst = 0  # sets a gateway holds before sending them with one stamp (gateway_burst)
        self.held: list[can.Message] = []
        self.held_sets = 0
        self.counter = [0] * self.n  # each frame sender's rolling counter (its next frame's)
        self.sync_counter = 0  # the CANopen SYNC's counter (its last, 1..240)
        self.intruder: dict[int, tuple[float, float]] = {}  # leg -> (reading, seconds after the set) (intruder)

    def pose(self) -> np.ndarray:
        n = len(self.sim.poses)
        k = int(np.floor(self.tau))
        a, b = self.sim.poses[k % n], self.sim.poses[(k + 1) % n]
        frac = self.tau - k
        if frac == 0.0 or n == 1:
            return a
        A, B = pin.SE3(a), pin.SE3(b)
        return (A * pin.exp6(frac * pin.log6(A.inverse() * B))).homogeneous

    def advance(self, t_sim: float) -> tuple[np.ndarray, np.ndarray]:
        """True pose and readings at ``t_sim`` (held brakes kept); the sequence position then moves on one set."""
        if self.path is not None:
            self._sol = self.hexa.inverse(self.path.pose(t_sim), guess=self._sol)
            pose, true = self._sol.pose, self._sol.lengths.copy()
        else:
            pose, true = self._play(t_sim)
        pose, true = self.brakes.apply(t_sim, pose, true, self._sol)
        if self.hexa.redundancy is not None:  # the extra sensors see the same pose
            true = np.concatenate([true, self.hexa.redundancy.extra_readings(pose)])
        return pose, true

    def message(
        self, channel: int, r: np.ndarray, error: bool = False, warning: bool = False, counter: int = 0
    ) -> can.Message:
        """The frame ``channel`` sends for readings ``r`` (reading order), a leg's with its rolling ``counter``."""
        if channel < len(self.cfg.legs):
            return self.cfg.legs[channel].message(float(r[channel]), error, warning, counter)
        assert self.cfg.inclinometer is not None
        return self.cfg.inclinometer.message(float(r[-2]), float(r[-1]), error, warning)

    def _play(self, t_sim: float) -> tuple[np.ndarray, np.ndarray]:
        factor = 1.0
        if self.follower is not None:
            f = self.follower
            key, target = self._targets(self.sim.name)
            f.request(key, target)
            playing = len(self.sim.poses) > 1 and self.sim.speed(t_sim) > 0.0
            current = self.pose() if self._sol is None else self._sol.pose
            if f.follow(current, t_sim, playing):
                self._sol = self.hexa.inverse(f.pose(t_sim), guess=self._sol)
                self._key = None
                return self._sol.pose, self._sol.lengths.copy()
            factor = f.sequence_speed(t_sim, playing)
        if self._key != self.tau:
            pose = self.pose()
            self._sol = self.hexa.inverse(pose, guess=self._sol)
            self._key = self.tau
        assert self._sol is not None
        pose, true = self._sol.pose, self._sol.lengths.copy()
        if len(self.sim.poses) > 1:
            self.tau = (self.tau + factor * self.sim.speed(t_sim)) % len(self.sim.poses)
        return pose, true

    def skip(self, t_sim: float) -> None:
        """Let a set's time pass unsent: the plate moves on."""
        f = self.follower
        if (f is not None and f.active) or self.path is not None:
            return  # the move is a function of time: nothing to advance
        if len(self.sim.poses) > 1:
            playing = self.sim.speed(t_sim) > 0.0
            factor = 1.0 if f is None else f.sequence_speed(t_sim, playing)
            self.tau = (self.tau + factor * self.sim.speed(t_sim)) % len(self.sim.poses)

    def frames(self, t_sim: float, true: np.ndarray) -> tuple[list[can.Message | None], tuple[str, ...]]:
        """The frames (``None``: not sent) of a set at ``t_sim``: one per leg, then the inclinometer's."""
        m, n, ch = len(true), self.n, self.channel
        r = true + self.rng.normal(0.0, 1.0, m) * self.sigma if self.sigma.any() else true.copy()
        self.noisy.append(r.copy())
        err, warn, drop = [False] * n, [False] * n, [False] * n
        self.late = {}  # leg -> sets: send that old frame last instead (late_frame)
        self.duplicate = {}  # leg -> reading of a second sender (duplicate_id)
        self.ahead, self.repeats, self.burst, self.intruder = {}, 1, 0, {}
        flip = 0.0
        active = []
        for i, f in enumerate(self.sim.faults):
            if f.kind == "spike":
                if t_sim >= f.start and i not in self._spiked:
                    self._spiked.add(i)
                    active.append(f.kind)
                    for k in f.legs:
                        r[k] += f.size
                continue
            if not f.active(t_sim):
                for k in f.legs:
                    if f.kind == "stuck_leg":
                        self._stuck.pop(k, None)
                continue
            active.append(f.kind)
            for k in f.legs:
                c = ch[k]
                if f.kind == "dropped_frames":
                    drop[c] |= bool(self.rng.random() < f.probability)
                elif f.kind == "silent_leg":
                    drop[c] = True
                elif f.kind == "stuck_leg":
                    r[k] = self._stuck.setdefault(k, float(r[k]))
                elif f.kind == "error_bit":
                    err[c] = True
                elif f.kind == "warning_bit":
                    warn[c] = True
                elif f.kind == "step":
                    r[k] += f.size
                elif f.kind == "creep":
                    r[k] += f.size * (t_sim - f.start)
                elif f.kind in ("late_reading", "replay"):  # readings of `sets` sets ago, stamped now
                    old = self.noisy[-1 - f.sets] if len(self.noisy) > f.sets else self.noisy[0]
                    r[k] = old[k] + (f.size if f.kind == "replay" else 0.0)
                elif f.kind == "late_frame":
                    self.late[c] = f.sets
                elif f.kind == "duplicate_id":
                    second = self.duplicate.setdefault(c, r.copy())
                    second[k] += f.size
                elif f.kind == "ahead_stamp":
                    self.ahead[c] = f.seconds
                elif f.kind == "repeated_frames":
                    self.repeats = f.sets
                elif f.kind == "gateway_burst":
                    self.burst = f.sets
                elif f.kind == "bit_flip":
                    flip = f.probability
                elif f.kind == "intruder":
                    self.intruder[k] = (float(r[k] + f.size), f.seconds)
            if f.kind == "lost_sets" and self.rng.random() < f.probability:
                drop = [True] * n
        msgs: list[can.Message | None] = []
        for k in range(n):
            try:
                msgs.append(None if drop[k] else self.message(k, r, err[k], warn[k], self.counter[k]))
            except FrameError as exc:
                log.warning("simulated fixture %s frame %d: not sent: %s", self.cfg.name, k + 1, exc)
                msgs.append(None)
            self.counter[k] += 1  # a lost frame was counted by its encoder
            sent = msgs[-1]
            if sent is not None and flip > 0.0 and self.rng.random() < flip:
                bit = int(self.rng.integers(8 * len(sent.data)))
                sent.data[bit >> 3] ^= 1 << (bit & 7)
        return msgs, tuple(active)

    def intruders(self, stamp: float | None) -> list[can.Message]:
        """The intruders' frames of this set: on a leg's id, with the encoder's next counter."""
        out = []
        for k, (reading, seconds) in self.intruder.items():
            try:
                m = self.cfg.legs[k].message(reading, counter=self.counter[k])
            except FrameError:
                continue
            if stamp is not None:
                m.timestamp = stamp + seconds
            out.append(m)
        return out

    def next_sync(self) -> int:
        """The counter of the next CANopen SYNC (1..240, as a SYNC producer's with overflow value 240)."""
        self.sync_counter = self.sync_counter % 240 + 1
        return self.sync_counter


class Simulator:
    """Simulated encoders of every fixture of ``sim`` on ``bus``.

    Args:
        service: the service configuration (frame layouts, CAN ids, hexapods).
        sim: the simulation.
        bus: where the frames go (a python-can bus; ``virtual`` reaches this process only and
            keeps the sampling-time stamps when created with ``preserve_timestamps=True``).
        truth: how many sent sets :attr:`truth` keeps.
        hexapods: already loaded hexapods by fixture name (else loaded here).
        targets: ``targets(name) -> (key, 4x4 pose or None)``: each fixture's current target (the
            key changes with it), which fixtures with a ``changeover`` script move to.
        monitor: watches the plan ``sim`` plays: :meth:`run` tells it when the plan starts.
    """

    def __init__(
        self,
        service: ServiceConfig,
        sim: SimConfig,
        bus: can.BusABC,
        truth: int = 200_000,
        hexapods: dict[str, Hexapod] | None = None,
        targets: Callable[[str], tuple[object, np.ndarray | None]] | None = None,
        monitor: PlanMonitor | None = None,
    ):
        self.bus, self.sim, self.monitor = bus, sim, monitor
        rng = np.random.default_rng(sim.seed)
        hexapods = hexapods or {}
        self._encoders = []
        for s in sim.fixtures:
            cfg = service.fixture(s.name)
            hexa = hexapods.get(s.name) or cfg.load_hexapod()
            enc_rng = np.random.default_rng(rng.integers(2**63))
            self._encoders.append(_Encoders(s, cfg, hexa, enc_rng, targets, carried(sim.plan, s.name)))
        self.truth: deque[SentSet] = deque(maxlen=truth)
        self.frames_sent = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def send_set(self, index: int, t_sim: float, stamp: float | None = None, stall_check: bool = True) -> SentSet:
        """Send one reading set of fixture ``index`` (of ``sim.fixtures``) at simulation time ``t_sim``.

        With ``stamp`` (s, Unix) the frames carry it (plus :data:`FRAME_TIME` per frame, as a bus
        delivers a burst) as their timestamps; a virtual bus keeps them when it was created with
        ``preserve_timestamps=True``, so the receiver sees the sampling times however late this
        thread runs. Without, the bus stamps them when sent. ``stall_check``: a set sent more
        than a period after its stamp is lost, as an encoder's would be.
        """
        enc = self._encoders[index]
        pose, true = enc.advance(t_sim)
        msgs, faults = enc.frames(t_sim, true)
        t_first = time.time()
        if stamp is not None and stall_check and t_first - stamp > 1.0 / enc.sim.rate:  # this thread stalled: lost
            msgs = [None] * enc.n
        for k, m in enumerate(msgs):
            if m is not None and stamp is not None:
                m.timestamp = stamp + k * FRAME_TIME + enc.ahead.get(k, 0.0)
        enc.past.append(list(msgs))
        order: list[can.Message | None] = []
        for k, m in enumerate(msgs):
            if k in enc.duplicate and m is not None:
                second = enc.message(k, enc.duplicate[k])
                second.timestamp = m.timestamp - FRAME_TIME / 2
                order.append(second)
            order.append(None if k in enc.late else m)
        for k, sets in enc.late.items():  # the frame of `sets` sets ago, with its own stamp, last
            old = enc.past[-1 - sets][k] if len(enc.past) > sets else None
            order.append(old)
            msgs[k] = old
        if enc.cfg.canopen is not None:  # CANopen encoders answer a SYNC; their heartbeats are due
            beat = t_sim >= enc.next_beat
            if beat:
                enc.next_beat = t_sim + enc.cfg.canopen.heartbeat
            sync = master_frames(enc.cfg.canopen, None if stamp is None else stamp - FRAME_TIME, beat, enc.next_sync())
            order[:0] = sync
        order += enc.intruders(stamp)
        out = [m for m in order if m is not None for _ in range(enc.repeats)]
        if enc.burst > 1 or enc.held:  # a gateway: the burst goes out at once, stamped with its last frame
            enc.held += out
            enc.held_sets += 1
            out = []
            if enc.burst <= 1 or enc.held_sets >= enc.burst:
                out, enc.held, enc.held_sets = enc.held, [], 0
                for m in out:
                    m.timestamp = out[-1].timestamp
        for m in out:
            self.bus.send(m)
        if stamp is not None:
            t_first, t_last = stamp, stamp + (enc.n - 1) * FRAME_TIME
        else:
            t_last = time.time()
        sent = SentSet(enc.sim.name, t_sim, t_first, t_last, pose, true, tuple(m is not None for m in msgs), faults)
        self.frames_sent += sum(sent.sent)
        self.truth.append(sent)
        return sent

    def run(self, duration: float | None = None) -> None:
        """Send sets at each fixture's rate until :meth:`stop` or ``duration`` seconds of simulation.

        Frames are stamped with their sampling time (see :meth:`send_set`); a set due more than
        one period ago is skipped (its time passes unsent), never sent in a burst.
        """
        start, wall = time.monotonic(), time.time()
        if self.monitor is not None and self.sim.plan is not None:
            self.monitor.begin(wall + self.sim.plan.start)  # the frames' stamps are wall + t_sim
        due = [0.0] * len(self._encoders)
        while not self._stop.is_set():
            i = min(range(len(due)), key=due.__getitem__)
            t_sim = due[i]
            if duration is not None and t_sim >= duration:
                return
            wait = start + t_sim - time.monotonic()
            if wait > 0:
                self._stop.wait(min(wait, 0.05))
                continue
            period = 1.0 / self._encoders[i].sim.rate
            if -wait > period:  # late by more than a period (busy machine): encoders sample on their
                self._encoders[i].skip(t_sim)  # own clock, so this set is lost, not sent in a burst
            else:
                try:
                    self.send_set(i, t_sim, wall + t_sim)
                except (can.CanError, HexapodError) as exc:
                    log.error("simulated fixture %s: %s", self._encoders[i].sim.name, exc)
            due[i] += period

    @property
    def running(self) -> bool:
        """True while the background thread sends."""
        return self._thread is not None and self._thread.is_alive()

    def start(self, duration: float | None = None) -> None:
        """Run in a background thread."""
        self._stop.clear()
        self._thread = NamedThread(target=self.run, args=(duration,), name="hx-sim")
        self._thread.start()

    def stop(self) -> None:
        """Stop sending (and wait for the background thread)."""
        self._stop.set()
        if self._thread is not None:
            if self._thread.ident is not None:  # Ctrl-C may land between creating and starting it
                self._thread.join()
            self._thread = None
