"""One fixture's cycle: encoder frames in, one record per sampling instant out.

A **reading set** holds one frame of each leg (and of the inclinometer of a hexapod with
redundant sensors, whose measuring legs count as legs ``leg7``, ...) from one sampling instant:
every frame within ``max_skew`` (default: 3/4 of the measured frame period) of the set's first,
whatever the arrival order. A frame older than the newest seen by more than that is *late* and
never joins a set (``late_frame:legN`` in the next record); a second frame on one leg's id
within the instant fails the set (``duplicate_frame``, ``duplicate:legN``: two senders on one
id); a frame of a newer instant closes an unfinished set, published as ``incomplete``
(``missing:legN``) or, when a missing leg's newest frame is older than ``staleness``,
``silent_leg``; a leg whose stamps run ahead of the others' is dropped and named
(``ahead:legN``, :mod:`~hexapod_model.service.cycle.ahead`), and an exact repeat of a frame is
dropped and counted. A frame failing its layout's integrity check
(:mod:`~hexapod_model.service.cycle.frame_checks`: ``bad_crc``, ``counter_gap``) takes its leg's
place in its set, which is published ``bad_frame`` naming the check and the leg (``bad_crc:leg3``),
as is a CANopen set whose frames follow different SYNCs (``sync_mismatch``). A batching gateway's
bursts are split into instants where they can be (:mod:`~hexapod_model.service.cycle.burst`). So
every instant ends in a record, and a set never mixes two instants. A set with a bad frame, an
error bit, a reading outside the stroke or a stuck leg is published with that status and **no
pose**; a solved set is ``ok`` only when the tracker (through
:class:`~hexapod_model.service.cycle.solver.PoseSolver`) raised no flag, no leg of a locked
fixture moved and no fault waits for an acknowledgement
(:mod:`~hexapod_model.service.cycle.alarms`).

Status values: ``ok``, ``no_data`` (nothing received yet), ``incomplete``, ``duplicate_frame``,
``silent_leg``, ``bad_frame``, ``encoder_error``, ``out_of_stroke``, ``stuck_leg``,
``leg_moved`` (one or two legs of a locked fixture left the band: no pose), ``not_converged``,
``inconsistent_readings`` (redundant sensors whose readings fail the consistency test: the
others' estimate when the data name the faulty reading, ``isolated:NAME``, else no pose),
``flagged``, ``drift`` (a locked fixture's averaged readings moved: a pose, named legs),
``unacknowledged_fault`` (a pose, but a latched fault waits). Flags name the leg
(``encoder_error:leg3``) or the tracker's doubt (``jump``, ``branch_uncertain``,
``near_singular``, ``out_of_limits``); *advisory* flags leave a good pose ``ok``:
``encoder_warning:legN``, ``late_frame:legN``, ``moved_while_off``, ``stored_geometry_changed``.
``batched_stamps``: a gateway stamped a burst of instants once; with a pose (``flagged``) when
the burst was split into its instants by an estimated period (or the set shares a stamp with
the one before), without one (``incomplete``) when it could not be split.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from dataclasses import replace
from operator import le

import numpy as np
import pinocchio as pin

from ...analysis.sensitivity import SensitivityEvaluator
from ...kinematics.hexapod import Hexapod
from ...lie import quaternion_of_matrix
from ...tracking.steps import StepDetector
from ..config.cell import InRobot
from ..config.settings import FixtureConfig
from ..record.pose import pose_record
from ..record.pose_record import PoseRecord
from ..store.fixture_store import LockEvent
from ..targets.guidance import deviation, within
from ..targets.target import Target
from .ahead import AheadCheck
from .alarms import UNACKNOWLEDGED, Acknowledgement, FaultLatch, LatchedFault
from .burst import SAME_STAMP, SMALL_BURSTS, Bursts
from .frame_checks import CHECKS, FrameChecks
from .lock import MOTION_LEGS, LockDetector
from .lock_load import lock_load
from .solver import PoseSolver, SolveOutcome
from .stuck import StuckDetector

log = logging.getLogger(__name__)
_POSE_STATUSES = ("ok", "flagged", "drift")
STATUS_OF = {"ok": "ok", "flagged": "flagged", "failed": "not_converged", "inconsistent": "inconsistent_readings"}
CLOCK_BACK_FRAMES = 12  # late frames in a row (two sets, no frame on time): the bus's clock went back
MOVED_SIGMAS = 5.0  # moved_while_off: first pose farther than this many sigma from the stored lock pose
BATCH_MEMORY = 64  # sets after the last two sharing a stamp during which records stay `batched_stamps`
REPEAT = 0.25  # periods: a frame equal to its leg's last one within this is a repeat (a leg at rest sends equal ones)
INTERVALS = 255  # frame intervals kept for the period: about 40 sets, so lost sets cannot stretch it
LOST_BETWEEN = 1.5  # periods: a longer interval between two frames of a leg spans lost sets (counted as periods)


class FixtureCycle:
    """Frames of one fixture in, published records out (not thread-safe: one caller thread).

    Args:
        cfg: the fixture's configuration.
        hexa: its hexapod.
        geometry_hash: of ``hexa`` (stored with every lock).
        recovered: the last stored lock event of this fixture, or None.
        t0: start time (s, Unix), the ``t`` of the first ``no_data`` record.
        sensitivity: an evaluator of ``hexa`` shared with the other cycles run on the same thread
            (default: one of its own; see :class:`~hexapod_model.service.cycle.solver.PoseSolver`).
    """

    def __init__(
        self,
        cfg: FixtureConfig,
        hexa: Hexapod,
        geometry_hash: str,
        recovered: LockEvent | None,
        t0: float,
        sensitivity: SensitivityEvaluator | None = None,
    ):
        self.cfg, self.hexa, self.geometry_hash = cfg, hexa, geometry_hash
        self.layout = cfg.legs[0].layout
        self._unpack, self._min_length = self.layout.unpack, self.layout.length
        self._metres_per_count = self.layout.metres_per_count
        cfg.check_sensors(hexa)
        # channels: one frame of each per set; the legs' (six, then measuring legs), then the inclinometer's
        n, self._n_legs, self._tilt = cfg.channels, len(cfg.legs), cfg.inclinometer
        self._n = n
        self._names = [f"leg{k + 1}" for k in range(self._n_legs)] + ["inclinometer"] * (n - self._n_legs)
        stroke = hexa.stroke if hexa.redundancy is None else np.vstack([hexa.stroke, hexa.redundancy.layout.stroke])
        self._lo, self._hi = stroke[:, 0].tolist(), stroke[:, 1].tolist()
        self._home = [leg.home_count for leg in cfg.legs]
        self._t = [-math.inf] * n  # receipt time of each channel's newest frame (lists: faster than arrays here)
        self._heard = [-math.inf] * n  # stamp of each channel's newest frame of any kind (taken or dropped)
        self._floor = -math.inf  # t of the last silent_leg record of check_silence: older frames come too late
        self._readings = [math.nan] * len(hexa.reading_names)  # the legs', then tilt_x and tilt_y
        #: each extra reading of redundant sensors: (name, index in the readings, its channel)
        self._extra = [(name, k, min(k, self._n_legs)) for k, name in enumerate(hexa.reading_names) if k >= 6]
        self._data: list[bytes | bytearray] = [b""] * n  # each channel's newest frame (a repeat of it is dropped)
        self._counts = [0] * n
        self._err, self._warn, self._fresh = [False] * n, [False] * n, [False] * n
        self._bad = [""] * n  # why each channel's newest frame is unusable: "bad_frame" (short) or a failed check
        self.inconsistent_since: float | None = None  # t of the first set of a run of inconsistent ones
        self._n_fresh = 0
        self._max_skew, self._staleness = cfg.max_skew, cfg.staleness  # read per frame (the config is frozen)
        self.lock = LockDetector(cfg.lock_time, cfg.steady_band, cfg.drift_limit, cfg.unlock_samples)
        self.stuck = StuckDetector(cfg.stuck_sigmas, cfg.noise, self.layout.metres_per_count)
        self.steps = StepDetector(cfg.noise)
        self._period = math.nan  # s, lower quartile of the intervals between two frames of one leg (recent frames)
        self._intervals: list[float] = []
        self._n_frames = 0
        self._instant = self._lost = 0  # sampling instants, and sets lost since the last complete one
        self._t_set = math.nan
        self._batched = -(10**9)  # the last instant whose set shared its stamp with the previous set
        self._t_newest = self._t_first = -math.inf  # newest frame seen; first frame of the set being collected
        self._late: set[int] = set()  # legs whose late frames were dropped since the last record
        self._late_run = 0  # late frames in a row (more than CLOCK_BACK_FRAMES: the bus clock went back)
        self._duplicate: set[int] = set()  # legs with a second frame in the set being collected
        #: frames and sets that could not be used, since the start (``/health``)
        self.counters = {
            "late_frames": 0,
            "duplicate_frames": 0,
            "incomplete_sets": 0,
            "repeated_frames": 0,
            "ahead_frames": 0,
            "inconsistent_sets": 0,
            **dict.fromkeys(CHECKS, 0),  # frames (sets for sync_mismatch) failing an integrity check
        }
        integrity = self.layout.integrity
        self._checks = FrameChecks(integrity, self._n_legs) if integrity.checked else None
        self._sync_byte = integrity.sync_byte
        self._tags = [0] * self._n_legs  # the SYNC counter each leg's newest frame follows (CANopen)
        self._failed: dict[tuple[int, float], str] = {}  # (leg, stamp) of a frame that failed a check -> the check
        self._named: list[str] = []  # failed checks of duplicate frames dropped from the set being collected
        self._ahead = AheadCheck()
        self._bursts = Bursts(self.layout.sample_period, n)
        self._estimated = False  # the sets being published were dated by an estimated period (batched_stamps)
        self._pending: deque[PoseRecord] = deque()  # records of a burst, published one per call
        self.alarm = FaultLatch(cfg.name)
        self._drift_logged = False
        self._advisory: set[str] = set()
        self._episode = self._stored_episode = 0
        self._new_lock_stored = False
        self._load: dict | None = None  # the process wrench's loads at the lock pose
        self.recovered: LockEvent | None = None
        self.recovery = "no stored lock pose"
        if recovered is not None and recovered.geometry_hash == geometry_hash:
            self.recovered, self.recovery = recovered, f"initial guess: the lock pose stored at t={recovered.t!r}"
            self.alarm.fault = LatchedFault.from_stored(recovered.status)  # stored while a fault waited
        elif recovered is not None:
            self._advisory.add("stored_geometry_changed")
            self.recovery = "stored lock pose not used: solved with another geometry (hash differs)"
        self._check_moved = self.recovered is not None
        initial = None if self.recovered is None else self.recovered.q
        self.solver = PoseSolver(
            hexa, cfg.noise, cfg.predictor, initial, cfg.confirm_samples, sensitivity, self.layout.metres_per_count
        )
        #: the changeover target (set by :class:`~hexapod_model.service.changeover.changeover.Changeover`): a lock
        #: pose within its tolerance is stored naming it
        self.target: Target | None = None
        #: the lock to commit: the service takes it, stores it and calls :meth:`lock_stored`
        self.pending_lock: tuple[int, LockEvent] | None = None
        self._in_robot = None if cfg.cell is None else InRobot(cfg.cell, cfg.noise, self.solver.propagation)
        #: complete sets wait for :meth:`finish_held` (the service's cycle thread: the sets of many
        #: fixtures queued on the bus are then solved back to back, their code and data warm in the caches)
        self.hold_sets = False
        self._held: tuple[float, np.ndarray, bool, bool] | None = None  # the set waiting: t, readings, its lock states
        self._may_hold = False  # a frame on the plain path is being taken (not a burst's, not a silence check's)
        #: the latest record
        self.last: PoseRecord = self._record(t0, "no_data", [], None)
        self._listening = t0  # s: since when the bus is read (see listen)

    def listen(self, t: float) -> None:
        """The bus is read from ``t`` on (s, the bus's time): no leg is silent before ``t + staleness``.

        The service calls it when its cycle starts reading: the kernels' warm-up before it (up
        to a minute after installation) is no silence of the fixture's legs.
        """
        self._listening = t

    # ----- input -----
    def on_frame(self, leg: int, data: bytes | bytearray, t: float) -> PoseRecord | None:
        """A frame of leg ``leg`` (0-based) stamped ``t`` (s); returns a record when one is published.

        A set holds frames of one sampling instant: within ``max_skew`` of its first frame. A
        frame older than the newest by more than that is *late* (an instant already closed) and
        is dropped, named in the next record; a second frame on one leg's id within the instant
        is a *duplicate* (two senders?) and fails the set; a frame of a newer instant closes an
        unfinished set as ``incomplete`` (or ``silent_leg``) naming the missing legs. A frame that
        would open a newer instant waits for the next frame (:mod:`~hexapod_model.service.cycle.ahead`):
        one whose stamp ran ahead of the others is dropped and named (``ahead:legN``). An exact
        repeat of a leg's frame (a gateway's) is dropped and counted. A gateway's bursts of
        instants under one stamp are buffered and split (:mod:`~hexapod_model.service.cycle.burst`):
        their records come one per call, after the burst.
        """
        if self._held is not None:  # a set held (hold_sets) and not finished: its record first
            self._queue_held()
        if t > self._heard[leg]:
            self._heard[leg] = t
        if self._bursts.engaged or self._bursts.shares_instant(leg, data, t):
            self._may_hold = False
            return self._burst_frame(leg, data, t)
        self._may_hold = self.hold_sets and not self._pending
        record = self._frame(leg, data, t)
        if self._pending:  # a burst's records are still queued: this one after them
            if record is not None:
                self._pending.append(record)
            return self._pending.popleft()
        return record

    def _frame(self, leg: int, data: bytes | bytearray, t: float, check: bool = True) -> PoseRecord | None:
        """A frame outside burst mode (see :meth:`on_frame`); ``check``: not checked yet (integrity)."""
        skew = self._max_skew or 0.75 * self._period  # NaN until the period is measured
        if t < self._t_newest - skew:  # older than this instant: a late frame (False for NaN)
            self._late_run += 1
            if self._late_run <= CLOCK_BACK_FRAMES:
                self.counters["late_frames"] += 1
                self._late.add(leg)
                return None
            self._clock_went_back(t)
        self._late_run = 0
        if t < self._floor:  # of an instant a silent_leg record covered: late (record times never run backwards)
            self.counters["late_frames"] += 1
            self._late.add(leg)
            return None
        since, window, ahead = t - self._t[leg], REPEAT * self._period, self._ahead  # a repeat comes at once
        if (
            (since == 0.0 or since <= window)
            and data == self._data[leg]
            or (ahead.held is not None and ahead.repeats(leg, data, t, window))
        ):
            self.counters["repeated_frames"] += 1  # the same frame again (a gateway's repeat)
            return None
        if self._checks is not None and check and leg < self._n_legs:  # the legs' layout (not the inclinometer's)
            failed = self._checks.check(leg, data)
            if failed is not None:  # it takes its leg's place in its set, which gives no pose
                self.counters[failed] += 1
                if len(self._failed) > 64:  # frames dropped meanwhile (ahead): never taken
                    self._failed.clear()
                self._failed[leg, t] = failed
        if ahead.held is None and not t > self._t_newest + skew:  # taken at once, as offer() would (False for NaN)
            return self._take(leg, data, t, skew)
        published = None
        current = self._t_first if self._n_fresh else self._t_newest
        for frame in ahead.offer(leg, data, t, skew, self._t_newest, current):
            published = self._take(*frame, skew) or published
        return published

    def _burst_frame(self, leg: int, data: bytes | bytearray, t: float) -> PoseRecord | None:
        """A frame in burst mode (:mod:`~hexapod_model.service.cycle.burst`): buffered; a new stamp judges the burst."""
        bursts = self._bursts
        if t < bursts.stamp - SAME_STAMP:  # older than the burst being received
            self.counters["late_frames"] += 1
            self._late.add(leg)
            return self._pending.popleft() if self._pending else None
        if t - bursts.stamp >= SAME_STAMP:
            single = len(bursts.frames) == 1 and bursts.frames.pop()  # not a burst: taken as a frame below
            self._close_burst(t)
            if single or bursts.small >= SMALL_BURSTS:  # stamps separate instants again
                bursts.disengage()
                if single:  # checked when it came
                    if single[3] is not None:
                        self._failed[single[0], single[2]] = single[3]
                    record = self._frame(*single[:3], check=False)
                    if record is not None:
                        self._pending.append(record)
                record = self._frame(leg, data, t)
                if record is not None:
                    self._pending.append(record)
                return self._pending.popleft() if self._pending else None
        failed = self._checks.check(leg, data) if self._checks is not None and leg < self._n_legs else None
        if failed is not None:
            self.counters[failed] += 1
        if not bursts.add(leg, data, t, failed):
            self.counters["repeated_frames"] += 1
        return self._pending.popleft() if self._pending else None

    def _close_burst(self, next_stamp: float) -> None:
        """Judge the burst received; its sets' records (or one ``incomplete`` record) wait in the queue."""
        frames, times, instants, exact = self._bursts.close(next_stamp)
        if not frames:
            return
        if times is None:  # its frames cannot be put into instants: no pose from them
            self._lost += instants
            self.counters["incomplete_sets"] += instants
            self._pending.append(self._failure(frames[-1][2], "incomplete", self._set_flags(["batched_stamps"])))
            return
        skew = self._max_skew or 0.75 * self._period
        self._estimated = not exact
        for j, (leg, data, _, failed) in enumerate(frames):
            t = times[j // self._n]
            if failed is not None:
                self._failed[leg, t] = failed
            record = self._take(leg, data, t, skew)
            if record is not None:
                self._pending.append(record)
        self._estimated = False

    def _take(self, leg: int, data: bytes | bytearray, t: float, skew: float) -> PoseRecord | None:
        """Add a frame that is neither late, a repeat nor ahead to the set (see :meth:`on_frame`)."""
        if self._held is not None:  # (a second frame of one call: the held set's record before any other)
            self._queue_held()
        published = None
        n_fresh, ts = self._n_fresh, self._t
        if n_fresh:
            repeat = self._fresh[leg]
            if t - self._t_first > skew or (repeat and not t - ts[leg] <= skew):
                published = self._close_incomplete()  # a newer instant begins: this set cannot complete
                n_fresh = 0
            elif repeat:  # a second frame on this id within one instant
                self.counters["duplicate_frames"] += 1
                self._duplicate.add(leg)
                why = self._failed.pop((leg, t), None) if self._failed else None
                if why is not None:
                    self._named.append(f"{why}:{self._names[leg]}")
                return None
        if self._failed and (leg, t) in self._failed:
            self._bad[leg], self._readings[leg] = self._failed.pop((leg, t)), math.nan
        elif leg >= self._n_legs:  # the inclinometer's frame: two angles
            self._tilt_frame(leg, data)
        elif len(data) >= self._min_length:  # codec.decode's check, without its exception on the hot path
            count, self._err[leg], self._warn[leg] = self._unpack(data)
            self._counts[leg], self._bad[leg] = count, ""
            self._readings[leg] = (count - self._home[leg]) * self._metres_per_count
            if self._sync_byte is not None:
                self._tags[leg] = data[self._sync_byte]
        else:
            self._bad[leg], self._readings[leg] = "bad_frame", math.nan
        dt = t - ts[leg]
        if 0.0 < dt <= self._staleness:  # the lower quartile ignores missed frames (up to 3 in 4 intervals)
            period, intervals, k = self._period, self._intervals, self._n_frames
            if dt > LOST_BETWEEN * period:  # sets were lost between: one period of them (False for NaN),
                dt /= round(dt / period)  # so that losing most sets (a busy sender) cannot double the period
            if len(intervals) < INTERVALS:
                intervals.append(dt)
            else:
                intervals[k % INTERVALS] = dt
            self._n_frames = k = k + 1
            if k % 32 == 8:
                self._period = sorted(intervals)[len(intervals) // 4]
        ts[leg], self._data[leg] = t, data
        if t > self._t_newest:
            self._t_newest = t
        if not n_fresh:
            self._t_first = t
        self._fresh[leg] = True
        self._n_fresh = n_fresh = n_fresh + 1
        if n_fresh == self._n:
            self._fresh = [False] * n_fresh
            self._n_fresh = 0
            if self._duplicate:
                self._lost += 1
                return self._failure(self._t_newest, "duplicate_frame", self._set_flags([]))
            return self._complete(self._t_newest)
        return published

    def _tilt_frame(self, channel: int, data: bytes | bytearray) -> None:
        """Decode the inclinometer's frame into the last two readings (a short one is a bad frame)."""
        tilt = self._tilt
        assert tilt is not None
        if len(data) >= tilt.length:
            x, y, self._err[channel], self._warn[channel] = tilt.readings(data)
            self._readings[-2], self._readings[-1], self._bad[channel] = x, y, ""
        else:
            self._bad[channel], self._readings[-2], self._readings[-1] = "bad_frame", math.nan, math.nan

    def _clock_went_back(self, t: float) -> None:
        """Frames keep coming older than the newest one: the bus's clock was set back; follow it."""
        back = self._t_newest - t
        log.warning("fixture %s: frame times went back %.3g s: following the bus clock", self.cfg.name, back)
        self._t_newest, self._t_set, self._t = t, math.nan, [min(tk, t) for tk in self._t]
        self._heard, self._floor = [min(tk, t) for tk in self._heard], -math.inf
        self._fresh, self._n_fresh = [False] * self._n, 0
        self._ahead.clear()
        self._failed.clear()
        self._lost += round(self._late_run / self._n)  # the sets whose frames were taken for late ones
        self._late.clear()
        self.lock.restart_clock(t)

    def _close_incomplete(self) -> PoseRecord:
        """Publish the unfinished set: ``silent_leg`` when a missing leg is stale, else what went wrong."""
        t = self._t_newest
        missing = [k for k in range(self._n) if not self._fresh[k]]
        self._fresh = [False] * self._n
        self._n_fresh = 0
        self._lost += 1
        self.counters["incomplete_sets"] += 1
        quiet = self._late | self._ahead.legs  # legs that sent, late or ahead: not silent
        silent = [k for k in missing if t - self._t[k] > self.cfg.staleness and k not in quiet]
        if silent:
            return self._failure(t, "silent_leg", self._set_flags([f"silent:{self._names[k]}" for k in silent]))
        status = "duplicate_frame" if self._duplicate else "incomplete"
        return self._failure(t, status, self._set_flags([f"missing:{self._names[k]}" for k in missing]))

    def _set_flags(self, flags: list[str]) -> list[str]:
        """``flags`` plus the set's duplicate and late frames (then forgotten)."""
        if self._named:
            flags += self._named
            self._named = []
        if self._duplicate:
            flags += [f"duplicate:{self._names[k]}" for k in sorted(self._duplicate)]
            self._duplicate.clear()
        if self._late:
            flags += [f"late_frame:{self._names[k]}" for k in sorted(self._late)]
            self._late.clear()
        if self._ahead.legs:
            flags += [f"ahead:{self._names[k]}" for k in sorted(self._ahead.legs)]
            self._ahead.legs.clear()
            self.counters["ahead_frames"] = self._ahead.frames
        return flags

    def check_silence(self, now: float) -> PoseRecord | None:
        """Publish ``silent_leg`` when nothing was published for ``staleness`` and a leg is silent.

        ``now`` (s) is the bus's time. A leg is silent when no frame of it came for ``staleness``
        (one dropped as ahead, late or repeated counts: it is heard). While a set is being
        collected, or a frame is held (:mod:`~hexapod_model.service.cycle.ahead`), within
        ``staleness`` of ``now``, frames flow: that set's record names what is missing. Frames
        older than a published ``silent_leg`` record are late from then on, so record times never
        run backwards; the unfinished set it ends is counted incomplete. A burst still buffered
        ``staleness`` after its stamp is judged now (the gateway sent no more).
        """
        if self._held is not None:  # a set held (hold_sets): its record first
            self._queue_held()
        self._may_hold = False
        staleness = self.cfg.staleness
        if self._bursts.frames and now - self._bursts.stamp > staleness:
            self._close_burst(self._bursts.stamp)
        if self._pending:
            return self._pending.popleft()
        if now - max(self.last.t, self._listening) <= staleness:
            return None
        if (self._n_fresh and now - self._t_first <= staleness) or now - self._ahead.held_stamp <= staleness:
            return None
        silent = [k for k in range(self._n) if now - self._heard[k] > staleness]
        if not silent:
            return None
        self._floor = now
        if self._n_fresh:
            self._fresh, self._n_fresh = [False] * self._n, 0
            self._lost += 1
            self.counters["incomplete_sets"] += 1
        return self._failure(now, "silent_leg", [f"silent:{self._names[k]}" for k in silent])

    def lock_stored(self, episode: int, event: LockEvent) -> None:
        """Called (from the store's thread) once ``event`` of lock ``episode`` is committed."""
        self._stored_episode = episode
        self._new_lock_stored = True
        log.info("fixture %s: lock pose stored (id %s, t=%r)", self.cfg.name, event.id, event.t)

    @property
    def fault(self) -> LatchedFault | None:
        """The fault waiting for an acknowledgement (:mod:`~hexapod_model.service.cycle.alarms`)."""
        return self.alarm.fault

    @property
    def acknowledged(self) -> Acknowledgement | None:
        """The last acknowledgement."""
        return self.alarm.acknowledged

    def acknowledge(self, by: str, client: str, note: str = "", now: float | None = None) -> Acknowledgement | None:
        """Acknowledge the latched fault (None when there is none); safe from another thread.

        The cycle's thread clears the fault at its next set; a locked fixture then takes a new
        lock from its readings as they are.
        """
        return self.alarm.request(by, client, note, now)

    @property
    def holding(self) -> bool:
        """Whether a complete set waits for :meth:`finish_held` (:attr:`hold_sets`)."""
        return self._held is not None

    def finish_held(self) -> PoseRecord | None:
        """Solve the held set (:attr:`hold_sets`) and return its record; None when no set is held."""
        held, self._held = self._held, None
        return None if held is None else self._solved(*held)

    def _queue_held(self) -> None:
        """Solve the held set now; its record goes first in the queue of records to publish."""
        record = self.finish_held()
        if record is not None:
            self._pending.append(record)

    # ----- one set -----
    def _complete(self, t: float) -> PoseRecord | None:
        steps, dt = 1 + self._lost, t - self._t_set  # instants since the last set: lost sets count
        if dt > 0.0 and self._period > 0.0:  # (False for NaN)
            steps = max(steps, round(dt / self._period))
        self._instant += steps
        if dt < SAME_STAMP:  # this set has the stamp of the previous one: a gateway stamped the burst once
            self._batched = self._instant
        self._lost, self._t_set = 0, t
        # the braked legs' readings: the lock, stuck and step detectors watch the six legs
        six = self._readings if self._n == 6 else self._readings[:6]
        if self.alarm.requested and self.alarm.take() is not None:  # acknowledged: readings taken as they are
            self.steps.reset()
            if self.lock.state == "locked":
                self.lock.release(t, six)
                self._episode += 1
        r = np.array(self._readings)
        if any(self._bad):  # a short frame, or one that failed an integrity check
            return self._failure(
                t, "bad_frame", self._set_flags([f"{b}:{self._names[k]}" for k, b in enumerate(self._bad) if b])
            )
        if self._sync_byte is not None and self._tags.count(self._tags[0]) != len(self._tags):
            self.counters["sync_mismatch"] += 1
            mixed = FrameChecks.sync_mismatch(self._tags)
            return self._failure(t, "bad_frame", self._set_flags([f"sync_mismatch:{self._names[k]}" for k in mixed]))
        if any(self._err):
            flags = [f"encoder_error:{self._names[k]}" for k in range(self._n) if self._err[k]]
            return self._failure(t, "encoder_error", self._set_flags(flags))
        lo, hi, readings = self._lo, self._hi, self._readings
        if not (all(map(le, lo, readings)) and all(map(le, readings, hi))):  # False for NaN, as below
            out = [k for k in range(len(lo)) if not lo[k] <= readings[k] <= hi[k]]
            return self._failure(t, "out_of_stroke", self._set_flags([f"out_of_stroke:leg{k + 1}" for k in out]))
        stuck = self.stuck.update(self._instant, self._counts[:6], six)
        if stuck:
            return self._failure(t, "stuck_leg", self._set_flags([f"stuck:leg{k + 1}" for k in stuck]))
        was_locked = self.lock.state == "locked"
        ready = self.lock.update(t, six)
        if was_locked and self.lock.state != "locked":
            self._episode += 1
            log.info("fixture %s: moving (lock released)", self.cfg.name)
        if self._may_hold:  # solved by finish_held, before this cycle takes another frame
            self._held = (t, r, was_locked, ready)
            return None
        return self._solved(t, r, was_locked, ready)

    def _solved(self, t: float, r: np.ndarray, was_locked: bool, ready: bool) -> PoseRecord:
        """The rest of :meth:`_complete`: the set's readings ``r`` solved, checked and recorded."""
        six = self._readings if self._n == 6 else self._readings[:6]  # no frame was taken since _complete
        outcome = self.solver.step(r, self._instant)
        jumped = outcome.legs if "jump" in outcome.flags else ()
        stepped = self.steps.update(self._instant, six, jumped)
        if stepped:  # on a locked fixture a leg moved alone: brake slip or encoder, six readings cannot tell
            self.alarm.latch("moved_while_locked" if was_locked else "discontinuity", stepped, t)
        if self.lock.slipped:
            self.alarm.latch("moved_while_locked", self.lock.slipped, t)
        if outcome.status == "ok":
            if self._check_moved:
                self._compare_recovered(t, outcome)
            elif ready:
                self._take_lock(t, outcome)
        flags = self._set_flags(list(outcome.flags))
        if self.lock.moved:  # one or two legs left the band of a locked fixture: not a new pose
            return self._failure(t, "leg_moved", flags + [f"moved:leg{k + 1}" for k in self.lock.moved])
        if self.lock.drift and not self._drift_logged:
            log.warning("fixture %s: drift: locked readings moved beyond %g m", self.cfg.name, self.cfg.drift_limit)
        self._drift_logged = self.lock.drift
        if self.lock.drift:
            if len(self.lock.drift_legs) < MOTION_LEGS:
                self.alarm.latch("moved_while_locked", self.lock.drift_legs, t)
            flags += [f"drift:leg{k + 1}" for k in self.lock.drift_legs]
        status = STATUS_OF[outcome.status]
        self._note_inconsistent(t, status, flags)
        if self.steps.pending and "jump" not in flags:  # a jump that may be a step: not ok until it is known
            flags.append("jump")
            status = "flagged" if status == "ok" else status
        if self._estimated or self._instant - self._batched <= BATCH_MEMORY:  # t: the burst's, or estimated
            flags.append("batched_stamps")
            status = "flagged" if status == "ok" else status
        if status == "ok" and self.lock.drift:
            status = "drift"
        return self._record(t, status, flags, outcome)

    def _compare_recovered(self, t: float, outcome: SolveOutcome) -> None:
        rec = self.recovered
        assert rec is not None and outcome.pose is not None and outcome.uncertainty is not None
        self._check_moved = False
        u = outcome.uncertainty
        dt = float(np.linalg.norm(outcome.pose[:3, 3] - rec.position))
        R = pin.Quaternion(*rec.quaternion[[3, 0, 1, 2]]).toRotationMatrix()
        dr = float(np.linalg.norm(pin.log3(R.T @ outcome.pose[:3, :3])))
        if dt > MOVED_SIGMAS * u.translation or dr > MOVED_SIGMAS * u.rotation:
            self._advisory.add("moved_while_off")
            log.warning(
                "fixture %s: moved while off: %.3g mm, %.3g deg from the stored lock pose",
                self.cfg.name,
                dt * 1e3,
                math.degrees(dr),
            )
        else:
            self.lock.lock(t, rec.readings)
            self._load = lock_load(self.cfg, self.hexa, rec.q)
            self._episode += 1
            self._stored_episode = self._episode

    def _note_inconsistent(self, t: float, status: str, flags: list[str]) -> None:
        """Count inconsistent sets; log the first of a run (naming the reading when the data do) and its end."""
        if status == "inconsistent_readings":
            self.counters["inconsistent_sets"] += 1
            if self.inconsistent_since is None:
                self.inconsistent_since = t
                named = [f for f in flags if f.startswith("isolated:")]
                log.warning(
                    "fixture %s: inconsistent readings%s: no ok pose until they agree again",
                    self.cfg.name,
                    f" ({named[0]})" if named else " (the faulty reading is not named)",
                )
        elif self.inconsistent_since is not None:
            log.info("fixture %s: readings consistent again after %.3g s", self.cfg.name, t - self.inconsistent_since)
            self.inconsistent_since = None

    def _take_lock(self, t: float, outcome: SolveOutcome) -> None:
        mean = self.lock.run_mean
        # redundant sensors have no brake: the lock pose is solved from the legs' mean and their latest readings
        every = mean if self._n == 6 else np.concatenate([mean, self._readings[6:]])
        sol = self.solver.solve_once(every, outcome.q)  # type: ignore[arg-type]
        if sol.status != "converged":
            self.lock.restart(t, np.array(self._readings[:6]))
            return
        quat = _quaternion(sol.pose[:3, :3])
        status = "ok" if self.fault is None else self.fault.stored_status()  # the lock carries a waiting fault
        event = LockEvent(self.cfg.name, t, sol.pose[:3, 3].copy(), quat, mean, status, self.geometry_hash, sol.q)
        target, u = self.target, outcome.uncertainty
        if target is not None and u is not None and status == "ok":  # a lock with a fault meets no target
            sigma = {"translation_mm": u.translation * 1e3, "rotation_deg": math.degrees(u.rotation)}
            if within(deviation(sol.pose, target.pose), sigma, target.tolerance):
                event = replace(event, target_id=target.id, recipe=target.recipe)
        self.lock.lock(t, mean)
        self._load = lock_load(self.cfg, self.hexa, sol.q)
        self._episode += 1
        self.pending_lock = (self._episode, event)
        log.info("fixture %s: locked", self.cfg.name)

    # ----- records -----
    def _failure(self, t: float, status: str, flags: list[str]) -> PoseRecord:
        return self._record(t, status, flags, None)

    def _record(self, t: float, status: str, flags: list[str], outcome: SolveOutcome | None) -> PoseRecord:
        if self._new_lock_stored:
            self._new_lock_stored = False
            self._advisory -= {"moved_while_off", "stored_geometry_changed"}
        if any(self._warn):
            flags.extend(
                f"encoder_warning:{self._names[k]}" for k in range(self._n) if self._warn[k] and not self._err[k]
            )
        if self._advisory:
            flags.extend(sorted(self._advisory))
        if self.fault is not None:  # nothing is ok until the fault is acknowledged
            flags.extend(self.fault.flags())
            if status in _POSE_STATUSES:
                status = UNACKNOWLEDGED
        pose = sigma = margin = in_robot = None
        if outcome is not None and outcome.pose is not None and outcome.uncertainty is not None:
            u = outcome.uncertainty
            pose = pose_record(outcome.pose)
            if math.isfinite(u.translation) and math.isfinite(u.rotation):
                sigma = {"translation_mm": u.translation * 1e3, "rotation_deg": math.degrees(u.rotation)}
                margin = u.margin
            elif status == "ok":
                status = "flagged"
                flags.append("near_singular")
            if self._in_robot is not None:
                in_robot = self._in_robot.record(outcome.pose, outcome.q, sigma)
        old, readings = t - self.cfg.staleness, self._readings if self._n == 6 else self._readings[:6]
        total = sum(readings)  # NaN when a reading is (readings are finite otherwise)
        if total == total and min(self._t) >= old:  # every reading fresh: the common case
            fresh: list[float | None] = list(readings)
        else:
            fresh = [None if v != v or self._t[k] < old else v for k, v in enumerate(readings)]  # v != v: NaN
        locked = self.lock.state == "locked"
        extra = test = None
        if self._extra:  # redundant sensors: their readings by name, fresh as the legs' are
            r, ts = self._readings, self._t
            extra = {name: None if r[k] != r[k] or ts[c] < old else r[k] for name, k, c in self._extra}
        if outcome is not None and outcome.consistency is not None:
            c = outcome.consistency
            test = {"chi2": c.statistic, "bound": c.threshold, "dof": c.dof, "alpha": c.alpha}
        record = PoseRecord(
            self.cfg.name,
            t,
            fresh,
            pose,
            status,
            flags,
            0 if outcome is None else outcome.iterations,
            self.lock.state,
            locked and self._stored_episode == self._episode,
            sigma,
            margin,
            self._load if locked else None,
            in_robot,
            None if pose is None else outcome.pose,  # type: ignore[union-attr]
            None if pose is None else outcome.q,  # type: ignore[union-attr]
            extra,
            test,
        )
        self.last = record
        return record


def _quaternion(R: np.ndarray) -> np.ndarray:
    """``qx, qy, qz, qw`` of ``R`` with ``qw >= 0``."""
    return np.array(quaternion_of_matrix(R))
