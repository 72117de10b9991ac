"""K-fold validation of a calibration: pose errors on measured poses the fit has not seen.

The poses are split at random into ``k`` folds. For each fold, the other ``k - 1`` folds are
the training set and the fold is predicted by

* **before**: the nominal geometry, with the measuring and marker frames fitted to the
  training set (a rigid alignment: without it the errors would only show the unknown frames);
* **after**: the geometry and frames identified on the training set.

When the rows carry a redundant hexapod's extra readings, *after* is the fit with them
(:func:`~hexapod_model.calibration.identify.identify` uses them), and the same folds are also
fitted from the six legs alone (``after_without_sensors``): the held-out pose errors of both,
each pose predicted from its six legs' readings by the geometry and frames of its fit, show
what the extra equations give. Every pose is predicted exactly once, so the errors cover the
whole data set.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from ..description.geometry import HexapodGeometry
from ..exceptions import InputError
from .frames import Noise, fit_frames, pose_errors, predict
from .identify import MeasuredPoses, identify, solve_nominal
from .parameters import ParameterSet

Progress = Callable[[Iterable, int, str], Iterable]


def _no_progress(iterable: Iterable, total: int, desc: str) -> Iterable:
    return iterable


@dataclass(frozen=True)
class Validation:
    """Held-out errors of every pose.

    Attributes:
        folds: ``k``.
        fold: (N,) the fold each pose was held out in.
        before, after: (translation mm, rotation deg) errors of each pose, (N,) each.
        after_without_sensors: the same errors after a fit from the six legs alone, when the
            rows carry extra readings (else ``None``).
    """

    folds: int
    fold: np.ndarray
    before: tuple[np.ndarray, np.ndarray]
    after: tuple[np.ndarray, np.ndarray]
    after_without_sensors: tuple[np.ndarray, np.ndarray] | None = None


def folds_of(n: int, k: int, seed: int = 0) -> np.ndarray:
    """(n,) fold index of each pose: a random split into ``k`` folds of (nearly) equal size."""
    if not 2 <= k <= n:
        raise InputError("folds", k, f"need 2 <= folds <= poses ({n})")
    fold = np.empty(n, dtype=int)
    fold[np.random.default_rng(seed).permutation(n)] = np.arange(n) % k
    return fold


def cross_validate(
    nominal: HexapodGeometry,
    data: MeasuredPoses,
    noise: Noise = Noise(),
    folds: int = 5,
    seed: int = 0,
    progress: Progress = _no_progress,
    **identify_options,
) -> Validation:
    """Held-out errors before and after calibration (see the module doc).

    Keywords go to :func:`~hexapod_model.calibration.identify.identify`.

    Raises:
        InputError: as :func:`~hexapod_model.calibration.identify.identify` on a training set
            (too few poses per fold, an outlier), or a held-out row the calibrated model
            cannot solve.
    """
    n = len(data.readings)
    fold = folds_of(n, folds, seed)
    ps = ParameterSet(nominal, identify_options.get("encoder_scale", False))
    _, P, _, _ = solve_nominal(ps, data)
    before = (np.zeros(n), np.zeros(n))
    after = (np.zeros(n), np.zeros(n))
    both = data.extra > 0 and identify_options.get("sensors", True)
    six = (np.zeros(n), np.zeros(n)) if both else None
    for f in progress(range(folds), folds, "k-fold validation"):
        test, train = np.flatnonzero(fold == f), np.flatnonzero(fold != f)
        frames = fit_frames(P[train], data.measured[train], noise)
        err = pose_errors(predict(frames[0], P[test], frames[1]), data.measured[test])
        before[0][test], before[1][test] = err
        fits = [(after, identify_options)]
        if six is not None:
            fits.append((six, identify_options | {"sensors": False}))
        for out, options in fits:
            result = identify(nominal, data.subset(train), noise, **options)
            M, ok = result.predict(data.readings[test])
            if not ok.all():
                k = int(test[np.flatnonzero(~ok)[0]])
                why = "the geometry calibrated on the other folds cannot solve it"
                raise InputError("measured row", data.line(k), why)
            out[0][test], out[1][test] = pose_errors(M, data.measured[test])
    return Validation(folds, fold, before, after, six)


IMPROVEMENT_SIGMAS = 2.0  # standard errors by which the held-out error must drop to call a calibration better


@dataclass(frozen=True)
class Verdict:
    """Whether the calibrated geometry predicts held-out poses better than the nominal one.

    The figure is the mean held-out translation error (mm); its uncertainty the standard error
    of the mean paired difference ``before - after`` over the poses. Better means the mean
    dropped by more than ``IMPROVEMENT_SIGMAS`` standard errors, and the mean rotation error
    (deg) did not rise by more than as many of its own.

    Attributes:
        better: the calibrated geometry is better beyond the uncertainty.
        before_mm, after_mm: mean held-out translation error, nominal and calibrated (mm).
        uncertainty_mm: ``IMPROVEMENT_SIGMAS`` standard errors of their difference (mm).
        before_deg, after_deg: mean held-out rotation error, nominal and calibrated (deg).
        uncertainty_deg: ``IMPROVEMENT_SIGMAS`` standard errors of their difference (deg).
    """

    better: bool
    before_mm: float
    after_mm: float
    uncertainty_mm: float
    before_deg: float
    after_deg: float
    uncertainty_deg: float

    def describe(self) -> str:
        """One line with both figures and the decision."""
        word = "better" if self.better else "not better"
        return (
            f"held-out error {self.before_mm:.4f} mm (nominal) -> {self.after_mm:.4f} mm (calibrated), "
            f"{self.before_deg:.4f} -> {self.after_deg:.4f} deg: {word} beyond the uncertainty "
            f"(+-{self.uncertainty_mm:.4f} mm, +-{self.uncertainty_deg:.4f} deg, "
            f"{IMPROVEMENT_SIGMAS:g} standard errors)"
        )


def verdict(validation: Validation) -> Verdict:
    """The :class:`Verdict` of a k-fold validation."""
    figures = []
    for before, after in zip(validation.before, validation.after):
        d = before - after
        se = float(np.std(d, ddof=1) / np.sqrt(d.size)) if d.size > 1 else float("inf")
        figures.append((float(np.mean(before)), float(np.mean(after)), IMPROVEMENT_SIGMAS * se))
    (b_mm, a_mm, u_mm), (b_deg, a_deg, u_deg) = figures
    better = b_mm - a_mm > u_mm and a_deg - b_deg <= u_deg
    return Verdict(bool(better), b_mm, a_mm, u_mm, b_deg, a_deg, u_deg)
