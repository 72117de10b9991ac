"""The stream tracker's side of a passage near a singularity: open it, feed the candidates, act on the verdict.

:class:`PassageMixin` is part of :class:`~hexapod_model.tracking.tracker.Tracker`; the
candidates and the statistics are :class:`~hexapod_model.tracking.branches.BranchResolver`.
A passage opens on a trusted sample whose condition number exceeds the tracker's limit, or on
a failed solve of readings without a jump or stuck leg while the newest trusted sample's
condition number is above a quarter of the limit (readings past the fold). It needs
twelve certified samples before it and ``recover=True``; otherwise ``branch_uncertain``
latches until ``reset()`` as before (the paper's raw tracker keeps its behaviour). While it
is open every sample is ``branch_uncertain``; when one candidate is singled out the sample
returns its pose, the history restarts there (the poses of the singular neighbourhood are too
imprecise for the motion model; the next samples are ``settling``) and the flag clears.
After ``resolve_samples`` samples without a verdict, or on a ``jump`` or ``stuck`` sample
within the passage, the flag latches until ``reset()``.
"""

from __future__ import annotations

from collections import deque

import numpy as np
import pinocchio as pin

from ..analysis.sensitivity import SensitivityEvaluator
from ..kinematics.hexapod import Hexapod
from ..kinematics.newton.solver import Solution
from ..lie import pose_distance
from .branches import BranchResolver, mirror_guess
from .reading_tests import TrackerSettings
from .types import posed

_MIN_BEFORE = 12  # certified samples before a passage: fewer cannot anchor the smooth motion


class PassageMixin:
    """Passages near a singularity, for :class:`~hexapod_model.tracking.tracker.Tracker`."""

    hexa: Hexapod
    settings: TrackerSettings
    length: float
    cond_limit: float
    _sens: SensitivityEvaluator
    _sens_b: SensitivityEvaluator | None
    _cond_b: float
    _calm: deque
    _resolver: BranchResolver | None
    _uncertified: bool
    _lost: bool
    _k: int
    _ff: slice
    _sign: int
    _near: bool
    _cond_last: float

    def _solve(self, l: np.ndarray, guess: np.ndarray) -> Solution:  # the Tracker's
        raise NotImplementedError

    def _restart(self, q: np.ndarray, trusted: bool) -> None:  # the Tracker's
        raise NotImplementedError

    def _passage(self, sol, sens, l, suspect: bool):
        """Open, follow and close a passage near a singularity (:mod:`.tracker_branches`).

        Returns ``(sol, sens, open)``: the sample's solution (the other candidate's when it is
        the one consistent with the motion) and whether its assembly is still uncertain.
        """
        s = self.settings
        near = sens.condition_number > self.cond_limit
        if self._resolver is None:
            if not near or suspect:
                return sol, sens, False
            self._open()
        r = self._resolver
        if r is None:
            return sol, sens, self._uncertified
        if suspect:  # a faulty reading within the passage: the candidates' sequences break off
            self._resolver, self._uncertified = None, True
            return sol, sens, True
        if near and not r.post:
            return sol, sens, True

        def solve(guess):
            alt = self._solve(l, guess)
            return alt.q if posed(alt) else None

        def measure(q):
            J = self._sens_b_eval(q)
            return self._cond_b <= self.cond_limit, J

        def at(q):
            ik = self.hexa.inverse(self.hexa.pose_of(q), guess=q, check=False)
            return ik.q, ik.lengths, self._sens_b_eval(ik.q)

        choice = r.follow(self._k, sol.q, self._sens.J, l, not near, solve, measure, self._displaced, at)
        if choice is None:
            if r.post >= s.resolve_samples:
                self._resolver, self._uncertified = None, True
            return sol, sens, True
        self._resolver = None
        if choice == "alt":
            assert r.alt is not None
            sol = self._solve(l, r.alt.qs[-1])
            sens = self._sens.evaluate(sol.q)
        # the history holds poses from the singular neighbourhood, too imprecise for the
        # motion model: it restarts here (the next samples are settling)
        self._restart(sol.q, trusted=False)
        self._sign, self._near = sens.det_sign, False
        return sol, sens, False

    def _sens_b_eval(self, q: np.ndarray) -> np.ndarray:
        """The eliminated Jacobian at ``q`` from the candidates' own evaluator (condition in ``_cond_b``)."""
        if self._sens_b is None:
            self._sens_b = SensitivityEvaluator(self.hexa, self.length)
        self._cond_b = self._sens_b.evaluate(q).condition_number
        return self._sens_b.J

    def _open(self, latch: bool = True) -> None:
        """Open a passage near a singularity.

        Args:
            latch: when no passage can be judged, latch ``branch_uncertain`` (otherwise do nothing).
        """
        if self._resolver is not None or self._uncertified or self._lost:
            return
        if len(self._calm) < _MIN_BEFORE or not self.settings.recover:  # too little to judge by / raw tracker
            self._uncertified = latch
            return
        s = self.settings
        self._resolver = BranchResolver(
            self.hexa.model,
            self._ff,
            [(k, q, self._sens_b_eval(q).copy(), l) for k, q, l in self._calm],
            self.length,
            s.noise,
            s.branch_alpha,
        )
        self._calm.clear()

    def _displaced(self, q: np.ndarray, twist: np.ndarray):
        """``(configuration, readings)`` of ``q``'s platform pose moved by the LOCAL ``twist``."""
        T = self.hexa.pose_of(q) @ pin.exp6(twist).homogeneous
        ik = self.hexa.inverse(T, guess=q, check=False)
        return ik.q, ik.lengths

    def _may_have_crossed(self, q_before: np.ndarray, q: np.ndarray, l: np.ndarray) -> bool:
        """Whether a platform re-anchored at ``q`` after a gap may have crossed a fold meanwhile.

        Continuation along the straight reading path keeps the assembly of ``q_before``; the
        platform itself may have crossed a singular surface during the gap. It may have when
        the mirror of ``q`` across its nearest fold is another assembly of the readings ``l``
        within the joint limits
        no farther from ``q`` than twice the distance moved since ``q_before``, and the newest
        trusted sample or ``q`` has a condition number above a tenth of the limit (a platform
        that crossed during the gap with both ends better conditioned is not detected).
        """
        cond = max(self._cond_last, self._sens.evaluate(q).condition_number)
        if not self.settings.recover or cond <= self.cond_limit / 10:  # no fold near either end
            return False
        guess = mirror_guess(self.hexa.model, self._ff, self.length, q, self._sens.J, self._displaced)
        if guess is None:
            return False
        alt = self._solve(l, guess)
        if alt.status != "converged":  # none, or one outside the joint limits: not the platform's
            return False
        pose = self.hexa.pose_of(q)
        apart = pose_distance(pose, alt.pose, self.length)
        moved = pose_distance(self.hexa.pose_of(q_before), pose, self.length)
        return 1e-9 * self.length < apart <= 2.0 * moved
