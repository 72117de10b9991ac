"""One fixture's cycle: encoder frames in, complete reading sets solved, records out.

A **reading set** is complete when each of the six legs has sent a frame since the last set,
all within ``max_skew`` of each other (default: 3/4 of the measured frame period) and younger
than ``staleness``. A leg sending twice before the set completes (a frame of another leg was
lost) starts a new set, and frames farther than ``max_skew`` from the newest are dropped from
it, so a set never mixes readings of two sampling instants (and re-synchronises after a lost
frame); when the missing leg's newest frame is older than ``staleness`` the set is published
as ``silent_leg``. A set with a bad frame, an error bit, a reading outside the stroke or a stuck
leg is published with that status and **no pose**; a solved set is ``ok`` only when the tracker
(through :class:`~hexapod_model.service.solve.PoseSolver`) raised no flag.

Status values: ``ok``, ``no_data`` (nothing received yet), ``silent_leg``, ``bad_frame``,
``encoder_error``, ``out_of_stroke``, ``stuck_leg``, ``not_converged``, ``flagged``. Flags name the
leg (``encoder_error:leg3``) or the tracker's doubt (``jump``, ``branch_uncertain``,
``near_singular``, ``out_of_limits``); *advisory* flags leave a good pose ``ok``:
``encoder_warning:legN``, ``drift``, ``moved_while_off``, ``stored_geometry_changed``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import numpy as np
import pinocchio as pin

from ..kinematics.hexapod import Hexapod
from .cell import InRobot
from .config import FixtureConfig
from .guidance import deviation, within
from .pose import pose_record, quaternion
from .solve import PoseSolver, SolveOutcome
from .state import LockDetector, StuckDetector
from .store import LockEvent
from .targets import Target

log = logging.getLogger(__name__)
RECORD_KEYS = (
    "fixture",
    "t",
    "readings",
    "pose",
    "status",
    "flags",
    "iterations",
    "state",
    "stored",
    "sigma",
    "singularity_margin",
    "pose_in_robot",
)
MOVED_SIGMAS = 5.0  # moved_while_off: first pose farther than this many sigma from the stored lock pose


class FixtureCycle:
    """Frames of one fixture in, published records out (not thread-safe: one caller thread).

    Args:
        cfg: the fixture's configuration.
        hexa: its hexapod.
        geometry_hash: of ``hexa`` (stored with every lock).
        recovered: the last stored lock event of this fixture, or None.
        t0: start time (s, Unix), the ``t`` of the first ``no_data`` record.
    """

    def __init__(self, cfg: FixtureConfig, hexa: Hexapod, geometry_hash: str, recovered: LockEvent | None, t0: float):
        self.cfg, self.hexa, self.geometry_hash = cfg, hexa, geometry_hash
        self.layout = cfg.legs[0].layout
        self._unpack, self._min_length = self.layout.unpack, self.layout.length
        self._metres_per_count = self.layout.metres_per_count
        self._lo, self._hi = hexa.stroke[:, 0].tolist(), hexa.stroke[:, 1].tolist()
        self._home = [leg.home_count for leg in cfg.legs]
        self._t = [-math.inf] * 6  # receipt time of each leg's newest frame (lists: faster than arrays here)
        self._readings = [math.nan] * 6
        self._counts = [0] * 6
        self._err, self._warn, self._bad, self._fresh = [False] * 6, [False] * 6, [False] * 6, [False] * 6
        self._n_fresh = 0
        self.lock = LockDetector(cfg.lock_time, cfg.steady_band, cfg.drift_limit, cfg.unlock_samples)
        self.stuck = StuckDetector(cfg.stuck_sigmas, cfg.noise, self.layout.metres_per_count)
        self._period = math.nan  # s, median interval between two frames of one leg (recent frames)
        self._intervals: list[float] = []
        self._n_frames = 0
        self._instant = self._lost = 0  # sampling instants, and sets lost since the last complete one
        self._t_set = math.nan
        self._advisory: set[str] = set()
        self._episode = self._stored_episode = 0
        self._new_lock_stored = False
        self.recovered: LockEvent | None = None
        self.recovery = "no stored lock pose"
        if recovered is not None and recovered.geometry_hash == geometry_hash:
            self.recovered, self.recovery = recovered, f"initial guess: the lock pose stored at t={recovered.t!r}"
        elif recovered is not None:
            self._advisory.add("stored_geometry_changed")
            self.recovery = "stored lock pose not used: solved with another geometry (hash differs)"
        self._check_moved = self.recovered is not None
        initial = None if self.recovered is None else self.recovered.q
        self.solver = PoseSolver(hexa, cfg.noise, cfg.predictor, initial, cfg.confirm_samples)
        #: the changeover target (set by :class:`~hexapod_model.service.changeover.Changeover`): a lock
        #: pose within its tolerance is stored naming it
        self.target: Target | None = None
        #: the lock to commit: the service takes it, stores it and calls :meth:`lock_stored`
        self.pending_lock: tuple[int, LockEvent] | None = None
        self._in_robot = None if cfg.cell is None else InRobot(cfg.cell, cfg.noise, self.solver.propagation)
        self.last: dict = self._record(t0, "no_data", [], None)

    # ----- input -----
    def on_frame(self, leg: int, data: bytes | bytearray, t: float) -> dict | None:
        """A frame of leg ``leg`` (0-based) received at ``t`` (s); returns a record when one is published."""
        published = None
        if self._fresh[leg]:  # a leg repeats: some other leg's frame is missing
            self._fresh = [False] * 6
            self._n_fresh = 0
            self._lost += 1
            silent = [k for k in range(6) if k != leg and t - self._t[k] > self.cfg.staleness]
            if silent:
                published = self._failure(t, "silent_leg", [f"silent:leg{k + 1}" for k in silent])
        if len(data) >= self._min_length:  # codec.decode's check, without its exception on the hot path
            count, self._err[leg], self._warn[leg] = self._unpack(data)
            self._counts[leg], self._bad[leg] = count, False
            self._readings[leg] = (count - self._home[leg]) * self._metres_per_count
        else:
            self._bad[leg], self._readings[leg] = True, math.nan
        dt = t - self._t[leg]
        if 0.0 < dt <= self.cfg.staleness:  # the median ignores missed frames and bunched arrivals
            if len(self._intervals) < 63:
                self._intervals.append(dt)
            else:
                self._intervals[self._n_frames % 63] = dt
            self._n_frames += 1
            if self._n_frames % 32 == 8:
                self._period = sorted(self._intervals)[len(self._intervals) // 2]
        self._t[leg] = t
        self._fresh[leg] = True
        self._n_fresh += 1
        if self._n_fresh == 6:
            skew = self.cfg.max_skew or 0.75 * self._period
            if t - min(self._t) > skew:  # frames of two sampling instants: keep the newest
                self._fresh = [bool(t - tk <= skew) for tk in self._t]
                self._n_fresh = sum(self._fresh)
                self._lost += 1
                return published
            self._fresh = [False] * 6
            self._n_fresh = 0
            return self._complete(t)
        return published

    def check_silence(self, now: float) -> dict | None:
        """Publish ``silent_leg`` when nothing was published for ``staleness`` and a leg is silent."""
        if now - self.last["t"] <= self.cfg.staleness:
            return None
        silent = [k for k in range(6) if now - self._t[k] > self.cfg.staleness]
        if not silent:
            return None
        return self._failure(now, "silent_leg", [f"silent:leg{k + 1}" for k in silent])

    def lock_stored(self, episode: int, event: LockEvent) -> None:
        """Called (from the store's thread) once ``event`` of lock ``episode`` is committed."""
        self._stored_episode = episode
        self._new_lock_stored = True
        log.info("fixture %s: lock pose stored (id %s, t=%r)", self.cfg.name, event.id, event.t)

    # ----- one set -----
    def _complete(self, t: float) -> dict:
        steps, dt = 1 + self._lost, t - self._t_set  # instants since the last set: lost sets count
        if dt > 0.0 and self._period > 0.0:  # (False for NaN)
            steps = max(steps, round(dt / self._period))
        self._instant += steps
        self._lost, self._t_set = 0, t
        r = np.array(self._readings)
        for status, bad, name in (
            ("bad_frame", self._bad, "bad_frame"),
            ("encoder_error", self._err, "encoder_error"),
        ):
            if any(bad):
                return self._failure(t, status, [f"{name}:leg{k + 1}" for k in range(6) if bad[k]])
        out = [k for k in range(6) if not self._lo[k] <= self._readings[k] <= self._hi[k]]
        if out:
            return self._failure(t, "out_of_stroke", [f"out_of_stroke:leg{k + 1}" for k in out])
        stuck = self.stuck.update(self._instant, self._counts, self._readings)
        if stuck:
            return self._failure(t, "stuck_leg", [f"stuck:leg{k + 1}" for k in stuck])
        was_locked = self.lock.state == "locked"
        ready = self.lock.update(t, self._readings)
        if was_locked and self.lock.state != "locked":
            self._episode += 1
            log.info("fixture %s: moving (lock released)", self.cfg.name)
        outcome = self.solver.step(r, self._instant)
        if outcome.status == "ok":
            if self._check_moved:
                self._compare_recovered(t, outcome)
            elif ready:
                self._take_lock(t, outcome)
        if self.lock.drift and "drift" not in self._advisory:
            log.warning("fixture %s: drift: locked readings moved beyond %g m", self.cfg.name, self.cfg.drift_limit)
        self._advisory.discard("drift")
        if self.lock.drift:
            self._advisory.add("drift")
        status = {"ok": "ok", "flagged": "flagged", "failed": "not_converged"}[outcome.status]
        return self._record(t, status, list(outcome.flags), outcome)

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
            self._episode += 1
            self._stored_episode = self._episode

    def _take_lock(self, t: float, outcome: SolveOutcome) -> None:
        mean = self.lock.run_mean
        sol = self.solver.solve_once(mean, outcome.q)  # type: ignore[arg-type]
        if sol.status != "converged":
            self.lock.restart(t, np.array(self._readings))
            return
        quat = _quaternion(sol.pose[:3, :3])
        event = LockEvent(self.cfg.name, t, sol.pose[:3, 3].copy(), quat, mean, "ok", self.geometry_hash, sol.q)
        target, u = self.target, outcome.uncertainty
        if target is not None and u is not None:
            sigma = {"translation_mm": u.translation * 1e3, "rotation_deg": math.degrees(u.rotation)}
            if within(deviation(sol.pose, target.pose), sigma, target.tolerance):
                event = replace(event, target_id=target.id, recipe=target.recipe)
        self.lock.lock(t, mean)
        self._episode += 1
        self.pending_lock = (self._episode, event)
        log.info("fixture %s: locked", self.cfg.name)

    # ----- records -----
    def _failure(self, t: float, status: str, flags: list[str]) -> dict:
        return self._record(t, status, flags, None)

    def _record(self, t: float, status: str, flags: list[str], outcome: SolveOutcome | None) -> dict:
        if self._new_lock_stored:
            self._new_lock_stored = False
            self._advisory -= {"moved_while_off", "stored_geometry_changed"}
        if any(self._warn):
            flags.extend(f"encoder_warning:leg{k + 1}" for k in range(6) if self._warn[k] and not self._err[k])
        if self._advisory:
            flags.extend(sorted(self._advisory))
        pose = sigma = margin = None
        if outcome is not None and outcome.pose is not None and outcome.uncertainty is not None:
            u = outcome.uncertainty
            pose = pose_record(outcome.pose)
            if math.isfinite(u.translation) and math.isfinite(u.rotation):
                sigma = {"translation_mm": u.translation * 1e3, "rotation_deg": math.degrees(u.rotation)}
                margin = u.margin
            elif status == "ok":
                status = "flagged"
                flags.append("near_singular")
        old = t - self.cfg.staleness
        fresh = [None if v != v or self._t[k] < old else v for k, v in enumerate(self._readings)]  # v != v: NaN
        locked = self.lock.state == "locked"
        record = {
            "fixture": self.cfg.name,
            "t": t,
            "readings": fresh,
            "pose": pose,
            "status": status,
            "flags": flags,
            "iterations": 0 if outcome is None else outcome.iterations,
            "state": self.lock.state,
            "stored": locked and self._stored_episode == self._episode,
            "sigma": sigma,
            "singularity_margin": margin,
            "pose_in_robot": None if pose is None or self._in_robot is None else self._in_robot.record(outcome, sigma),
        }
        self.last = record
        return record


def _quaternion(R: np.ndarray) -> np.ndarray:
    """``qx, qy, qz, qw`` of ``R`` with ``qw >= 0``."""
    return np.array(quaternion(R))
