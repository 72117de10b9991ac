"""Per-fixture state judged from the readings alone: locked / moving / drift, and stuck legs.

* :class:`LockDetector`: the brakes (Bem, Ude, Nemec 2026, §2) hold the plate still, so readings
  that stay within ``band`` (m) of where a steady run started for ``lock_time`` (s) mean
  ``locked``. The lock reference is the mean of that run. While locked, ``unlock_samples``
  consecutive samples farther than ``band`` from the reference mean ``moving`` again (one
  spike does not unlock); an exponential average of the readings (time constant ``lock_time``)
  farther than ``drift_limit`` from the reference is a ``drift`` alarm (the plate creeps while
  the brakes are on).
* :class:`StuckDetector`: an encoder repeating exactly the same count while its own recent
  velocity predicts a change of more than ``sigmas`` times the noise is ``stuck``.
"""

from __future__ import annotations

import math

import numpy as np

GAP_INSTANTS = 3  # sampling instants without a set after which a leg's speed estimate restarts
STEP_SIGMAS = 5.0  # a step estimate beyond this many of its sigmas is a step (StepDetector)
REPEATS = 3  # a count repeated this many sets after it first came can be stuck (fewer happen as a leg stops)
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


class StuckDetector:
    """Legs whose count stays exactly the same although their own recent motion says it should change.

    A moving leg's count changes every set (its noise alone makes an exact repeat unlikely), so a
    repeat is suspicious in proportion to the change the leg's recent velocity predicts: after a
    repeat lasting ``n`` frame periods at an estimated ``v`` (m per period), the leg is ``stuck``
    when ``|v| n > sigmas * max(noise, resolution)``. The velocity is an exponential average
    (``alpha`` per instant) of the leg's rate of change, frozen while the count repeats, and
    forgotten after a gap of more than ``GAP_INSTANTS`` sampling instants. With the
    default 8 sigma a stuck leg goes unnoticed while it would have moved about 8 sigma (about 3
    sigma of the pose) when its speed is well known; a leg moving by about the noise per set has
    a noisy speed estimate and may take a few sets more. A still fixture (a locked plate) cannot
    reveal a stuck encoder, and needs not: its readings do not change.

    Args:
        sigmas: threshold in noise units; 0 disables the check.
        noise: 1-sigma reading noise (m).
        resolution: metres per count.
    """

    def __init__(self, sigmas: float, noise: float, resolution: float, alpha: float = 0.3):
        self.limit = sigmas * max(noise, abs(resolution))
        self.alpha = alpha
        self._counts: list[int] | None = None
        self._since = [0] * 6  # sampling instant the current count was first seen
        self._value = [0.0] * 6  # its reading (m)
        self._v = [0.0] * 6  # m per instant

    def update(self, instant: int, counts: list[int], readings) -> list[int]:
        """Add a set: its sampling instant (frame periods since the start), raw counts and readings (m).

        Returns the stuck legs (0-based). Counting in sampling instants rather than in seconds keeps
        the speed estimate right when frames arrive bunched (USB adapters, a busy host).
        """
        if self.limit == 0.0:
            return []
        stuck = []
        prev, since, value, v = self._counts, self._since, self._value, self._v
        for k in range(6):
            if prev is not None and counts[k] == prev[k]:
                n = instant - since[k]
                # a leg slowing down to a stop repeats its count naturally for a set or two while
                # the average still says it moves: REPEATS sets
                if n >= REPEATS and abs(v[k]) * n > self.limit:
                    stuck.append(k)
                continue
            n = instant - since[k]
            if prev is not None and 0 < n <= GAP_INSTANTS:  # an average over n instants weighs as n sets
                v[k] += (1.0 - (1.0 - self.alpha) ** n) * ((float(readings[k]) - value[k]) / n - v[k])
            elif n > GAP_INSTANTS:  # the speed before a long gap says nothing about now
                v[k] = 0.0
            since[k], value[k] = instant, float(readings[k])
        self._counts = list(counts)
        return stuck


class StepDetector:
    """Legs whose reading jumped and stayed there: a step (slipped encoder, swapped legs), not a spike.

    The tracker flags a reading far from its motion model (``jump``) but, for a small step, may
    take the new level as motion from the next set on. So when it flags a jump at a sampling
    instant, each named leg's readings around it, ``before`` instants before and ``after``
    after, are fitted twice: a cubic in time plus a *step* from that instant on, and a cubic plus
    a *spike* at it. A leg is stepped when the step model fits better, its step exceeds
    :data:`STEP_SIGMAS` of its own uncertainty (the reading noise through the fit) and a quarter
    of the largest step found. Until then
    the caller keeps the records off ``ok``. The trend restarts after a gap of more than
    :data:`GAP_INSTANTS` instants. A step below the tracker's jump threshold (about 5 sigma of
    its prediction), one within a gap, and a creep slower than the noise are not seen.

    Args:
        noise: 1-sigma reading noise (m).
        before: readings per leg before the jump in the fit.
        after: readings per leg after the jump's own.
    """

    def __init__(self, noise: float, before: int = 6, after: int = 3):
        self.noise, self.before, self.after = noise, before, after
        self._history: list[tuple[int, list[float]]] = []  # (instant, readings), the last `before` sets
        self._jump: tuple[int, tuple[int, ...]] | None = None  # (instant, legs) being checked
        self._post: list[tuple[int, list[float]]] = []

    @property
    def pending(self) -> bool:
        """Whether a jump is being checked (a step or a spike: not known yet)."""
        return self._jump is not None

    def reset(self) -> None:
        """Forget the readings seen (after a step, or an acknowledgement)."""
        self._history, self._jump, self._post = [], None, []

    def update(self, instant: int, readings, jump_legs: tuple[int, ...]) -> tuple[int, ...]:
        """Add a set (sampling instant, readings in m, legs the tracker flags ``jump``); returns stepped legs."""
        x = [float(v) for v in readings]
        if self._jump is not None and instant - self._post[-1][0] > GAP_INSTANTS:
            self.reset()  # a gap in the check: what happened in it is not known
        if self._jump is not None:
            self._post.append((instant, x))
            if len(self._post) <= self.after:
                return ()
            stepped = self._decide()
            after = self._post[1:]
            self.reset()
            self._history = after  # the readings after the jump: the new level (or the old, after a spike)
            return stepped
        if self._history and instant - self._history[-1][0] > GAP_INSTANTS:
            self._history = []  # a gap (sets lost or failed): the trend restarts
        if jump_legs and len(self._history) >= self.before:
            self._jump, self._post = (instant, tuple(jump_legs)), [(instant, x)]
            return ()
        self._history.append((instant, x))
        if len(self._history) > self.before:
            del self._history[0]
        return ()

    def _decide(self) -> tuple[int, ...]:
        assert self._jump is not None
        k, legs = self._jump
        sets = self._history + self._post
        n = np.array([i for i, _ in sets], dtype=float) - k
        R = np.array([r for _, r in sets])
        base = np.column_stack([np.ones_like(n), n, n**2, n**3])
        fits = {}
        for name, extra in (("step", n >= 0), ("spike", n == 0)):
            V = np.column_stack([base, extra.astype(float)])
            coef, *_ = np.linalg.lstsq(V, R, rcond=None)
            rss = ((R - V @ coef) ** 2).sum(axis=0)
            sd = self.noise * math.sqrt(float(np.linalg.inv(V.T @ V)[4, 4]))
            fits[name] = (coef[4], rss, sd)
        step, rss_step, sd = fits["step"]
        rss_spike = fits["spike"][1]
        found = [j for j in legs if abs(step[j]) > STEP_SIGMAS * sd and rss_step[j] < rss_spike[j]]
        largest = max((abs(step[j]) for j in found), default=0.0)
        return tuple(j for j in found if abs(step[j]) >= largest / 4)  # not a leg the largest step dragged along
