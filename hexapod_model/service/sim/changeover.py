"""A scripted changeover for the simulated encoders: the plate follows its fixture's target.

``sim.toml``, per fixture::

    [fixtures.changeover]
    move = 4.0        # s from where the plate is to the target, then
    overshoot = 0.15  # beyond it by this fraction of the way (a hand moving a plate overshoots)
    settle = 1.0      # s back onto the target, where it stays (the brakes lock it)

When the fixture's target changes (set on its own or by activating a recipe), the plate's pose
sequence (trajectory, CSV or hold) slows to a stop, then the plate moves on the SE(3) geodesic
from its current pose through the target: the path parameter runs smoothly from 0 to
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

    A plate never changes its velocity at once (the tracker would rightly see a jump): when a new
    target comes while the pose sequence plays, the sequence first slows to a stop over ``ramp``
    seconds (:meth:`sequence_speed`), then the move starts from rest; a target that changes
    during a move is taken once the move has settled.

    Args:
        script: the motion's timing.
        ramp: seconds to stop the pose sequence (the fixture's ``ramp``).
    """

    def __init__(self, script: ChangeoverScript, ramp: float = 0.3):
        self.script, self.ramp = script, max(ramp, 0.05)
        self.key: object = None  # the target requested (its store id)
        self._goal: np.ndarray | None = None
        self._pending = False
        self._stopping: float | None = None  # t_sim the sequence began to stop
        self._start: pin.SE3 | None = None
        self._step: np.ndarray | None = None  # log6(start^-1 target) as a vector
        self._t0 = 0.0
        self._settled = True
        self.active = False  # True once a move started: the pose sequence no longer plays

    def request(self, key: object, target: np.ndarray | None) -> None:
        """The fixture's current target (``key`` changes with it); a changed one is queued."""
        if key != self.key:
            self.key, self._goal, self._pending = key, target, True

    def _busy(self) -> bool:
        return self.active and not self._settled  # a move ends once its settled pose was shown

    def sequence_speed(self, t_sim: float, playing: bool) -> float:
        """Factor (0..1) on the pose sequence's speed while it still plays: 1, or slowing to a stop."""
        if self.active or not self._pending or self._goal is None:
            return 1.0
        if not playing:
            return 0.0
        if self._stopping is None:
            self._stopping = t_sim
        x = (t_sim - self._stopping) / self.ramp
        return 0.0 if x >= 1.0 else 0.5 * (1.0 + math.cos(math.pi * x))

    def follow(self, current: np.ndarray, t_sim: float, playing: bool) -> bool:
        """Start a queued move from ``current`` when the plate is at rest; True while the follower drives the pose."""
        at_rest = self.active or not playing or self.sequence_speed(t_sim, playing) == 0.0
        if self._pending and not self._busy() and at_rest:
            self._pending, self._stopping = False, None
            if self._goal is None:  # cleared: stay where the plate is
                if self.active:
                    self._start, self._step = pin.SE3(current), np.zeros(6)
            else:
                self.active = True
                self._start = pin.SE3(current)
                self._step = pin.log6(self._start.inverse() * pin.SE3(self._goal)).vector
                self._t0, self._settled = t_sim, False
        return self.active

    def pose(self, t_sim: float) -> np.ndarray:
        """The plate's pose (4x4) at ``t_sim`` while following."""
        assert self._start is not None and self._step is not None
        s = self.script.progress(t_sim - self._t0)
        self._settled = self._settled or t_sim - self._t0 >= self.script.move + self.script.settle
        return (self._start * pin.exp6(s * self._step)).homogeneous
