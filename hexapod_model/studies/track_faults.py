"""Fault injection on Jakobović and Jelenković's trajectory B: what the stream tracker flags, and how fast.

A run takes the true readings of trajectory B (``true_readings``), adds Gaussian noise of
standard deviation ``noise`` (m) and one injected fault, tracks them with a
:class:`~hexapod_model.tracking.tracker.Tracker` told that noise level, and compares every
sample with the true pose (``pose_distance`` with the tracker's length, m):

* a *stream alarm* is a sample with ``jump``, ``stuck``, ``branch_uncertain`` or a late
  ``settling`` (one after the first ``settle_samples``), or a failed solve; on a fault-free
  run every stream alarm is a false alarm (``near_singular``, ``out_of_limits`` and
  ``imprecise`` state properties of the configuration and are counted apart);
* a sample is *good* when it is ``ok`` with no flag; its error is compared both with the
  noise and with its own 1-sigma uncertainty ``hypot(sigma_translation, length * sigma_rotation)``.

Faults: ``("stuck", leg, start, samples)`` holds a reading at its last value;
``("spike", leg, at, size)`` adds ``size`` (m) to one sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analysis.trajectories import trajectory_poses
from ..exceptions import InputError
from ..kinematics.hexapod import Hexapod
from ..tracking.tracker import Tracker, TrackResult, characteristic_length, pose_distance
from .track import true_readings

STREAM_FLAGS = ("jump", "stuck", "branch_uncertain")


def inject(readings: np.ndarray, fault: tuple | None) -> np.ndarray:
    """A copy of the (n, 6) ``readings`` with ``fault`` applied (see module doc)."""
    out = np.array(readings, dtype=float)
    if fault is None:
        return out
    kind, leg, start, value = fault
    if kind == "stuck":
        out[start : start + value, leg] = out[start - 1, leg]
    elif kind == "spike":
        out[start, leg] += value
    else:
        raise InputError("fault", kind, "choose 'stuck' or 'spike'")
    return out


@dataclass(frozen=True)
class FaultRun:
    """Per-sample outcome of one run (arrays of length n).

    Attributes:
        error: pose error against the truth (m, rotations x length).
        sigma: 1-sigma pose uncertainty the tracker stated (m; ``nan`` without a pose).
        good: sample ``ok`` with no flag. alarm: stream alarm (see module doc).
        stuck: sample flagged ``stuck``. flags: the samples' flags.
    """

    error: np.ndarray
    sigma: np.ndarray
    good: np.ndarray
    alarm: np.ndarray
    stuck: np.ndarray
    flags: tuple
    noise: float

    def first(self, mask: np.ndarray, start: int) -> int | None:
        """Samples from ``start`` to the first ``mask`` sample, counting it (1 = at ``start``)."""
        hits = np.flatnonzero(mask[start:])
        return int(hits[0]) + 1 if hits.size else None

    def clean_again(self, start: int) -> int | None:
        """Samples from ``start`` until every later sample is free of stream alarms (1 = at once)."""
        bad = np.flatnonzero(self.alarm[start:])
        return int(bad[-1]) + 2 if bad.size else 1

    @property
    def wrong(self) -> np.ndarray:
        """Samples whose pose is off by more than 10 noise and 5 of their own sigmas (or failed)."""
        with np.errstate(invalid="ignore"):
            return (self.error > 10.0 * self.noise) & ~(self.error <= 5.0 * self.sigma)

    @property
    def false_alarm(self) -> np.ndarray:
        """Stream alarms on samples whose pose is right (failed solves excluded)."""
        return self.alarm & ~self.wrong & np.isfinite(self.sigma)

    def worst_good(self) -> tuple[float, float]:
        """Largest error of a good sample in units of the noise and of its own sigma."""
        g = self.good & np.isfinite(self.sigma)
        if not g.any():
            return 0.0, 0.0
        return float(np.max(self.error[g]) / self.noise), float(np.max(self.error[g] / self.sigma[g]))


def run_faults(
    hexa: Hexapod,
    speed: float,
    noise: float,
    fault: tuple | None = None,
    predictor: str = "eq22",
    seed: int = 0,
    readings: tuple | None = None,
    **options,
) -> FaultRun:
    """Track trajectory B at ``speed`` with noise and ``fault``; see :class:`FaultRun`."""
    length = characteristic_length(hexa)
    _, poses = trajectory_poses("B", hexa.home_pose, length / 50.0, 1000.0, speed)
    lengths = (readings or true_readings(hexa, poses))[0]
    rng = np.random.default_rng(seed)
    noisy = inject(lengths + rng.normal(0.0, noise, lengths.shape), fault)
    tracker = Tracker(
        hexa, predictor, initial=hexa.inverse(poses[0], check=False), length=length, noise=noise, **options
    )
    res = [tracker.step(x) for x in noisy]
    settle = tracker.settings.settle_samples
    return FaultRun(
        np.array([pose_distance(T, r.pose, length) for T, r in zip(poses, res)]),
        np.array([np.hypot(r.sigma_translation, length * r.sigma_rotation) for r in res]),
        np.array([r.ok for r in res]),
        np.array([_alarm(r, k, settle) for k, r in enumerate(res)]),
        np.array(["stuck" in r.flags for r in res]),
        tuple(r.flags for r in res),
        noise,
    )


def _alarm(r: TrackResult, k: int, settle: int) -> bool:
    return r.failed or any(f in r.flags for f in STREAM_FLAGS) or ("settling" in r.flags and k >= settle)
