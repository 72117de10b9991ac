"""Steps: legs whose reading jumped and stayed there (a slipped encoder, swapped legs), not a spike.

Used by the fixture service's cycle (which latches them) and by ``hexapod track --readings``
(:func:`~hexapod_model.studies.track.track_log`, which flags every later row).
"""

from __future__ import annotations

import math

import numpy as np

GAP_INSTANTS = 3  # sampling instants without a set after which a leg's trend restarts
STEP_SIGMAS = 5.0  # a step estimate beyond this many of its sigmas is a step (StepDetector)
LOST_SPAN = 2  # instants: a fit window longer than its sets' own span by more (sets lost in it) fits a quintic


class StepDetector:
    """Legs whose reading jumped and stayed there: a step (slipped encoder, swapped legs), not a spike.

    The tracker flags a reading far from its motion model (``jump``) but, for a small step, may
    take the new level as motion from the next set on. So when it flags a jump at a sampling
    instant, each named leg's readings around it, ``before`` instants before and ``after``
    after, are fitted twice: a cubic in time plus a *step* from that instant on, and a cubic plus
    a *spike* at it (a quintic where sets lost in the window stretch it by more than
    :data:`LOST_SPAN` instants: over a longer span a cubic does not follow a plate that speeds up
    or slows down, and the step took up the difference). A leg is stepped when the step model
    fits better, its step exceeds :data:`STEP_SIGMAS` of its own uncertainty (the reading noise
    through the fit, or the scatter of the leg's readings about the step model where that is
    larger) and a quarter of the largest step found. Until then the caller keeps the records off
    ``ok``. The trend restarts after a gap of more than
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
        # a cubic follows the motion over the window's own span; one that lost sets stretched, a quintic
        degree = 3 if n[-1] - n[0] <= self.before + self.after + LOST_SPAN else 5
        base = np.column_stack([n**p for p in range(degree + 1)])
        fits = {}
        for name, extra in (("step", n >= 0), ("spike", n == 0)):
            V = np.column_stack([base, extra.astype(float)])
            coef, *_ = np.linalg.lstsq(V, R, rcond=None)
            rss = ((R - V @ coef) ** 2).sum(axis=0)
            sd = self.noise * math.sqrt(float(np.linalg.inv(V.T @ V)[-1, -1]))
            fits[name] = (coef[-1], rss, sd)
        step, rss_step, sd = fits["step"]
        rss_spike = fits["spike"][1]
        # a leg's readings the step model leaves farther from it than the noise (a motion the polynomial does
        # not follow) judge its step by that scatter, not by the noise
        dof = len(sets) - degree - 2
        scatter = np.sqrt(rss_step / dof) / self.noise if dof > 0 else np.ones(len(step))
        sds = sd * np.maximum(1.0, scatter)
        found = [j for j in legs if abs(step[j]) > STEP_SIGMAS * sds[j] and rss_step[j] < rss_spike[j]]
        largest = max((abs(step[j]) for j in found), default=0.0)
        return tuple(j for j in found if abs(step[j]) >= largest / 4)  # not a leg the largest step dragged along
