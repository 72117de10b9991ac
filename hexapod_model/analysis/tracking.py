"""Tracking a stream of leg readings (seed 002 §V): warm starts, predictors, branch safety.

Each sample is solved by Newton from a *predicted* configuration built from the last
solutions ``P0`` (newest), ``P1``, ``P2``:

* ``none``: ``X = P0``;
* ``eq22``: ``X = 2 P0 - P1``;
* ``eq23``: ``X = 1.5 P0 - 0.5 P2``;
* ``eq24``: ``T1 = (P0 + P1)/2, T2 = (P1 + P2)/2, X = 2.5 T1 - 1.5 T2``.

The seed applies them to pose coordinates; here they act on the whole Pinocchio configuration
(platform free flyer and every leg joint) in the tangent space at ``P0``:
``X = P0 (+) sum_k a_k (P_k (-) P0)`` with ``pin.integrate`` / ``pin.difference``, so the
quaternion stays a unit quaternion and a constant-twist motion is predicted exactly.

Branch safety without the truth: a sample is *flagged* (never silently returned as fine) when

* ``jump``: the solution is farther from the linear extrapolation ``2 P0 - P1`` than
  ``jump_ratio`` times the last step plus ``jump_floor`` (a velocity discontinuity, the
  signature of a switch to another assembly branch at a bifurcation);
* ``near_singular``: the condition number of the direct-kinematics constraint Jacobian exceeds
  ``cond_limit`` (by default ``cond_factor`` times its value at home): a bifurcation is near and
  the solution may be the wrong one even if no jump is visible;
* ``branch_uncertain``: every sample after a ``jump``, until :meth:`Tracker.reset` re-anchors
  the tracker on a known configuration (a wrong branch is smooth and self-consistent once
  taken, so the doubt must persist);
* ``out_of_limits``: converged, but a joint is outside its limits (``Solution.status``);
* ``not_converged``: the solve failed (status ``failed``; the history is not updated).

Pose distances use metres with rotations scaled by a characteristic length ``length`` (m per
rad; default: the largest base anchor radius).
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import HexapodError, InputError
from ..kinematics.hexapod import Hexapod
from ..kinematics.solver import Solution

PREDICTORS = ("none", "eq22", "eq23", "eq24")
# X - P0 = sum_k a_k (P_k - P0), k = 1, 2
_COEFFS = {"none": (0.0, 0.0), "eq22": (-1.0, 0.0), "eq23": (0.0, -0.5), "eq24": (0.5, -0.75)}


def characteristic_length(hexa: Hexapod) -> float:
    """Largest horizontal base anchor radius (m); for a URDF, of the legs' first joints."""
    g = hexa.geometry
    if g is not None:
        return float(np.max(np.linalg.norm(g.base_points()[:, :2], axis=1)))
    m = hexa.model
    pts = np.array([m.jointPlacements[leg.joints[0]].translation for leg in hexa.closed_loop.legs])
    return float(np.max(np.linalg.norm(pts[:, :2], axis=1))) or 0.25


def predict(model: pin.Model, history, predictor: str) -> np.ndarray:
    """Predicted configuration from ``history = [P0, P1, P2, ...]`` (newest first).

    With fewer samples than the predictor needs, the highest-order predictor the history
    allows is used (``eq24``/``eq23`` fall back to ``eq22``, which falls back to ``none``).
    """
    if predictor not in _COEFFS:
        raise InputError("predictor", predictor, f"choose one of {PREDICTORS}")
    if len(history) < 3 and predictor in ("eq23", "eq24"):
        predictor = "eq22"
    if len(history) < 2:
        predictor = "none"
    a1, a2 = _COEFFS[predictor]
    p0 = history[0]
    if a1 == 0.0 and a2 == 0.0:
        return p0.copy()
    dv = np.zeros(model.nv)
    if a1:
        dv += a1 * pin.difference(model, p0, history[1])
    if a2:
        dv += a2 * pin.difference(model, p0, history[2])
    return pin.integrate(model, p0, dv)


def pose_distance(Ta: np.ndarray, Tb: np.ndarray, length: float) -> float:
    """``sqrt(|dt|^2 + (length * angle)^2)`` between two 4x4 poses (m)."""
    M = pin.SE3(Ta[:3, :3], Ta[:3, 3]).inverse() * pin.SE3(Tb[:3, :3], Tb[:3, 3])
    xi = pin.log6(M).vector
    return float(np.hypot(np.linalg.norm(Ta[:3, :3] @ xi[:3]), length * np.linalg.norm(xi[3:])))


@dataclass(frozen=True)
class TrackResult:
    """One tracked sample.

    Attributes:
        solution: the solver's :class:`Solution` (pose 4x4 base -> platform, m).
        status: ``"ok"`` (no flag), ``"flagged"`` (a pose, but see ``flags``) or ``"failed"``.
        flags: subset of ``jump``, ``branch_uncertain``, ``near_singular``, ``out_of_limits``, ``not_converged``.
        jump: distance (m, rotations scaled) between the solution and ``2 P0 - P1``.
        allowed_jump: the bound ``jump`` was checked against (``inf`` before two samples).
        condition_number: of the direct-kinematics constraint Jacobian.
        solve_time: wall-clock seconds of prediction + solve.
    """

    solution: Solution
    status: str
    flags: tuple[str, ...]
    jump: float
    allowed_jump: float
    condition_number: float
    solve_time: float

    @property
    def ok(self) -> bool:
        """True when the sample's status is ``ok`` (no failure, no flag)."""
        return self.status == "ok"

    @property
    def pose(self) -> np.ndarray:
        """Platform pose of the sample (4x4, base frame, metres)."""
        return self.solution.pose


class Tracker:
    """Solve a stream of readings, each from a predicted guess, and flag doubtful samples.

    Args:
        hexa: the hexapod.
        predictor: one of :data:`PREDICTORS`.
        initial: known starting configuration (``Solution`` or ``q``); default home.
        tol, max_iter: Newton settings per sample.
        jump_ratio, jump_floor: the ``jump`` flag bound ``jump_ratio * step + jump_floor``
            (``jump_floor`` in m; default ``1e-6 * length``).
        cond_limit: ``near_singular`` bound; default ``cond_factor`` x the home value.
        length: m per rad in pose distances (default :func:`characteristic_length`).
    """

    def __init__(
        self,
        hexa: Hexapod,
        predictor: str = "eq22",
        initial=None,
        *,
        tol: float = 1e-10,
        max_iter: int = 20,
        jump_ratio: float = 0.5,
        jump_floor: float | None = None,
        cond_limit: float | None = None,
        cond_factor: float = 100.0,
        length: float | None = None,
    ):
        if predictor not in PREDICTORS:
            raise InputError("predictor", predictor, f"choose one of {PREDICTORS}")
        self.hexa, self.predictor, self.tol, self.max_iter = hexa, predictor, tol, max_iter
        self.length = characteristic_length(hexa) if length is None else float(length)
        self.jump_ratio = jump_ratio
        self.jump_floor = 1e-6 * self.length if jump_floor is None else jump_floor
        if cond_limit is None:
            home = hexa.forward(np.zeros(6))
            cond_limit = cond_factor * home.condition_number
        self.cond_limit = float(cond_limit)
        self._history: deque[np.ndarray] = deque(maxlen=3)
        self.reset(initial)

    def reset(self, initial=None) -> None:
        """Forget the history; restart from ``initial`` (``Solution``, ``q`` or home)."""
        self._history.clear()
        self._solved = 0
        self._uncertain = False
        if initial is None:
            q = self.hexa.q_home
        elif isinstance(initial, Solution):
            q = initial.q.copy()
        else:
            q = np.asarray(initial, dtype=float).copy()
        self._history.appendleft(q)

    def step(self, lengths) -> TrackResult:
        """Solve one sample (readings in m). Never raises on a failed solve: see ``status``."""
        model = self.hexa.model
        t0 = time.perf_counter()
        guess = predict(model, list(self._history), self.predictor)
        try:
            sol = self.hexa.forward(lengths, guess=guess, tol=self.tol, max_iter=self.max_iter, check=False)
        except HexapodError as exc:  # readings outside the stroke, NaN, ...
            q = self._history[0]
            sol = Solution(
                self.hexa.pose_of(q),
                q.copy(),
                np.asarray(lengths, dtype=float),
                "invalid_input",
                0,
                float("nan"),
                None,
                str(exc),
            )
        elapsed = time.perf_counter() - t0
        flags: list[str] = []
        if sol.status not in ("converged", "out_of_limits"):
            return TrackResult(sol, "failed", ("not_converged",), float("nan"), float("nan"), float("nan"), elapsed)
        if sol.status == "out_of_limits":
            flags.append("out_of_limits")
        jump, allowed = 0.0, float("inf")
        if self._solved >= 2:
            pose_of = self.hexa.pose_of
            p0, p1 = pose_of(self._history[0]), pose_of(self._history[1])
            lin = pose_of(predict(model, list(self._history)[:2], "eq22"))
            jump = pose_distance(lin, sol.pose, self.length)
            allowed = self.jump_ratio * pose_distance(p1, p0, self.length) + self.jump_floor
            if jump > allowed:
                flags.append("jump")
                self._uncertain = True
        if self._uncertain and "jump" not in flags:
            flags.append("branch_uncertain")
        cond = sol.condition_number
        if not cond <= self.cond_limit:
            flags.append("near_singular")
        self._history.appendleft(sol.q)
        self._solved += 1
        return TrackResult(sol, "flagged" if flags else "ok", tuple(flags), jump, allowed, cond, elapsed)
