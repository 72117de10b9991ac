"""A jerk-limited time law of the carry's path parameter, and the plate jerk the tracker tolerates.

The service's tracker (:mod:`hexapod_model.tracking.reading_tests`) predicts each leg reading by
a least-squares quadratic through the last six samples, extrapolated one sample ahead: a motion
of constant jerk ``j`` (m/s^3) leaves a model error of ``C3 j dt^3`` with ``C3 = 4.2``
(:func:`model_error_factor`), and a step of the acceleration is a model error of order
``da dt^2``, which at 50 Hz and 0.5 m/s^2 is about five innovation sigmas: a ``jump``, and a
``discontinuity`` when it lasts. :func:`tracker_jerk_limit` is the jerk whose model error is
``share`` (default one half) of one innovation sigma at a given rate and reading noise;
:data:`DEFAULT_CARRY_JERK` is its value at 50 Hz and 10 um, the slowest and noisiest
plate of the examples (0.30 m/s^3).

:class:`SCurve` is the time-optimal rest-to-rest move of a parameter ``s`` from 0 to 1 under
bounds on its rate, acceleration and jerk: seven phases of constant jerk ``(+J, 0, -J, 0, -J,
0, +J)``, so its acceleration ramps and never steps.
"""

from __future__ import annotations

import math

import numpy as np

from ..exceptions import InputError
from ..tracking.reading_tests import DEFAULT_READING_NOISE, MotionModel

WINDOW = 6  # trusted samples of the tracker's quadratic (TrackerSettings.window's default)


def model_error_factor(window: int = WINDOW) -> tuple[float, float]:
    """``(C3, spread)``: the tracker's model error per ``j dt^3`` of a constant jerk, and its innovation spread."""
    w, spread = MotionModel().weights(tuple(range(1, window + 1)))
    t = -np.arange(1, window + 1, dtype=float)
    return float(abs(w @ t**3) / 6.0), spread


def tracker_jerk_limit(rate: float = 50.0, noise: float = DEFAULT_READING_NOISE, share: float = 0.5) -> float:
    """The jerk (m/s^3) of a leg whose motion-model error is ``share`` innovation sigmas.

    Args:
        rate: reading sets per second (Hz).
        noise: 1-sigma reading noise (m).
        share: the model error allowed, in innovation sigmas ``noise * spread``.
    """
    for name, v in (("rate", rate), ("noise", noise), ("share", share)):
        if not (math.isfinite(v) and v > 0.0):
            raise InputError(name, v, "expected a number above 0")
    c3, spread = model_error_factor()
    return share * noise * spread / (c3 / rate**3)


DEFAULT_CARRY_JERK = round(tracker_jerk_limit(), 2)  # m/s^3: 50 Hz, 10 um, half a sigma


class SCurve:
    """The time-optimal rest-to-rest move of ``s`` from 0 to 1 with ``|sd| <= v``, ``|sdd| <= a``, ``|sddd| <= j``.

    Args:
        v: largest rate (1/s).
        a: largest acceleration (1/s^2).
        j: largest jerk (1/s^3).
    """

    def __init__(self, v: float, a: float, j: float):
        for name, x in (("v", v), ("a", a), ("j", j)):
            if not (math.isfinite(x) and x > 0.0):
                raise InputError(name, x, "expected a number above 0")
        a = min(a, math.sqrt(v * j))  # the acceleration reached before the rate is
        if v * (v / a + a / j) > 1.0:  # the rate is not reached: the largest one that is
            v_a = (-a * a / j + math.sqrt((a * a / j) ** 2 + 4.0 * a)) / 2.0  # with a constant-acceleration phase
            if v_a >= a * a / j:
                v = v_a
            else:
                v = (j / 4.0) ** (1.0 / 3.0)  # jerk phases only: v * 2 sqrt(v / j) = 1
                a = math.sqrt(v * j)
        tj = a / j
        tc = max(v / a - tj, 0.0)
        tv = max((1.0 - v * (v / a + tj)) / v, 0.0)
        self.durations = np.array([tj, tc, tj, tv, tj, tc, tj])
        self.jerks = np.array([j, 0.0, -j, 0.0, -j, 0.0, j])
        self.duration = float(self.durations.sum())
        self.peak_rate, self.peak_acceleration = v, a
        starts = [(0.0, 0.0, 0.0)]  # (s, sd, sdd) at each phase's start
        for d, jj in zip(self.durations, self.jerks):
            starts.append(self._advance(*starts[-1], jj, d))
        self._starts = np.array(starts)
        self._t0 = np.r_[0.0, np.cumsum(self.durations)]

    @staticmethod
    def _advance(s: float, sd: float, sdd: float, j: float, d: float) -> tuple[float, float, float]:
        return s + sd * d + sdd * d * d / 2.0 + j * d**3 / 6.0, sd + sdd * d + j * d * d / 2.0, sdd + j * d

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(s, sd, sdd, sddd)`` at times ``t`` (s; clipped to the move)."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        k = np.clip(np.searchsorted(self._t0, t, side="right") - 1, 0, 6)
        d = t - self._t0[k]
        s0, v0, a0 = self._starts[k].T
        j = self.jerks[k]
        return s0 + v0 * d + a0 * d * d / 2.0 + j * d**3 / 6.0, v0 + a0 * d + j * d * d / 2.0, a0 + j * d, j

    def times(self, s: np.ndarray) -> np.ndarray:
        """The times (s) at which the move passes ``s`` (increasing, in [0, 1]); by bisection to 1e-12 s."""
        s = np.asarray(s, dtype=float)
        lo, hi = np.zeros(s.shape), np.full(s.shape, self.duration)
        while np.any(hi - lo > 1e-12):
            mid = (lo + hi) / 2.0
            below = self(mid)[0] < s
            lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
        t = (lo + hi) / 2.0
        t[s <= 0.0], t[s >= 1.0] = 0.0, self.duration
        return t
