"""A scripted changeover for the simulated encoders: the plate follows its fixture's target.

``sim.toml``, per fixture::

    [fixtures.changeover]
    move = 4.0        # s from where the plate is to the target, then
    overshoot = 0.15  # beyond it by this fraction of the way (a hand moving a plate overshoots)
    settle = 1.0      # s back onto the target, where it stays (the brakes lock it)

When the fixture's target changes (set on its own or by activating a recipe), the plate leaves
its pose sequence (trajectory, CSV or hold) and moves on the SE(3) geodesic from its current pose
to ``target * exp(overshoot * log(target^-1 ... ))``: the path parameter runs smoothly from 0 to
``1 + overshoot`` in ``move`` seconds, back to 1 in ``settle`` seconds, and stays there until the
target changes again; the reading noise and faults act as on any other pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin


@dataclass(frozen=True)
class ChangeoverScript:
    """How a simulated plate moves to a new target.

    Attributes:
        move: seconds from the current pose to the overshoot.
        overshoot: how far past the target (fraction of the way, 0..1).
        settle: seconds from the overshoot back onto the target.
    """

    move: float = 4.0
    overshoot: float = 0.0
    settle: float = 1.0

    def progress(self, t: float) -> float:
        """Path parameter at ``t`` seconds after the move started: 0 -> 1 + overshoot -> 1 (smooth)."""
        if t <= 0.0:
            return 0.0
        top = 1.0 + self.overshoot
        if t < self.move:
            return top * 0.5 * (1.0 - math.cos(math.pi * t / self.move))
        if t < self.move + self.settle and self.overshoot > 0.0:
            x = (t - self.move) / self.settle
            return top - self.overshoot * 0.5 * (1.0 - math.cos(math.pi * x))
        return 1.0


class Follower:
    """The changeover motion of one simulated plate.

    Args:
        script: the motion's timing.
    """

    def __init__(self, script: ChangeoverScript):
        self.script = script
        self.key: object = None  # the target being followed (its store id)
        self._start: pin.SE3 | None = None
        self._step: np.ndarray | None = None  # log6(start^-1 target) as a vector
        self._t0 = 0.0
        self.active = False  # True once a target was set: the pose sequence no longer plays

    def update(self, key: object, target: np.ndarray | None, current: np.ndarray, t_sim: float) -> None:
        """Start a move from ``current`` when the target (``key``) changed; a cleared target stops where it is."""
        if key == self.key:
            return
        self.key = key
        if target is None:
            if self.active:  # stay where the plate is now
                self._start, self._step = pin.SE3(current), np.zeros(6)
            return
        self.active = True
        self._start = pin.SE3(current)
        self._step = pin.log6(self._start.inverse() * pin.SE3(target)).vector
        self._t0 = t_sim

    def pose(self, t_sim: float) -> np.ndarray:
        """The plate's pose (4x4) at ``t_sim`` while following."""
        assert self._start is not None and self._step is not None
        s = self.script.progress(t_sim - self._t0)
        return (self._start * pin.exp6(s * self._step)).homogeneous
