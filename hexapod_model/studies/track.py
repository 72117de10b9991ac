"""``hexapod track``: Jakobović and Jelenković's 1 kHz tracking experiment (trajectories A/B, predictors, speeds).

True poses follow trajectory A or B (Jakobović and Jelenković (2002) eqs. 20-21; positions scaled by
``base radius / 50`` m per paper unit, as :mod:`hexapod_model.studies.bench`), leg readings come from
the model's inverse kinematics (offset-Cardan model for the ``reference`` preset), and the
:class:`~hexapod_model.tracking.Tracker` solves them at 1 kHz. Errors are absolute differences
of the roll/pitch/yaw angles (deg) and of x, y, z (m) between solved and true poses; the
figures show their worst value over each 100 ms window (Jakobović and Jelenković (2002) Figs. 7-10).

A sample is *off the true branch* when its pose error exceeds ``1e-5`` (m with rotations
scaled by the base radius); a *branch jump* is a transition onto a wrong branch.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..analysis.trajectories import trajectory_poses
from ..exceptions import InputError
from ..io.tables import POSE_COLUMNS, pose_row
from ..kinematics.hexapod import Hexapod
from ..lie import matrix_to_rpy
from ..tracking.steps import StepDetector
from ..tracking.tracker import PREDICTORS, Tracker, characteristic_length, pose_distance

SPEEDS = (1, 2, 4, 8)
OFF_BRANCH = 1e-5
WINDOW_S = 0.1


@dataclass(frozen=True)
class TrackingRun:
    """One simulated run. Arrays have one row per 1 kHz sample.

    Attributes:
        t: times (s). errors: (n, 6) |d roll|, |d pitch|, |d yaw| (deg), |dx|, |dy|, |dz| (m).
        distance: (n,) pose error (m, rotations x base radius). off_branch: (n,) bool.
        status: (n,) ``ok`` (no flag), ``flagged`` (a pose with flags) or ``failed`` (no pose).
        flags: counts per flag.
        truth_status: counts of the inverse-kinematics statuses of the true poses.
    """

    trajectory: str
    predictor: str
    speed: float
    t: np.ndarray
    errors: np.ndarray
    distance: np.ndarray
    off_branch: np.ndarray
    status: np.ndarray
    solve_times: np.ndarray
    flags: dict = field(default_factory=dict)
    truth_status: dict = field(default_factory=dict)

    @property
    def branch_jumps(self) -> int:
        """Transitions from the true branch onto another one."""
        ob = self.off_branch.astype(int)
        return int(np.sum(np.diff(np.r_[0, ob]) == 1))

    @property
    def unflagged_off_branch(self) -> int:
        """Samples off the true branch that the tracker returned as ``ok`` (should be 0)."""
        return int(np.sum(self.off_branch & (self.status == "ok")))

    def summary(self) -> dict:
        """The run's figures as a JSON-ready dict."""
        return {
            "trajectory": self.trajectory,
            "predictor": self.predictor,
            "speed": self.speed,
            "samples": int(self.t.size),
            "max_angle_error_deg": float(self.errors[:, :3].max()),
            "max_position_error_m": float(self.errors[:, 3:].max()),
            "branch_jumps": self.branch_jumps,
            "off_branch_samples": int(self.off_branch.sum()),
            "unflagged_off_branch": self.unflagged_off_branch,
            "flagged": int(np.sum(self.status == "flagged")),
            "failed": int(np.sum(self.status == "failed")),
            "flags": self.flags,
            "truth_ik_status": self.truth_status,
            "median_solve_us": float(np.median(self.solve_times) * 1e6),
        }

    def window_max(self) -> tuple[np.ndarray, np.ndarray]:
        """Window end times and (m, 6) worst errors per 100 ms window."""
        n = max(1, int(round(WINDOW_S / (self.t[1] - self.t[0])))) if self.t.size > 1 else 1
        k = int(np.ceil(self.t.size / n))
        out = np.array([self.errors[i * n : (i + 1) * n].max(axis=0) for i in range(k)])
        ends = np.array([self.t[min((i + 1) * n, self.t.size) - 1] for i in range(k)])
        return ends, out


def true_readings(hexa: Hexapod, poses: np.ndarray) -> tuple[np.ndarray, dict]:
    """Readings of the true poses.

    Readings (n, m) of the true poses by warm-started inverse kinematics (``check=False``),
    with the redundant sensors' readings of a hexapod that has them (``m`` its
    ``reading_names``), and the count of each IK status (``out_of_limits`` = a Cardan angle or
    the stroke exceeded).
    """
    extra = hexa.redundancy
    sol, out = None, np.empty((len(poses), len(hexa.reading_names)))
    counts: dict[str, int] = {}
    for k, T in enumerate(poses):
        sol = hexa.inverse(T, guess=sol, check=False)
        counts[sol.status] = counts.get(sol.status, 0) + 1
        out[k, :6] = sol.lengths
        if extra is not None:
            out[k, 6:] = extra.extra_readings(T)
    return out, counts


def simulate(
    hexa: Hexapod,
    trajectory: str = "A",
    speed: float = 1.0,
    predictor: str = "none",
    rate_hz: float = 1000.0,
    readings=None,
    **tracker_options,
) -> TrackingRun:
    """Run the Jakobović and Jelenković (2002) experiment once (see module doc)."""
    length = characteristic_length(hexa)
    t, poses = trajectory_poses(trajectory, hexa.home_pose, length / 50.0, rate_hz, speed)
    if readings is None:
        readings = true_readings(hexa, poses)
    lengths, truth_status = readings
    first = hexa.inverse(poses[0], check=False)
    tracker_options.setdefault("recover", False)  # the paper's tracker: the predictor alone decides
    tracker = Tracker(hexa, predictor, initial=first, length=length, **tracker_options)
    n = len(t)
    errors, dist = np.zeros((n, 6)), np.zeros(n)
    status, times = np.empty(n, dtype=object), np.zeros(n)
    flags: dict[str, int] = {}
    for k in range(n):
        res = tracker.step(lengths[k])
        T = res.pose
        d = np.abs(matrix_to_rpy(T[:3, :3]) - matrix_to_rpy(poses[k][:3, :3]))
        errors[k, :3] = np.degrees(np.minimum(d, 2 * np.pi - d))
        errors[k, 3:] = np.abs(T[:3, 3] - poses[k][:3, 3])
        dist[k] = pose_distance(poses[k], T, length)
        status[k] = "ok" if res.ok else ("failed" if res.failed else "flagged")
        times[k] = res.solve_time
        for f in res.flags:
            flags[f] = flags.get(f, 0) + 1
    return TrackingRun(
        trajectory,
        predictor,
        float(speed),
        t,
        errors,
        dist,
        dist > OFF_BRANCH * max(length, 1.0),
        status.astype(str),
        times,
        flags,
        truth_status,
    )


def run_table(
    hexa: Hexapod, trajectories=("A", "B"), predictors=PREDICTORS, speeds=SPEEDS, progress=None
) -> list[dict]:
    """Trajectory x predictor x speed -> summary dicts (readings computed once per trajectory/speed)."""
    rows = []
    combos = [(tr, sp) for tr in trajectories for sp in speeds]
    for tr, sp in progress(combos, len(combos), "track") if progress else combos:
        length = characteristic_length(hexa)
        _, poses = trajectory_poses(tr, hexa.home_pose, length / 50.0, 1000.0, sp)
        readings = true_readings(hexa, poses)
        for pr in predictors:
            rows.append(simulate(hexa, tr, sp, pr, readings=readings).summary())
    return rows


TRACK_LOG_COLUMNS = ["t", *POSE_COLUMNS, "status", "flags", "iterations"]


def track_log(
    hexa: Hexapod, times: np.ndarray, readings: np.ndarray, predictor: str = "eq22", progress=None, **options
) -> tuple[list[list], dict]:
    """Track a recorded stream: rows of :data:`TRACK_LOG_COLUMNS` and counts per flag/status.

    ``times`` (s) must increase strictly (the checks assume one sample per period); a row of
    readings with NaN (an unreadable cell) is that sample's ``invalid_input``. A failed
    sample's pose cells are NaN (written empty), never the previous pose. As in the fixture
    service, a jump the tracker flags is checked for a step (:class:`~hexapod_model.tracking.steps.StepDetector`:
    a slipped encoder, swapped legs): rows are flagged ``jump`` until it is known, and from a
    step on every row carries ``discontinuity:legN`` (what the service latches until someone
    acknowledges it; an audit has no one to, so it stays to the end).
    """
    times = np.asarray(times, dtype=float)
    names = hexa.reading_names
    if np.shape(readings)[-1] != len(names):
        why = f"expected {len(names)} readings a row ({', '.join(names)}) for this hexapod"
        raise InputError("readings", f"{np.shape(readings)[-1]} columns", why)
    if times.size > 1 and not np.all(np.diff(times) > 0):
        k = int(np.flatnonzero(~(np.diff(times) > 0))[0])
        raise InputError("t", float(times[k + 1]), f"row {k + 2}: times must increase strictly")
    tracker = Tracker(hexa, predictor, **options)
    steps = StepDetector(tracker.settings.noise)
    latched: list[str] = []  # discontinuity:legN, from the first step found on
    rows: list[list] = []
    counts: dict[str, int] = {}
    items = zip(times, readings)
    for k, (t, lengths) in enumerate(progress(items, len(times), "track") if progress else items):
        r = tracker.step(lengths)
        flags = list(r.flags)
        if not r.failed:  # a failed sample is a gap for the step check, as a failed set in the service
            stepped = steps.update(k, lengths, r.legs if "jump" in r.flags else ())
            if stepped and not latched:
                latched = [f"discontinuity:leg{j + 1}" for j in stepped]
            if steps.pending and "jump" not in flags:
                flags.append("jump")
        flags += latched
        pose = pose_row(r.pose) if not r.failed else [float("nan")] * len(POSE_COLUMNS)
        rows.append([float(t), *map(float, pose), r.status, ";".join(flags), r.iterations])
        for key in (r.status,) if r.failed else flags:
            counts[key] = counts.get(key, 0) + 1
    return rows, counts
