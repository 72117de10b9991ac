"""The service's one adapter to the stream tracker, and the pose uncertainty of a solution.

The cycle (:mod:`hexapod_model.service.cycle`) never calls the tracker directly: it calls
:class:`PoseSolver` — ``step(readings)`` per complete reading set, ``gap()`` when sets were
skipped, ``solve_once(readings, q)`` for a lock pose — and gets a :class:`SolveOutcome`. Only
this module knows the tracker's API (:class:`hexapod_model.analysis.tracking.Tracker`:
``Tracker(hexa, predictor, initial=q, jump_floor=..., length=...)``, ``step(readings)`` ->
``.solution``, ``.status`` in ``ok``/``flagged``/``failed``, ``.flags``, ``reset(q)``).

What the adapter adds to the tracker (until the tracker does it itself):

* the ``jump`` bound's floor from the configured reading noise (a jump is judged against the
  noise, not only against the last step);
* a predictor restart from the last good configuration after skipped sets (``gap``);
* clearing ``branch_uncertain``: after ``confirm_samples`` samples without a jump, the readings
  are solved again from the last good configuration; the doubt clears only if both solves agree.

The 1-sigma pose uncertainty propagates independent reading noise ``noise`` (m) through the
eliminated 6x6 Jacobian (see :mod:`hexapod_model.analysis.jacobian`): ``d xi = X d l`` with
``X = -(G_free^-1 G_legs)`` restricted to the platform rows, ``Cov(xi) = noise^2 X X^T``.
``translation`` is ``sqrt(trace)`` of the position block (the RMS length of the position error,
m), ``rotation`` that of the rotation-vector block (rad); both are frame-independent.
``singularity_margin`` is ``cond(home) / cond(here)`` of the 6x6 map with rotations scaled by
the characteristic length: 1 at home, larger when better conditioned, towards 0 at a singularity.
Both change by less than 0.3 % per mm or 0.1 deg of platform motion over the reference hexapod's
+-50 mm / +-25 deg box, so a set within 0.5 mm and 0.05 deg of the pose they were last computed at
(margin above 0.2) reuses them: at 1 kHz that skips most evaluations.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..analysis.tracking import Tracker, characteristic_length, pose_distance
from ..kinematics.hexapod import Hexapod
from ..kinematics.linalg import lu_apply, lu_apply_transposed, lu_factor
from ..kinematics.solver import NewtonSolver, Solution

JUMP_NOISE_FACTOR = 4.0 * np.sqrt(6.0)  # jump floor / RMS pose noise: 2 P0 - P1 - P has 6x the variance
AGREE = 1e-7  # m (rotations scaled): two solves on the same branch agree to ~1e-9
REUSE_M, REUSE_COS = 0.5e-3, np.cos(np.radians(0.05))  # sigma is reused within 0.5 mm and 0.05 deg
REUSE_MARGIN = 0.2  # ... of where it was computed, unless a singularity is near


@dataclass(frozen=True)
class Uncertainty:
    """Noise-propagated 1-sigma pose uncertainty and the distance from a singularity.

    Attributes:
        translation: RMS length of the position error (m).
        rotation: RMS angle of the rotation error (rad).
        margin: ``cond(home) / cond(here)`` of the length-scaled 6x6 Jacobian.
    """

    translation: float
    rotation: float
    margin: float


@dataclass(frozen=True)
class SolveOutcome:
    """One solved reading set.

    Attributes:
        pose: 4x4 base -> platform (m), or ``None`` when the solve failed.
        q: the configuration of the solution (``None`` when failed).
        status: ``ok`` (no flag), ``flagged`` (a pose, see ``flags``) or ``failed``.
        flags: tracker flags (``jump``, ``branch_uncertain``, ``near_singular``,
            ``out_of_limits``, ``not_converged``) and the solver status of a failed solve.
        iterations: Newton steps.
        uncertainty: of the pose (``None`` when failed).
        solve_time: seconds spent (prediction, solve, uncertainty).
    """

    pose: np.ndarray | None
    q: np.ndarray | None
    status: str
    flags: tuple[str, ...]
    iterations: int
    uncertainty: Uncertainty | None
    solve_time: float


class PoseSolver:
    """Readings of one fixture in, tracked poses with flags and uncertainty out.

    Args:
        hexa: the fixture's hexapod.
        noise: 1-sigma reading noise (m).
        predictor: the tracker's predictor.
        initial: configuration ``q`` to start from (a recovered lock pose); default home.
        confirm_samples: samples without a jump before a ``branch_uncertain`` doubt is re-checked.
    """

    def __init__(self, hexa: Hexapod, noise: float, predictor: str = "eq22", initial=None, confirm_samples: int = 5):
        self.hexa, self.noise, self.confirm_samples = hexa, float(noise), confirm_samples
        self.length = characteristic_length(hexa)
        clm, m = hexa.closed_loop, hexa.closed_loop.model
        self._evaluator = NewtonSolver(clm, ())
        self._rows = 6 if clm.kind == "6d" else 3
        self._leg_cols = np.array([[m.joints[j].idx_v for j in leg.joints] for leg in clm.legs], dtype=np.int64)
        self._leg_pos = np.array([leg.joints.index(leg.prismatic) for leg in clm.legs], dtype=np.int64)
        self._ff = np.arange(clm.platform_v, clm.platform_v + 6, dtype=np.int64)
        self._scale = np.array([1.0, 1.0, 1.0, self.length, self.length, self.length])
        self._cond_home = self._measure(hexa.q_home)[2]
        q0 = hexa.q_home if initial is None else np.asarray(initial, dtype=float)
        u = self.uncertainty(q0)
        pose_rms = float(np.hypot(u.translation, self.length * u.rotation)) if np.isfinite(u.translation) else 0.0
        floor = max(1e-6 * self.length, JUMP_NOISE_FACTOR * pose_rms)
        self.tracker = Tracker(hexa, predictor, initial=q0, jump_floor=floor, length=self.length)
        self._good_q = np.array(q0, dtype=float)
        self._u_at: tuple[np.ndarray, Uncertainty] | None = None  # last computed uncertainty, where
        self._restart = False
        self._doubt = False
        self._consistent = 0

    def _jacobian(self, q: np.ndarray) -> np.ndarray:
        """Closure Jacobian at ``q`` with a column for every joint velocity (the legs' included)."""
        return self._evaluator.evaluate(np.asarray(q, dtype=float))[1]

    def propagation(self, q: np.ndarray) -> np.ndarray:
        """``X`` (6x6): platform twist ``[v; w]`` (platform frame) per unit reading change, at ``q``.

        The inverse of :func:`hexapod_model.analysis.jacobian.leg_jacobian_local` (NaN when singular).
        """
        X = np.empty((6, 6))
        self._measure(q, X)
        return X

    def _measure(self, q: np.ndarray, X: np.ndarray | None = None) -> tuple[float, float, float]:
        G = self._jacobian(q)
        return _propagate(G, self._rows, self._leg_cols, self._leg_pos, self._ff, self._scale, X)

    def uncertainty(self, q: np.ndarray) -> Uncertainty:
        """1-sigma pose uncertainty at configuration ``q`` (inf and margin 0 when singular)."""
        t, r, cond = self._measure(q)
        if not cond < np.inf:
            return Uncertainty(float("inf"), float("inf"), 0.0)
        return Uncertainty(self.noise * t, self.noise * r, self._cond_home / cond)

    def _uncertainty_at(self, pose: np.ndarray, q: np.ndarray) -> Uncertainty:
        """:meth:`uncertainty`, reused near the pose where it was last computed (see module doc)."""
        if self._u_at is not None:
            T, u = self._u_at
            dp = pose[:3, 3] - T[:3, 3]
            cos = 0.5 * (float(np.sum(pose[:3, :3] * T[:3, :3])) - 1.0)
            if u.margin > REUSE_MARGIN and float(dp @ dp) < REUSE_M**2 and cos > REUSE_COS:
                return u
        u = self.uncertainty(q)
        self._u_at = (pose, u)
        return u

    def gap(self) -> None:
        """Reading sets were skipped: the next step restarts the predictor from the last good pose."""
        self._restart = True

    def solve_once(self, readings: np.ndarray, q: np.ndarray) -> Solution:
        """A single solve from ``q`` (no tracking), never raising: see ``status``."""
        return self.hexa.forward(readings, guess=q, tol=self.tracker.tol, check=False)

    def step(self, readings: np.ndarray) -> SolveOutcome:
        """Solve one complete reading set (m, leg order); never raises on a failed solve."""
        t0 = time.perf_counter()
        if self._restart:
            self.tracker.reset(self._good_q)
            self._restart = False
        r = self.tracker.step(readings)
        sol = r.solution
        if r.status == "failed":
            self._restart = True
            return SolveOutcome(None, None, "failed", (*r.flags, sol.status), sol.iterations, None, _since(t0))
        flags = [f for f in r.flags if f != "branch_uncertain"]
        if "jump" in flags:
            self._doubt, self._consistent = True, 0
        elif self._doubt:
            self._consistent += 1
            if self._consistent >= self.confirm_samples and self._confirm(readings, sol):
                self._doubt = False
            else:
                flags.append("branch_uncertain")
        if not flags:
            self._good_q = sol.q
        u = self._uncertainty_at(sol.pose, sol.q)
        status = "flagged" if flags else "ok"
        return SolveOutcome(sol.pose, sol.q, status, tuple(flags), sol.iterations, u, _since(t0))

    def _confirm(self, readings: np.ndarray, tracked: Solution) -> bool:
        """Solve again from the last good configuration; on agreement re-anchor the tracker there."""
        self._consistent = 0
        check = self.solve_once(readings, self._good_q)
        if check.status != "converged" or pose_distance(check.pose, tracked.pose, self.length) > AGREE:
            return False
        self.tracker.reset(tracked)
        return True


@njit(cache=True)
def _propagate(G, rows, leg_cols, leg_pos, ff, scale, X=None):  # pragma: no cover - compiled
    """Eliminate each leg's passive joints from ``G``, invert the 6x6 map, measure it.

    Per leg the square block ``L_i`` (all its joints) gives ``n_i`` with ``L_i^T n_i = e_leg``,
    and row ``i`` of ``J`` (``dl = J xi``) is ``-n_i^T A_i`` (``A_i``: the platform columns).
    Returns the Frobenius norms of the translation and rotation rows of ``X = J^-1`` and the
    condition number of ``diag(scale) X`` (``inf`` when singular); fills ``X`` when given.
    """
    J = np.empty((6, 6))
    L = np.empty((rows, rows))
    piv = np.empty(rows, dtype=np.int64)
    e, n = np.zeros(rows), np.empty(rows)
    for i in range(6):
        for a in range(rows):
            for b in range(rows):
                L[a, b] = G[i * rows + a, leg_cols[i, b]]
        if lu_factor(L, L, piv) == 0.0:
            return np.inf, np.inf, np.inf
        e[:] = 0.0
        e[leg_pos[i]] = 1.0
        lu_apply_transposed(L, piv, e, n)
        for c in range(6):
            s = 0.0
            for a in range(rows):
                s -= n[a] * G[i * rows + a, ff[c]]
            J[i, c] = s
    LU, pj = np.empty((6, 6)), np.empty(6, dtype=np.int64)
    if lu_factor(J, LU, pj) == 0.0:
        return np.inf, np.inf, np.inf
    Xi, col = np.empty((6, 6)), np.empty(6)
    for c in range(6):
        e6 = np.zeros(6)
        e6[c] = 1.0
        lu_apply(LU, pj, e6, col)
        Xi[:, c] = col
    if X is not None:
        X[:, :] = Xi
    t = np.sqrt(np.sum(Xi[:3] ** 2))
    r = np.sqrt(np.sum(Xi[3:] ** 2))
    for a in range(6):
        Xi[a] *= scale[a]
    sv = np.linalg.svd(Xi)[1]
    cond = sv[0] / sv[-1] if sv[-1] > 0.0 else np.inf
    return t, r, cond


def _since(t0: float) -> float:
    return time.perf_counter() - t0
