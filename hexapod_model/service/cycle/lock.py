"""A fixture's lock state judged from the readings alone: locked / moving / drift.

* :class:`LockDetector`: the brakes (Bem, Ude, Nemec 2026, §2) hold the plate still, so readings
  that stay within ``band`` (m) of where a steady run started for ``lock_time`` (s) mean
  ``locked``. The lock reference is the mean of that run. While locked, ``unlock_samples``
  consecutive samples farther than ``band`` from the reference mean ``moving`` again (one
  spike does not unlock); an exponential average of the readings (time constant ``lock_time``)
  farther than ``drift_limit`` from the reference is a ``drift`` alarm (the plate creeps while
  the brakes are on).

Stuck legs: :mod:`~hexapod_model.service.cycle.stuck`; steps: :mod:`~hexapod_model.tracking.steps`.
"""

from __future__ import annotations

import math

import numpy as np

MOTION_LEGS = 3  # legs leaving the band together: the plate moves (fewer: a leg moved alone, an alarm)


class LockDetector:
    """Locked / moving / drift of one fixture from its reading sets.

    The per-set arithmetic is on Python floats (six of them: faster than NumPy calls on
    6-vectors, and the same IEEE operations, so the same results); :attr:`reference` and
    :attr:`run_mean` are arrays.

    Args:
        lock_time: seconds of steady readings before ``locked`` (also the drift average's
            time constant).
        band: steady band (m).
        drift_limit: drift alarm threshold (m), below ``band``.
        unlock_samples: consecutive samples outside the band that unlock.
    """

    def __init__(self, lock_time: float, band: float, drift_limit: float, unlock_samples: int):
        self.lock_time, self.band, self.drift_limit, self.unlock_samples = lock_time, band, drift_limit, unlock_samples
        self.state = "moving"
        self.reference: np.ndarray | None = None  # mean readings of the locking run (m)
        self.drift = False
        self.drift_legs: tuple[int, ...] = ()  # legs whose average is beyond drift_limit
        self.moved: tuple[int, ...] = ()  # one or two legs out of the band while the others stay
        self.slipped: tuple[int, ...] = ()  # moved for 2 x unlock_samples sets: the caller latches it
        self._alone = 0
        self._ref: list[float] = []  # the reference as floats
        self._run_start: tuple[float, list[float]] | None = None
        self._sum = [0.0] * 6
        self._n = 0
        self._outside = 0
        self._ema = [0.0] * 6
        self._t_last = 0.0

    def _restart(self, t: float, readings: list[float]) -> None:
        self._run_start = (t, readings)
        self._sum = readings.copy()
        self._n = 1

    def update(self, t: float, readings) -> bool:
        """Add a set of six readings (m) at time ``t`` (s); True when a moving fixture has been steady long enough.

        The caller then calls :meth:`lock` (with the reference it accepted) or :meth:`restart`.
        """
        x = [float(v) for v in readings]
        if self.state == "locked":
            ref = self._ref
            if _beyond(x, ref, self.band):
                self._outside += 1
                if self._outside >= self.unlock_samples:
                    out = _legs_beyond(x, ref, self.band)
                    if len(out) >= MOTION_LEGS:
                        self.state, self.reference, self.drift, self._outside = "moving", None, False, 0
                        self.drift_legs, self.moved, self._alone = (), (), 0
                        self._restart(t, x)
                    else:
                        self.moved, self._alone = out, self._alone + 1
                        if self._alone >= 2 * self.unlock_samples:
                            self.slipped = out
                return False
            self._outside, self.moved, self._alone = 0, (), 0
            alpha = 1.0 - math.exp(-max(t - self._t_last, 0.0) / max(self.lock_time, 1e-9))
            ema = self._ema
            for k in range(6):  # ema += alpha (readings - ema)
                ema[k] += alpha * (x[k] - ema[k])
            self._t_last = t
            self.drift = _beyond(ema, ref, self.drift_limit)
            self.drift_legs = _legs_beyond(ema, ref, self.drift_limit) if self.drift else ()
            return False
        if self._run_start is None or _beyond(x, self._run_start[1], self.band):
            self._restart(t, x)
        else:
            total = self._sum
            for k in range(6):
                total[k] += x[k]
            self._n += 1
        return t - self._run_start[0] >= self.lock_time  # type: ignore[index]

    @property
    def run_mean(self) -> np.ndarray:
        """Mean readings (m) of the current steady run."""
        return np.array(self._sum) / max(self._n, 1)

    def lock(self, t: float, reference: np.ndarray) -> None:
        """Enter ``locked`` with ``reference`` readings (m) at time ``t`` (s)."""
        self.state, self.reference, self.drift, self._outside = "locked", np.array(reference, dtype=float), False, 0
        self.drift_legs, self.moved, self.slipped, self._alone = (), (), (), 0
        self._ref = self.reference.tolist()
        self._ema = self._ref.copy()
        self._t_last = t

    def restart(self, t: float, readings) -> None:
        """Start a new steady run at this set (a lock could not be taken)."""
        self._restart(t, [float(v) for v in readings])

    def restart_clock(self, t: float) -> None:
        """The clock was set back to ``t`` (s): a steady run restarts, a lock's average goes on from ``t``."""
        self._t_last = min(self._t_last, t)
        if self._run_start is not None:
            self._restart(t, self._run_start[1])

    def release(self, t: float, readings) -> None:
        """Leave ``locked`` (an acknowledged alarm): a new lock is taken from the readings as they are now."""
        self.state, self.reference, self.drift, self._outside = "moving", None, False, 0
        self.drift_legs, self.moved, self.slipped, self._alone = (), (), (), 0
        self._restart(t, [float(v) for v in readings])


def _beyond(a: list[float], b: list[float], limit: float) -> bool:
    """``max |a - b| > limit`` as NumPy's ``abs(a - b).max() > limit`` decides it (False when a difference is NaN)."""
    worst = 0.0
    for u, v in zip(a, b):
        d = abs(u - v)
        if d != d:  # NaN: NumPy's maximum is NaN, and NaN > limit is False
            return False
        if d > worst:
            worst = d
    return worst > limit


def _legs_beyond(a: list[float], b: list[float], limit: float) -> tuple[int, ...]:
    """Legs (0-based) with ``|a - b| > limit``."""
    return tuple(k for k, (u, v) in enumerate(zip(a, b)) if abs(u - v) > limit)
