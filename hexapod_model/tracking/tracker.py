"""Tracking a stream of leg readings (Jakobović and Jelenković (2002) §V): predictors, statistical checks, recovery.

Each sample is solved by Newton from a *predicted* configuration built from the last trusted
solutions ``P0`` (newest), ``P1``, ``P2``: ``none`` (``P0``), ``eq22`` (``2 P0 - P1``),
``eq23`` (``1.5 P0 - 0.5 P2``), ``eq24`` (``T1 = (P0 + P1)/2, T2 = (P1 + P2)/2,
X = 2.5 T1 - 1.5 T2``), applied to the whole Pinocchio configuration in the tangent space at
``P0`` (``X = P0 (+) sum_k a_k (P_k (-) P0)``), so a constant-twist motion is predicted exactly.

Every sample is then checked (statistics in :mod:`~hexapod_model.tracking.reading_tests`):
its readings against the motion model (``jump``, ``stuck``), its pose against the motion
model's pose plus the reading innovation mapped through the inverse of the eliminated 6x6
Jacobian (``branch_uncertain``), and its configuration (``near_singular``, ``out_of_limits``,
``cone_limit`` and ``collision`` (the solve's body-check flags: a path through the machine's
body), ``imprecise``). A sample with ``jump``, ``stuck`` or ``branch_uncertain``, or whose solve
failed, is *untrusted*: it never enters the history. After more than ``max_gap`` untrusted
samples the history is reset: the next sample with no stuck leg is solved by continuation
(readings moved in steps of at most ``continuation_step``) from the last trusted
configuration, and the next ``settle_samples`` samples, unchecked, are flagged ``settling``
(also at the start and after :meth:`Tracker.reset`). Each sample carries its 1-sigma pose
uncertainty propagated from the reading noise and its condition number. A passage near a
singularity (two assemblies meet) is ``branch_uncertain`` until the readings single out one
assembly (:mod:`~hexapod_model.tracking.passage`). A warm solve the solver returns
``uncertified`` (near a fold, its Krawczyk proof refused) is ``branch_uncertain`` unless the
branch check found its pose consistent with the motion model and its condition number is under
``cond_limit``: the motion model then vouches for the assembly.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import deque
from collections.abc import Callable
from typing import Literal

import numpy as np
import pinocchio as pin

from ..analysis.sensitivity import SensitivityEvaluator
from ..exceptions import HexapodError, InputError
from ..kinematics.hexapod import Hexapod
from ..kinematics.newton.entries import direct, plain
from ..kinematics.newton.first_compile import announce
from ..kinematics.newton.kernels import largest_step
from ..kinematics.newton.proof import ProofState
from ..kinematics.newton.solver import Solution
from ..lie import pose_distance
from .extra_readings import step_with_extra_readings
from .kernels import SCALARS, begin_sample, branch_residual, predict_into, push_trusted, stuck_checks
from .passage import PassageMixin
from .reading_tests import MotionModel, TrackerSettings
from .types import (
    FAILED_STATUSES,
    FLAGS,
    PREDICTORS,
    TrackResult,
    characteristic_length,
    posed,
    predict,
    predictor_layout,
    predictor_weights,
    track_result,
)

_NONE = np.zeros(0)  # no previous readings / no motion model (writeable: one compiled signature)
# the innovations when the motion model is not available (writeable, never written: the stuck test's one signature)
_NO_Z = np.full(6, np.nan)
_SCALE_RATE = 0.02  # weight of a sample in the observed innovation scale (~50 samples)
_SCALE_FLOOR = 1e-3  # the branch check never assumes readings better than 1e-3 noise
_STUCK_LOOKBACK = 8  # readings kept beyond stuck_samples to see the other legs move
_LEG_SETS = [tuple(i for i in range(6) if bits >> i & 1) for bits in range(64)]  # the legs named by stuck_checks' bits
_BEFORE = 24  # certified samples before a passage near a singularity that the candidates are judged by
_INNOVATION_SIGMA, _Z2, _SCALE = (SCALARS.index(name) for name in ("innovation_sigma", "z2", "scale"))

__all__ = [
    "FAILED_STATUSES",
    "FLAGS",
    "PREDICTORS",
    "TrackResult",
    "Tracker",
    "TrackerSettings",
    "characteristic_length",
    "pose_distance",
    "predict",
]


class Tracker(PassageMixin):
    """Solve a stream of readings, each from a predicted guess, and flag doubtful samples.

    Args:
        hexa: the hexapod.
        predictor: one of :data:`PREDICTORS` (the Newton guess; the checks do not depend on it).
        initial: known starting configuration (``Solution`` or ``q``); default home.
        tol: Newton tolerance per sample (closure residual, m and rad; default 100 times the
            hexapod's :attr:`~.hexapod.Hexapod.default_tol`, 1e-10 on the presets).
        max_iter: Newton iterations per sample at most.
        length: m per rad in pose distances and condition numbers (default
            :func:`characteristic_length`).
        settings: a :class:`TrackerSettings`; keyword ``options`` replace its fields
            (``noise=50e-6``, ``recover=False``, ...). A ``resolution`` left at 0 (not given
            as an option) becomes the hexapod's :attr:`~.hexapod.Hexapod.encoder_resolution`.
        sensitivity: the evaluator of ``hexa`` to use, with ``length`` (default: one of its own).
            Its buffers only hold what one step computes, so trackers stepped one after another
            on one thread may share one (its Pinocchio data is ~3 MB); never trackers stepped on
            different threads.

    A tracker keeps per-stream state and its own solver buffers: one tracker per stream and
    thread (the :class:`Hexapod` may be shared).

    A hexapod with redundant sensors (:mod:`hexapod_model.kinematics.redundant`): :meth:`step`
    takes all its readings; the six legs are tracked as above, then every reading is solved
    from that configuration (:mod:`~hexapod_model.tracking.extra_readings`: the least-squares
    pose, ``inconsistent_readings`` when they fail the consistency test).
    """

    def __init__(
        self,
        hexa: Hexapod,
        predictor: str = "eq22",
        initial=None,
        *,
        tol: float | None = None,
        max_iter: int = 20,
        length: float | None = None,
        settings: TrackerSettings | None = None,
        sensitivity: SensitivityEvaluator | None = None,
        **options,
    ):
        if predictor not in PREDICTORS:
            raise InputError("predictor", predictor, f"choose one of {PREDICTORS}")
        tol = 100.0 * hexa.default_tol if tol is None else tol
        self.hexa, self.predictor, self.tol, self.max_iter = hexa, predictor, tol, max_iter
        s = TrackerSettings.with_options(settings, options) if options or settings is None else settings
        if s.resolution == 0.0 and hexa.encoder_resolution > 0.0 and "resolution" not in options:
            s = dataclasses.replace(s, resolution=hexa.encoder_resolution)  # the geometry's encoder count
        # what the stream needs only now and then is loaded now, not in the middle of it: the
        # stuck test's run length (computed at a leg's first frozen run) and scipy.special (the
        # passage test's quantiles); loading them mid-stream stalled a sample (~0.2 s a process)
        import scipy.special  # noqa: F401

        s.frozen_run  # noqa: B018 - a cached property, evaluated for its side effect
        self.settings = s
        self.length = characteristic_length(hexa) if length is None else float(length)
        self._motion = MotionModel()
        if sensitivity is not None and (sensitivity.hexa is not hexa or sensitivity.length != self.length):
            raise InputError("sensitivity", sensitivity, "expected an evaluator of this hexapod with this length")
        self._sens = SensitivityEvaluator(hexa, self.length) if sensitivity is None else sensitivity
        clm = hexa.closed_loop
        self._prism_q, self._ff = clm.prismatic_q, slice(clm.platform_v, clm.platform_v + 6)
        self._ffq = slice(clm.platform_q, clm.platform_q + 7)  # the platform's free-flyer coordinates
        home = self._sens.evaluate(hexa.q_home)
        self.home_condition = home.condition_number
        self.cond_limit = float(s.cond_limit) if s.cond_limit is not None else s.cond_factor * self.home_condition
        self._hist: deque[np.ndarray] = deque(maxlen=s.window)
        # the predictor compiled (:func:`.kernels.predict_into`; None: Pinocchio's, :func:`.types.predict`)
        self._layout = predictor_layout(hexa.model)
        # the predictor's (a1, a2) by the history's length (.types.predictor_weights)
        self._predictor_weights = [predictor_weights(predictor, n) for n in range(s.window + 1)]
        nv = hexa.model.nv
        mats = [np.zeros((3, 3)) for _ in range(3)]
        self._predict_work = (np.zeros(nv), np.zeros(nv), *mats, np.zeros(3))
        # the compiled predictor: loaded (or compiled, about a second after installation) now, on
        # throwaway arrays of the types a step passes (every array it takes is plain: .entries), and
        # called directly from then on
        self._predict_into: Callable[..., None] = predict_into
        if self._layout is not None:
            q0 = np.array(hexa.q_home, dtype=float)
            probe_args = (q0, q0, 1.0, q0, 0.0, self._layout, np.empty(q0.size), self._predict_work)
            self._predict_into = _loaded(predict_into, probe_args)
        self._branch_ready = False  # the branch check's kernel announced (its first call compiles it: 1-2 s)
        # the histories of the motion model, windows of buffers twice as tall (.kernels.push_trusted)
        self._Fbuf, self._Lbuf = np.zeros((2 * s.window, 7)), np.zeros((2 * s.window, 6))
        self._tops = (s.window, s.window)  # the windows' first rows
        self._F = self._Fbuf[s.window :]  # free-flyer coordinates of _hist, newest first
        self._L = self._Lbuf[s.window :]  # readings of the trusted samples, newest first
        self._e = np.zeros(6)  # the branch check's residual
        self._lhat = np.zeros(6)  # the motion model's readings (m)
        self._bound = s.branch_sigmas * s.noise  # the branch check's bound per scale and spread
        self._z = np.zeros(6)  # the sample's normalised innovations
        self._born: list[int] = [0] * s.window  # sample number of each trusted one, newest first
        self._run = 0  # trusted samples at consecutive sample numbers ending at _born[0]
        self._ages = [tuple(range(1, n + 1)) for n in range(s.window + 1)]  # of n of them, the sample after
        # the readings kept for the stuck test, a ring: the newest in row _raw_state[0], _raw_state[1] of them
        self._raw = np.zeros((s.stuck_samples + _STUCK_LOOKBACK, 6))
        self._raw_state = np.zeros(2, dtype=np.int64)
        # begin_sample's scalars (.kernels.SCALARS): the settings it reads, the innovation sigma of the
        # sample, and the observed / stated noise (z2 its mean square, scale its root, <= 1)
        values = {"stuck_tolerance": s.stuck_tolerance, "jump_sigmas": s.jump_sigmas}
        values |= {"scale_rate": _SCALE_RATE, "scale_floor": _SCALE_FLOOR, "z2": 1.0, "scale": 1.0}
        self._scalars = np.array([values.get(name, 0.0) for name in SCALARS])
        self._moving, self._moved = np.zeros(6), np.zeros(6)  # the stuck test's work
        first_run = s.frozen_run if s.resolution > 0.0 else 1  # with counts, only an improbable run counts
        moved_bound = s.stuck_sigmas * math.sqrt(2.0) * s.reading_sigma  # another leg's change that is motion (m)
        self._stuck_args = (first_run, s.frozen_run)
        self._stuck_bounds = np.array(
            [s.stuck_samples, s.stuck_sigmas, moved_bound, s.stuck_motion_sigmas, s.jump_sigmas, s.reading_sigma]
        )
        self._calm: deque[tuple[int, np.ndarray, np.ndarray]] = deque(maxlen=_BEFORE)  # certified, not near-singular
        self._sens_b: SensitivityEvaluator | None = None  # for the candidates of a passage
        self._k = 0  # samples since the start
        # the proofs of this stream's steps keep their region and preconditioner in a state of their
        # own (.newton.proof): trackers stepped in turn on one thread would otherwise find another
        # stream's, and prove every step afresh. None until the first step; False: no prover
        self._proof_state: ProofState | Literal[False] | None = None
        self.reset(initial)
        # the stuck test's kernel runs only when a reading repeats (a fixture at rest): loaded (or
        # compiled, about a second after installation) now, on no reading, and called directly from then on
        args = (self._raw, 0, 0, self._frozen, _NO_Z, self._stuck, 1, 1, self._stuck_bounds, self._moving, self._moved)
        self._stuck_checks: Callable[..., tuple] = _loaded(stuck_checks, args)
        # the statistics of every sample (.kernels.begin_sample) likewise: loaded or compiled (about a
        # second) now, on throwaway arrays of the types a step passes, and called directly from then on
        l, lhat, z = np.zeros(6), np.zeros(6), np.zeros(6)
        raw, raw_state, frozen, stuck = (
            np.zeros_like(self._raw),
            np.zeros(2, dtype=np.int64),
            np.zeros(6, dtype=np.int64),
            np.zeros(6, dtype=bool),
        )
        probe = (l, raw, raw_state, frozen, stuck, _NONE, np.zeros_like(self._L), lhat, z, self._scalars.copy())
        self._begin_sample: Callable[..., tuple] = _loaded(begin_sample, probe)
        # the histories' push (.kernels.push_trusted) likewise, on throwaway buffers
        buffers = (np.zeros_like(self._Fbuf), np.zeros_like(self._Lbuf))
        pushed = (plain(hexa.q_home), self._ffq.start, self._prism_q, *buffers, 0, 0, False)
        self._push_rows: Callable[..., tuple[int, int]] = _loaded(push_trusted, pushed)

    def reset(self, initial=None) -> None:
        """Forget the history; restart from ``initial`` (``Solution``, ``q`` or home)."""
        if initial is None:
            q = self.hexa.q_home
        elif isinstance(initial, Solution):
            q = initial.q.copy()
        else:
            q = np.asarray(initial, dtype=float).copy()
            if q.shape != (self.hexa.nq,) or not np.all(np.isfinite(q)):
                raise InputError("initial", initial, f"expected a Solution or {self.hexa.nq} finite values")
        self._restart(q, trusted=False)
        self._raw_state[1] = 0
        self._frozen = np.zeros(6, dtype=np.int64)
        self._stuck = np.zeros(6, dtype=bool)
        self._lost = False  # recover=False: a failed branch check latches branch_uncertain
        self._uncertified = False  # passed near a singularity without singling out the assembly
        self._resolver = None  # the candidates of the current passage
        self._cond_last = self.home_condition  # of the newest trusted sample
        self._calm.clear()
        self._sign, self._near = self._sens.evaluate(q).det_sign, False  # of the newest trusted sample
        self._scalars[_Z2] = self._scalars[_SCALE] = 1.0  # observed / stated noise (mean square, root), <= 1

    def _restart(self, q: np.ndarray, trusted: bool) -> None:
        """History = ``q`` only (``trusted``: ``q`` is a sample of the stream)."""
        q = plain(q)  # the predictor's one compiled type
        self._hist.clear()
        self._hist.appendleft(q)
        self._F[0] = q[self._ffq]
        self._n = 0
        self._gap = 0
        self._doubt = False  # a pose failed the branch check since the newest trusted sample
        self._last_q = q
        if trusted:
            self._push_trusted(q)

    def _push_trusted(self, q: np.ndarray) -> None:
        q = plain(q)  # the predictor's one compiled type (a solver's q is one: no copy)
        first = self._n == 0
        if first:
            # the history's one entry is the start (home, initial, reset()'s), no sample of the stream:
            # the first trusted sample replaces it, so that no prediction extrapolates from the start
            self._hist[0] = q
        else:
            self._hist.appendleft(q)
        tops = self._push_rows(q, self._ffq.start, self._prism_q, self._Fbuf, self._Lbuf, *self._tops, first)
        (f, l), window = tops, self.settings.window
        self._tops, self._F, self._L = tops, self._Fbuf[f : f + window], self._Lbuf[l : l + window]
        born, k = self._born, self._k
        self._run = self._run + 1 if born[0] == k - 1 else 1
        born.insert(0, k)  # age 0 now, one more at each sample
        born.pop()
        self._n = min(self._n + 1, self.settings.window)
        self._gap = 0
        self._doubt = False

    # ----- the per-sample work -----
    def step(self, lengths) -> TrackResult:
        """Solve and check one sample (readings in m, leg order).

        A hexapod with redundant sensors takes all its readings, in the order of its
        ``reading_names`` (m for legs, rad for tilts): :mod:`~hexapod_model.tracking.extra_readings`.
        Never raises on bad readings or a failed solve: see ``status`` and ``flags``.
        """
        state = self._proof_state
        if state is None:  # the first step: this stream's proof state, or False when the model has no prover
            prover = self.hexa.engine.prover
            state = self._proof_state = False if prover is None else prover.new_state()
        previous = state.prover.use(state) if state else None  # every solve of the step proves with it
        try:
            if self.hexa.redundancy is not None:
                return step_with_extra_readings(self.hexa, lengths, self._step, self.tol, self.max_iter)
            return self._step(lengths)
        finally:
            if state:
                state.prover.use(previous)  # the thread's own again

    def _step(self, lengths) -> TrackResult:
        """:meth:`step` of six leg readings."""
        t0 = time.perf_counter()
        s = self.settings
        self._k += 1  # every sample, readable or not, is one period: ages are counted from here
        # the readings copied: the stuck test keeps them, and a caller may refill one array sample after sample
        if type(lengths) is np.ndarray and lengths.dtype == np.float64 and lengths.ndim == 1:  # the common case
            l = lengths.copy()
        else:
            l = np.array(lengths, dtype=float).reshape(-1) if _numeric(lengths) else np.full(6, np.nan)
        n, m = self._n, self._gap + 1
        checked = l.shape == (6,) and n >= s.settle_samples and m <= s.max_gap + 1
        lhat, w, spread = _NONE, _NONE, 0.0
        if checked:
            k = self._k
            if self._run >= n and self._born[0] == k - 1:  # no untrusted sample among the last n
                ages = self._ages[n]
            else:
                ages = tuple([k - b for b in self._born[:n]])
            w, spread = self._motion.weights(ages)
            lhat = self._lhat
        # in one compiled call (.kernels.begin_sample): the motion model's readings lhat = w @ L[:n];
        # finite readings; frozen runs (|l - previous| <= stuck_tolerance); z = |l - l^| / (noise spread);
        # then, for finite readings, the readings ring and the observed noise scale (the branch check's)
        raw_state = self._raw_state
        if l.shape != (6,):
            finite, zmax, zz, frozen, any_stuck = False, math.nan, 0.0, 0, False
        else:
            scalars = self._scalars
            scalars[_INNOVATION_SIGMA] = s.innovation_sigma(spread)
            args = (l, self._raw, raw_state, self._frozen, self._stuck, w, self._L, self._lhat, self._z, scalars)
            finite, zmax, zz, frozen, any_stuck = self._begin_sample(*args)
        if not finite:
            msg = f"expected 6 finite readings, got {lengths!r}"
            return self._failure(l if l.shape == (6,) else np.full(6, np.nan), "invalid_input", msg, (), (), t0)
        flags: list[str] = []
        legs: tuple[int, ...] = ()
        suspect = False
        if zmax > s.jump_sigmas or frozen > 0 or any_stuck:
            # reading_tests.stuck_legs, compiled; the latched legs (self._stuck) updated in place
            first_run, run = self._stuck_args
            stuck_args = (
                self._raw,
                raw_state[1],
                raw_state[0],
                self._frozen,
                self._z if checked else _NO_Z,
                self._stuck,
                first_run,
                run,
                self._stuck_bounds,
                self._moving,
                self._moved,
            )
            jumped, stuck_any, bits = self._stuck_checks(*stuck_args)
            legs = _LEG_SETS[bits]
            flags += ["jump"] * jumped + ["stuck"] * stuck_any
            suspect = bool(flags)
        if self._gap > s.max_gap and "stuck" not in flags:
            return self._reanchor(l, flags, legs, t0)
        sol = self._solve(l, self._guess())
        if not posed(sol):
            if not suspect and sol.status != "invalid_input" and self._cond_last > self.cond_limit / 4:
                self._open(latch=False)  # no assembly near the prediction: readings past a fold?
            return self._failure(l, sol.status, sol.message, tuple(flags), legs, t0, sol)
        sens = self._sens.evaluate_solved(sol.q)  # from the solve's own Jacobians
        consistent = False
        if checked and not suspect and not self._lost:
            sol, sens, consistent = self._branch_check(sol, sens, l, lhat, w, spread)
            if not consistent:
                flags.append("branch_uncertain")
                self._lost = not s.recover
                self._doubt = suspect = s.recover
        if self._resolver is None and (legs or self._lost or not sens.condition_number > self.cond_limit):
            open_ = False  # no passage open, none to open (the first test of _passage)
        else:
            sol, sens, open_ = self._passage(sol, sens, l, bool(legs) or self._lost)
        # the solver could not certify the assembly from the guess alone (a warm step near a
        # fold, its Krawczyk proof refused); the branch check's motion model vouches for it when
        # the pose is consistent with it and the condition number is under the tracker's limit
        # (the other assembly is then farther than the check's bound: passages judge the rest)
        vouched = consistent and not open_ and sens.condition_number <= self.cond_limit
        uncertified = sol.status == "uncertified" and not vouched
        if (self._lost or self._uncertified or open_ or uncertified) and "branch_uncertain" not in flags:
            flags.append("branch_uncertain")
        if not checked and m <= s.max_gap + 1:
            flags.append("settling")
        return self._finish(sol, sens, flags, legs, zmax, trusted=not suspect, t0=t0)

    def _guess(self) -> np.ndarray:
        if self._gap > self.settings.max_gap:
            return self._last_q
        hist = self._hist  # reads P0, P1, P2 only: the trusted samples (before the first, the start)
        if self._layout is None:  # a model of other joints: Pinocchio's
            return predict(self.hexa.model, hist, self.predictor)
        a1, a2 = self._predictor_weights[len(hist)]
        q0 = hist[0]
        if a1 == 0.0 and a2 == 0.0:
            return q0.copy()
        out = np.empty(q0.shape[0])
        if a1 != 0.0:
            args = (q0, hist[1], a1, hist[2] if a2 != 0.0 else q0, a2, self._layout, out, self._predict_work)
        else:
            args = (q0, hist[2], a2, q0, 0.0, self._layout, out, self._predict_work)
        self._predict_into(*args)
        return out

    def _solve(self, l: np.ndarray, guess: np.ndarray) -> Solution:
        # a step within continuation_step carries its Krawczyk proof; a longer one (the first
        # sample, after a gap: flagged settling) the certificate's checks, not the proven steps
        # that would hold the cycle for tens of milliseconds
        joints = l if self.hexa.engine.encoder is None else self.hexa.joints_of(l[:6])  # m, as the guess's
        step = largest_step(joints, guess, self._prism_q)  # m, compiled: NumPy's would be four dispatches
        prove = bool(step <= self.settings.continuation_step)
        try:
            if self.hexa.redundancy is not None:  # the six legs' solve of a hexapod with redundant sensors
                return self.hexa.engine.forward(l, guess, self.tol, self.max_iter, False, False, prove)
            return self.hexa.forward(l, guess=guess, tol=self.tol, max_iter=self.max_iter, check=False, prove=prove)
        except HexapodError as exc:  # a reading outside the stroke
            q = self._last_q
            return Solution(self.hexa.pose_of(q), q.copy(), l.copy(), "invalid_input", 0, math.nan, None, str(exc))

    def _branch_check(self, sol, sens, l, lhat, w, spread):
        """Compare the pose with the motion model's pose plus ``J^-1`` (reading innovation).

        On a mismatch re-solve from the motion model's configuration (``recover``). The
        comparison needs the platform's pose only (:func:`.tracker_kernels.branch_residual`);
        the whole configuration of the motion model is made for a re-solve only.
        """
        if self.settings.recover and sens.condition_number > self.cond_limit:
            # near a singularity assemblies meet: keep the one the motion continues to
            alt = self._solve(l, self._model_q(w))
            if posed(alt) and pose_distance(alt.pose, sol.pose, 1.0) > 1e-9:
                sol, sens = alt, self._sens.evaluate(alt.q)
        bound = self._bound * self._scalars.item(_SCALE) * spread
        if self._consistent(sol, sens, l, lhat, w, bound):
            return sol, sens, True
        if not self.settings.recover:
            return sol, sens, False
        retry = self._solve(l, self._model_q(w))
        if posed(retry):
            rsens = self._sens.evaluate(retry.q)
            if self._consistent(retry, rsens, l, lhat, w, bound):
                return retry, rsens, True
            self._sens.evaluate(sol.q)
        return sol, sens, False

    def _consistent(self, sol, sens, l, lhat, w, bound) -> bool:
        """Whether ``sol`` is within ``bound`` propagated pose sigmas of the motion model's pose."""
        cond = sens.condition_number
        if sens.det_sign != self._sign and not (self._near or cond > self.cond_limit):
            return False  # across a singularity without passing near one: another assembly
        e = self._e  # log6(Mm^-1 Ms) - J^-1 (l - l^), Mm the motion model's pose
        if not self._branch_ready:
            announce(branch_residual)
            self._branch_ready = True
        et, er = branch_residual(self._F, w.size, w, sol.q[self._ffq], self._sens.Jinv, l, lhat, e)
        length = self.length
        size = math.hypot(et, length * er)
        return size <= bound * math.hypot(sens.translation, length * sens.rotation) + 1e-9 * length

    def _model_q(self, w: np.ndarray) -> np.ndarray:
        """The motion model's configuration ``P0 (+) sum_j w_j (P_j (-) P0)`` (a Newton guess)."""
        model, q0 = self.hexa.model, self._hist[0]
        dv = np.zeros(model.nv)
        for j in range(1, w.size):
            dv += w[j] * pin.difference(model, q0, self._hist[j])
        return pin.integrate(model, q0, dv)

    def _reanchor(self, l: np.ndarray, flags: list[str], legs: tuple, t0: float) -> TrackResult:
        """Continuation to ``l`` from the last trusted configuration; restart the history there.

        In finer steps if needed, then from the newest solved configuration.
        """
        s = self.settings
        sol: Solution | None = None
        for q0, step in ((self._hist[0], s.continuation_step), (self._hist[0], s.continuation_step / 8)) + (
            (self._last_q, s.continuation_step),
        ):
            sol = self._continue(q0, l, step)
            if posed(sol):
                break
        else:
            assert sol is not None
            return self._failure(l, sol.status, f"re-anchoring: {sol.message}", tuple(flags), legs, t0, sol)
        assert sol is not None
        sens = self._sens.evaluate(sol.q)
        # poses that kept failing the branch check: the last trusted one may be on another
        # assembly already, so the re-anchored one cannot be certified (until reset)
        # (within a passage near a singularity the candidates are judged there instead)
        self._lost = self._lost or (self._doubt and self._resolver is None)
        crossed = self._resolver is None and self._may_have_crossed(self._hist[0], sol.q, l)
        self._restart(sol.q, trusted=True)
        if crossed:  # the assembly is judged as after a passage near a singularity
            self._open()
        self._sign, self._near = sens.det_sign, sens.condition_number > self.cond_limit
        uncertain = self._lost or self._uncertified or self._resolver is not None
        out = [*flags] + (["branch_uncertain"] if uncertain else []) + ["settling"]
        return self._finish(sol, sens, out, legs, math.nan, trusted=None, t0=t0)

    def _continue(self, q0: np.ndarray, l: np.ndarray, step: float) -> Solution:
        """Newton along the straight reading path from ``q0``'s readings to ``l``."""
        l0 = q0[self._prism_q]
        n = max(1, math.ceil(float(np.max(np.abs(l - l0))) / step))
        q, sol = q0, None
        for k in range(1, n + 1):
            sol = self._solve(l0 + (l - l0) * (k / n), q)
            if not posed(sol):
                return sol
            q = sol.q
        assert sol is not None
        return sol

    def _finish(self, sol, sens, flags, legs, innovation, trusted, t0) -> TrackResult:
        s = self.settings
        cond = sens.condition_number
        near = cond > self.cond_limit
        if near:
            flags.append("near_singular")
            # a re-anchored pose here: its assembly cannot be certified (until reset())
            self._uncertified = self._uncertified or (trusted is None and self._resolver is None)
        if sol.status == "out_of_limits":
            flags.append("out_of_limits")
        if sol.flags:  # a path through the machine's body
            flags += [f for f in ("cone_limit", "collision") if f in sol.flags]
        noise = s.noise
        sig_t, sig_r = noise * sens.translation, noise * sens.rotation
        if s.max_sigma_factor is not None and not math.hypot(sig_t, self.length * sig_r) <= s.max_sigma_factor * noise:
            flags.append("imprecise")
        q = sol.q
        if trusted:
            self._push_trusted(q)
            self._sign, self._near = sens.det_sign, near
            self._cond_last = cond
            if not (near or self._lost or self._uncertified or self._resolver):
                self._calm.append((self._k, q, sol.lengths))
        elif trusted is not None:
            self._gap += 1
        self._last_q = q
        margin = self.home_condition / cond
        return track_result(
            sol, "ok", tuple(flags), legs, innovation, sig_t, sig_r, cond, margin, time.perf_counter() - t0
        )

    def _failure(self, l, status, message, flags, legs, t0, sol=None) -> TrackResult:
        self._gap += 1
        if sol is None:
            q = self._last_q
            sol = Solution(self.hexa.pose_of(q), q.copy(), l.copy(), status, 0, math.nan, None, message)
        nan = math.nan
        return track_result(sol, status, flags, legs, nan, nan, nan, nan, nan, time.perf_counter() - t0)


def _loaded(kernel: Callable, args: tuple) -> Callable:
    """``kernel``'s machine code for ``args``' types, to call directly.

    Announced (:func:`.first_compile.announce`), then loaded or compiled by a call on ``args``.
    """
    announce(kernel)
    kernel(*args)
    return direct(kernel, args)


def _numeric(values) -> bool:
    try:
        np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        return False
    return True
