"""The service's one adapter to the stream tracker.

The cycle (:mod:`hexapod_model.service.cycle.fixture_cycle`) never calls the tracker directly: it calls
:class:`PoseSolver` — ``step(readings, instant)`` per reading set it solves (``instant``: the
sampling instant's number, so instants without a solved set are known), ``solve_once(readings, q)``
for a lock pose — and gets a :class:`SolveOutcome`. Only this module knows the tracker's API
(:class:`hexapod_model.tracking.tracker.Tracker`, whose statistical, self-clearing checks
judge every sample against the configured reading noise; see docs/evaluate.md).

* An instant without a solved set (lost frames, a faulty encoder, ...) is given to the tracker
  as an unreadable sample, so its motion model keeps one period per instant; after more than
  ``max_gap`` of them it re-anchors by continuation and flags the next samples ``settling``.
* The 1-sigma pose uncertainty is the tracker's: independent reading noise ``noise`` (m)
  propagated through the eliminated 6x6 Jacobian, ``Cov(xi) = noise^2 J^-1 J^-T``;
  ``translation`` is ``sqrt(trace)`` of the position block (RMS length of the position error, m),
  ``rotation`` that of the rotation-vector block (rad). ``margin`` is ``cond(home) / cond(here)``
  of the 6x6 map with rotations scaled by the characteristic length: 1 at home, towards 0 at a
  singularity.
* A hexapod with redundant sensors (measuring legs, an inclinometer:
  :mod:`hexapod_model.kinematics.redundant`) takes every reading, legs first; the tracker tracks
  the six legs and solves all of them (:mod:`hexapod_model.tracking.extra_readings`): the
  outcome's pose is their weighted least-squares pose, and a set failing the consistency test
  is ``inconsistent`` (flags ``inconsistent_readings`` and ``isolated:NAME`` when the data name
  the faulty reading, whose exclusion gives the pose, flagged ``estimate``; else
  ``suspects:N`` and no pose). The uncertainty stays the six legs' (an upper bound: more
  readings only shrink it).
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np

from ...analysis.sensitivity import SensitivityEvaluator
from ...exceptions import HexapodError
from ...kinematics.consistency import Consistency
from ...kinematics.hexapod import Hexapod
from ...kinematics.newton.solver import Solution
from ...kinematics.redundant import RedundantSolution
from ...lie import xyz_rpy_to_pose
from ...tracking.tracker import Tracker, characteristic_length


class Uncertainty(NamedTuple):
    """Noise-propagated 1-sigma pose uncertainty and the distance from a singularity.

    Immutable records made once per reading set (tuples: a third of a frozen dataclass's cost).

    Attributes:
        translation: RMS length of the position error (m).
        rotation: RMS angle of the rotation error (rad).
        margin: ``cond(home) / cond(here)`` of the length-scaled 6x6 Jacobian.
    """

    translation: float
    rotation: float
    margin: float


class SolveOutcome(NamedTuple):
    """One solved reading set (an immutable record, as :class:`Uncertainty`).

    Attributes:
        pose: 4x4 base -> platform (m), or ``None`` when the solve failed.
        q: the configuration of the solution (``None`` when failed).
        status: ``ok`` (no flag), ``flagged`` (a pose, see ``flags``), ``failed`` or
            ``inconsistent`` (redundant readings failing their consistency test).
        flags: tracker flags (``jump``, ``stuck``, ``branch_uncertain``, ``settling``,
            ``near_singular``, ``out_of_limits``, ``imprecise``) and, for a failed solve, the
            failure's name.
        iterations: Newton steps.
        uncertainty: of the pose (``None`` when failed).
        solve_time: seconds spent (prediction, solve, checks, uncertainty).
        legs: legs (0-based) the tracker's ``jump`` or ``stuck`` names.
        consistency: the consistency test of a solve from redundant readings, else ``None``.
    """

    pose: np.ndarray | None
    q: np.ndarray | None
    status: str
    flags: tuple[str, ...]
    iterations: int
    uncertainty: Uncertainty | None
    solve_time: float
    legs: tuple[int, ...] = ()
    consistency: Consistency | None = None


class PoseSolver:
    """Readings of one fixture in, tracked poses with flags and uncertainty out.

    Args:
        hexa: the fixture's hexapod.
        noise: 1-sigma reading noise (m).
        predictor: the tracker's predictor.
        initial: configuration ``q`` to start from (a recovered lock pose); default home.
        confirm_samples: kept for configuration compatibility; the tracker's own checks decide
            when a doubt clears.
        sensitivity: the tracker's evaluator (see :class:`~hexapod_model.tracking.tracker.Tracker`),
            also used for poses outside the stream; solvers stepped on one thread may share one
            (its Pinocchio data is ~3 MB); default: one of its own.
        resolution: the encoders' count (m; 0: continuous readings): the tracker's checks allow
            for the rounding and for a leg at rest repeating its count.
    """

    def __init__(
        self,
        hexa: Hexapod,
        noise: float,
        predictor: str = "eq22",
        initial=None,
        confirm_samples: int = 5,
        sensitivity: SensitivityEvaluator | None = None,
        resolution: float = 0.0,
    ):
        self.hexa, self.noise, self.confirm_samples = hexa, float(noise), confirm_samples
        self.length = characteristic_length(hexa)
        if sensitivity is None:
            sensitivity = SensitivityEvaluator(hexa, self.length)
        q0 = hexa.q_home if initial is None else np.asarray(initial, dtype=float)
        self.tracker = Tracker(
            hexa,
            predictor,
            initial=q0,
            length=self.length,
            noise=self.noise,
            resolution=abs(float(resolution)),
            sensitivity=sensitivity,
        )
        self._sens = sensitivity  # for poses outside the stream, between two steps
        self._unreadable = np.full(len(hexa.reading_names), np.nan)  # an instant without a solved set
        self._instant: int | None = None  # of the last set given to the tracker

    def propagation(self, q: np.ndarray) -> np.ndarray:
        """``J^-1`` (6x6): platform twist ``[v; w]`` (platform frame) per unit reading change, at ``q``.

        The inverse of :func:`hexapod_model.analysis.jacobian.leg_jacobian_local` (NaN when singular).
        """
        self._sens.evaluate(np.asarray(q, dtype=float))
        return self._sens.Jinv.copy()

    def uncertainty(self, q: np.ndarray) -> Uncertainty:
        """1-sigma pose uncertainty at configuration ``q`` (inf and margin 0 when singular)."""
        s = self._sens.evaluate(np.asarray(q, dtype=float))
        if not s.condition_number < np.inf:
            return Uncertainty(float("inf"), float("inf"), 0.0)
        return Uncertainty(
            self.noise * s.translation, self.noise * s.rotation, self.tracker.home_condition / s.condition_number
        )

    def solve_once(self, readings: np.ndarray, q: np.ndarray) -> Solution:
        """A single solve from ``q`` (no tracking), never raising: see ``status``."""
        return self.hexa.forward(readings, guess=q, tol=self.tracker.tol, check=False)

    def step(self, readings: np.ndarray, instant: int | None = None) -> SolveOutcome:
        """Solve one complete reading set (m, leg order); never raises on a failed solve.

        Args:
            readings: the set's six readings (m).
            instant: number of the set's sampling instant (``None``: the one after the last).
        """
        t0 = time.perf_counter()
        if instant is not None and self._instant is not None:
            # beyond max_gap + 1 the tracker re-anchors anyway: more unreadable samples change nothing
            for _ in range(min(instant - self._instant - 1, self.tracker.settings.max_gap + 1)):
                self.tracker.step(self._unreadable)
        self._instant = instant
        r = self.tracker.step(readings)
        if r.failed:
            flags = (*r.flags, r.status)
            return SolveOutcome(None, None, "failed", flags, r.iterations, None, _since(t0), r.legs)
        u = Uncertainty(r.sigma_translation, r.sigma_rotation, r.singularity_margin)
        sol = r.solution
        if "inconsistent_readings" in r.flags:
            return _inconsistent(sol, r.flags, u, t0, r.legs)
        status = "flagged" if r.flags else "ok"
        test = sol.consistency if isinstance(sol, RedundantSolution) else None
        return SolveOutcome(sol.pose, sol.q, status, r.flags, sol.iterations, u, _since(t0), r.legs, test)


def _inconsistent(
    sol: Solution, flags: tuple[str, ...], u: Uncertainty, t0: float, legs: tuple[int, ...]
) -> SolveOutcome:
    """Readings failing their consistency test: the named reading and the others' estimate, or no pose."""
    test = sol.consistency if isinstance(sol, RedundantSolution) else None
    named = () if test is None or test.isolated is None else (f"isolated:{test.isolated}",)
    why = named or (f"suspects:{0 if test is None else len(test.suspects)}",)
    if not named or "estimate" not in sol.flags:  # no pose the data vouch for
        return SolveOutcome(None, None, "inconsistent", (*flags, *why), sol.iterations, None, _since(t0), legs, test)
    out = (*flags, *why, "estimate")
    return SolveOutcome(sol.pose, sol.q, "inconsistent", out, sol.iterations, u, _since(t0), legs, test)


def _since(t0: float) -> float:
    return time.perf_counter() - t0


def warm_up(hexa: Hexapod, noise: float, predictor: str = "eq22", samples: int = 20) -> None:
    """Run what a reading set may run (tracker step, certified solve, readings path, proof, sensitivity).

    The first call of each compiled kernel compiles it (one to two minutes after installation,
    before numba has cached it next to the package) or loads it from the cache: done here,
    before the first frame is read, no set waits for a compilation. ``samples`` sets along a
    small ramp from home run the tracker's kernels and the warm certified solve; then the
    kernels a set runs only sometimes: the readings path that a solve follows in substeps when
    its first attempt does not certify (the first sets after a restart with the plate moved
    from its stored lock pose, :func:`_warm_readings_path`), and the Krawczyk proof of a warm
    step (:meth:`~hexapod_model.kinematics.hexapod.Hexapod.forward` proves every warm step; the
    tracker's steps compile it already).
    """
    solver = PoseSolver(hexa, max(noise, 1e-6), predictor)
    ramp = np.linspace(0.0, 1e-4, samples)
    extra = np.zeros(len(hexa.reading_names) - 6)  # redundant sensors: their home readings (a consistency test fails)
    for k, step in enumerate(ramp):
        solver.step(np.concatenate([np.full(6, step), extra]), k)
    solver.uncertainty(hexa.q_home)
    _warm_readings_path(hexa)
    first = solver.solve_once(np.concatenate([np.zeros(6), extra]), hexa.q_home)
    step = solver.solve_once(np.concatenate([np.full(6, 1e-4), extra]), first.q)
    if first.converged and step.converged:
        hexa.prove_step(first, step)


def _warm_readings_path(hexa: Hexapod) -> None:
    """Solve from home the readings of the plate turned and raised (as after a restart with the plate moved).

    Far enough that the first attempt does not certify: the path is followed in substeps to a
    certified result. Turns of growing size until one did (a geometry whose workspace is small
    stops at the first it cannot reach).
    """
    from ...kinematics.newton.follow import follow  # the compiled readings path: compiled once it ran

    rise = 0.15 * float(np.mean(hexa.stroke[:, 1] - hexa.stroke[:, 0]))
    for yaw in (45.0, 30.0, 60.0, 20.0):
        if not hexa.compiled:
            return
        try:
            target = hexa.inverse(hexa.home_pose @ xyz_rpy_to_pose([0.0, 0.0, rise, 0.0, 0.0, yaw]))
            sol = hexa.forward(target.lengths, guess=hexa.q_home, check=False)
        except HexapodError:  # outside what this geometry reaches: the next turn may not be
            continue
        if follow.signatures and sol.converged:
            return
