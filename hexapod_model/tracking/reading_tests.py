"""The stream tracker's statistics: its settings, the motion model and the per-leg reading tests.

Measurement model: each reading is the true leg value plus independent Gaussian noise of
standard deviation ``noise`` (m; default the encoder accuracy, 10 um). Over a few
milliseconds a leg moves like a quadratic in time, so the *motion model* predicts the next
readings by a least-squares quadratic through the last ``n`` *trusted* samples (3 <= n <=
``window``), extrapolated ``m`` samples ahead (``m - 1`` untrusted samples in between). The
prediction ``l^ = sum_j w_j l_j`` is linear in the readings, so its innovation
``nu = l - l^`` has standard deviation ``noise * spread`` with ``spread = sqrt(1 + sum w_j^2)``
(2.05 for ``n = 6, m = 1``); the model's own error (the third derivative of the motion) is
not in ``spread``: on trajectory B at 8x it is below 6 um (0.5 ``noise``).

Per leg, ``z = |nu| / (noise * spread)``:

* ``jump``: ``z > jump_sigmas`` (default 5: 6e-7 per leg and sample under the model);
* ``stuck``: the reading has not changed (by more than ``stuck_tolerance``, default 0: a
  frozen value) while the motion implies it must move: its own prediction moved by more than
  ``stuck_sigmas`` (default 3), or, after ``stuck_samples`` (default 3) unchanged samples,
  another leg moved by more than ``stuck_sigmas * sqrt(2) * noise`` meanwhile, or moves at a
  rate (least-squares slope over the readings kept, ``stuck_samples + 8``) of more than
  ``stuck_motion_sigmas`` (default 5) of its standard deviation: at 50 um noise and 1x a slow
  leg needs 5-6 samples to move by ``3 sqrt(2)`` noise, its slope is significant at once. A working
  encoder with counts (``resolution``) repeats its value with probability ``p_repeat`` per
  sample (about resolution / (2 sqrt(pi) noise)): with counts every rule needs a frozen run
  of ``frozen_run`` samples, one a working encoder shows with probability below 1e-9
  (:mod:`.false_alarms`, which also states each flag's false-alarm rate per hour). The flag
  stays while the reading stays unchanged.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, fields

import numpy as np

from ..exceptions import InputError
from .false_alarms import reading_sigma, stuck_run

DEFAULT_READING_NOISE = 10e-6  # m, the order of the LinACE encoder accuracy (Bem et al. (2026) §2)


@dataclass(frozen=True)
class TrackerSettings:
    """What the tracker assumes and when it flags; every length in metres.

    Attributes:
        noise: standard deviation of the Gaussian reading noise (m).
        jump_sigmas: a reading farther than this many innovation sigmas from the motion
            model's prediction is a ``jump``.
        stuck_samples: unchanged readings before the other legs' motion can raise ``stuck``.
        stuck_sigmas: how clearly the motion must imply that a frozen leg moves.
        stuck_tolerance: largest change (m) that counts as "unchanged" (0: identical value).
        stuck_motion_sigmas: how significant another leg's rate of motion must be for a
            reading unchanged ``stuck_samples`` times to be ``stuck``.
        window: trusted samples in the least-squares quadratic (>= 3).
        max_gap: untrusted samples the motion model may bridge; after more, the history is
            reset and the tracker re-anchors (see :class:`~hexapod_model.tracking.tracker.Tracker`).
        settle_samples: trusted samples after a reset before the checks run again (>= 3:
            the quadratic needs three); those samples are flagged ``settling``.
        branch_sigmas: the solved pose may differ from the motion model's pose plus the
            reading innovation mapped through ``J^-1`` by this many propagated pose sigmas
            (plus ``1e-9 * length``) before ``branch_uncertain``.
        cond_factor: ``near_singular`` when the condition number of the eliminated Jacobian
            exceeds ``cond_factor`` x its home value (or ``cond_limit`` when given).
        cond_limit: absolute ``near_singular`` bound (default from ``cond_factor``).
        max_sigma_factor: ``imprecise`` when the 1-sigma pose uncertainty
            ``hypot(sigma_translation, length * sigma_rotation)`` exceeds this many ``noise``
            (the Jacobian amplifies the reading noise; ``None``: never).
        branch_alpha: significance at which an assembly is rejected after a passage near a
            singularity (:mod:`~hexapod_model.tracking.branches`).
        resolve_samples: samples after such a passage within which one assembly must be
            singled out; after them ``branch_uncertain`` stays until ``reset``.
        continuation_step: largest reading change (m) per Newton solve when re-anchoring.
        recover: re-solve from the motion model when a pose fails the branch check;
            ``False`` keeps the Jakobović and Jelenković (2002) experiment's raw behaviour (a failed branch check
            latches ``branch_uncertain`` until ``reset``).
        resolution: the encoder's count (m; 0: continuous readings). Counts add
            ``resolution / sqrt(12)`` to the reading spread and make a working leg repeat its
            value: ``stuck`` then needs a longer frozen run (:mod:`.false_alarms`).
        motion_error: the motion model's own prediction error (m, speed-dependent), added in
            quadrature to the innovation spread of ``jump``.
    """

    noise: float = DEFAULT_READING_NOISE
    jump_sigmas: float = 5.0
    stuck_samples: int = 3
    stuck_sigmas: float = 3.0
    stuck_tolerance: float = 0.0
    stuck_motion_sigmas: float = 5.0
    window: int = 6
    max_gap: int = 3
    settle_samples: int = 3
    branch_sigmas: float = 3.0
    cond_factor: float = 100.0
    cond_limit: float | None = None
    max_sigma_factor: float | None = 10.0
    branch_alpha: float = 1e-6
    resolve_samples: int = 200
    continuation_step: float = 2e-3
    recover: bool = True
    resolution: float = 0.0
    motion_error: float = 0.0

    def __post_init__(self) -> None:
        positive = (
            "noise",
            "jump_sigmas",
            "stuck_sigmas",
            "stuck_motion_sigmas",
            "branch_sigmas",
            "cond_factor",
            "continuation_step",
        )
        for name in positive:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v > 0):
                raise InputError(name, v, "expected a finite number > 0")
        for name in ("cond_limit", "max_sigma_factor"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0):
                raise InputError(name, v, "expected a number > 0 or None")
        for name in ("stuck_tolerance", "resolution", "motion_error"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v >= 0):
                raise InputError(name, v, "expected a finite number >= 0")
        v = self.branch_alpha
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < 1:
            raise InputError("branch_alpha", v, "expected a number in (0, 1)")
        limits = (("stuck_samples", 1), ("window", 3), ("max_gap", 0), ("settle_samples", 3), ("resolve_samples", 3))
        for name, lo in limits:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                raise InputError(name, v, f"expected an integer >= {lo}")
        if self.settle_samples > self.window:
            raise InputError("settle_samples", self.settle_samples, f"cannot exceed window ({self.window})")
        if not isinstance(self.recover, bool):
            raise InputError("recover", self.recover, "expected True or False")

    @functools.cached_property
    def reading_sigma(self) -> float:
        """Standard deviation of a reading (m): ``noise`` and the count's rounding (:mod:`.false_alarms`)."""
        return reading_sigma(self.noise, self.resolution)

    def innovation_sigma(self, spread: float) -> float:
        """Standard deviation (m) of a reading's innovation for the motion model's ``spread``."""
        sigma = self.reading_sigma * spread
        return sigma if self.motion_error == 0.0 else math.hypot(sigma, self.motion_error)

    @functools.cached_property
    def frozen_run(self) -> int:
        """Unchanged samples before ``stuck`` (:func:`.false_alarms.stuck_run`; ``stuck_samples`` without counts)."""
        if self.resolution == 0.0:
            return self.stuck_samples
        return stuck_run(self.noise, self.resolution, self.stuck_samples)

    @classmethod
    def with_options(cls, base: TrackerSettings | None, options: dict) -> TrackerSettings:
        """``base`` (default settings) with the keyword ``options`` replaced.

        Unknown names are an :class:`InputError`.
        """
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(options) - known)
        if unknown:
            raise InputError("tracker option", unknown[0], f"choose from {sorted(known)}")
        values = {f.name: getattr(base, f.name) for f in fields(cls)} if base is not None else {}
        values.update(options)
        return cls(**values)


class MotionModel:
    """Least-squares quadratic extrapolation weights and innovation spreads.

    ``weights(ages)`` are the weights of the trusted samples (newest first) taken ``ages``
    samples before the current one (``(1, 2, 3, ...)`` without a gap; untrusted samples
    leave holes); they sum to 1, so they also act on configurations in the tangent space
    at the newest one (``X = P0 (+) sum_j w_j (P_j (-) P0)``). Cached per pattern of ages.
    """

    def __init__(self) -> None:
        self._cache: dict[tuple[int, ...], tuple[np.ndarray, float]] = {}

    def weights(self, ages: tuple[int, ...]) -> tuple[np.ndarray, float]:
        """``(w, spread)`` for trusted samples of the given ages (>= 3 of them, all distinct)."""
        hit = self._cache.get(ages)
        if hit is None:
            t = -np.asarray(ages, dtype=float)
            # the fit's value at t = 0, a contiguous row of its own: the tracker's compiled sample statistics
            # (.kernels.begin_sample) are called with the types of their first call
            w = np.array(np.linalg.pinv(np.vander(t, 3, increasing=True))[0], dtype=np.float64, order="C")
            hit = self._cache[ages] = (w, float(np.sqrt(1.0 + w @ w)))
        return hit


def motion_sigmas(raw: np.ndarray, noise: float) -> np.ndarray:
    """Per leg: the largest ``|slope| / sd(slope)`` of the *other* legs' readings ``raw`` (n, 6).

    The slope is the least-squares rate over the ``n`` readings (oldest first), its standard
    deviation ``noise / sqrt(sum (t - mean t)^2)`` under the noise model; 0 with fewer than 3.
    """
    n = raw.shape[0]
    if n < 3:
        return np.zeros(6)
    t = np.arange(n) - (n - 1) / 2.0
    z = np.abs(t @ raw) / (noise * math.sqrt(float(t @ t)))
    return np.array([np.max(np.delete(z, i)) for i in range(6)])


def stuck_legs(
    frozen: np.ndarray, z: np.ndarray, moved: np.ndarray, settings: TrackerSettings, moving: np.ndarray | None = None
) -> np.ndarray:
    """Boolean (6,): frozen legs that the motion implies move.

    The tracker runs this test compiled, with its inputs, in one call
    (:func:`~hexapod_model.tracking.kernels.stuck_checks`); a test holds the kernel to this one.

    A leg is stuck when its reading is unchanged while its own prediction moves by more than
    ``stuck_sigmas`` innovation sigmas, or when it has been unchanged for ``stuck_samples``
    while another leg moved by more than ``stuck_sigmas * sqrt(2) * noise``.

    Args:
        frozen: consecutive samples each leg's reading has stayed unchanged.
        z: normalised innovations (``nan`` when the motion model is not available).
        moved: largest change of the *other* legs' readings over each leg's frozen run (m).
        settings: the tracker's settings.
        moving: :func:`motion_sigmas` of the readings kept (``None``: not used).
    """
    counts = settings.resolution > 0.0  # a working encoder repeats counts: only an improbable run counts
    run = settings.frozen_run
    predicted = (frozen >= (run if counts else 1)) & (np.nan_to_num(z, nan=0.0) > settings.stuck_sigmas)
    evidence = moved > settings.stuck_sigmas * math.sqrt(2.0) * settings.reading_sigma
    if moving is not None:
        evidence |= moving > settings.stuck_motion_sigmas
    others = (frozen >= run) & evidence
    return predicted | others
