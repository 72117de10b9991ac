"""Stuck legs: an encoder repeating exactly the same count while its own recent velocity predicts a change.

:class:`StuckDetector`: a leg is ``stuck`` when its count repeats while its recent velocity
predicts a change of more than ``sigmas`` times the reading noise.
"""

from __future__ import annotations

from ...tracking.steps import GAP_INSTANTS  # sampling instants without a set after which a leg's speed restarts

REPEATS = 3  # a count repeated this many sets after it first came can be stuck (fewer happen as a leg stops)


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
        # the average's weight of a change over n instants, 1 - (1 - alpha)^n, for n = 0 .. GAP_INSTANTS
        self._gain = [1.0 - (1.0 - alpha) ** n for n in range(GAP_INSTANTS + 1)]
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
        prev, since, value, v, gain = self._counts, self._since, self._value, self._v, self._gain
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
                v[k] += gain[n] * ((float(readings[k]) - value[k]) / n - v[k])
            elif n > GAP_INSTANTS:  # the speed before a long gap says nothing about now
                v[k] = 0.0
            since[k], value[k] = instant, float(readings[k])
        self._counts = list(counts)
        return stuck
