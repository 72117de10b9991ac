"""The stream tracker's vocabulary: predictors, pose distances, the per-sample result.

Predictors are Jakobović and Jelenković's eqs. 22-24; :class:`TrackResult` is what clients (the CLI, the
fixture service) read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import InputError
from ..kinematics.hexapod import Hexapod
from ..kinematics.newton.solver import Solution

PREDICTORS = ("none", "eq22", "eq23", "eq24")
# X - P0 = sum_k a_k (P_k - P0), k = 1, 2
_COEFFS = {"none": (0.0, 0.0), "eq22": (-1.0, 0.0), "eq23": (0.0, -0.5), "eq24": (0.5, -0.75)}

#: every flag a sample can carry, in the order they are checked
FLAGS = (
    "jump",
    "stuck",
    "branch_uncertain",
    "settling",
    "near_singular",
    "out_of_limits",
    "cone_limit",
    "collision",
    "imprecise",
    "inconsistent_readings",  # redundant sensors: the readings fail their consistency test
)
#: statuses of a sample without a pose (``status`` is ``ok`` otherwise)
FAILED_STATUSES = ("invalid_input", "max_iterations", "not_found", "singular", "out_of_limits")
#: solve statuses that give the tracker a closed configuration (``uncertified``: flagged
#: ``branch_uncertain``, its assembly is the tracker's passage logic's to judge)
POSED_STATUSES = ("converged", "out_of_limits", "uncertified")


def posed(sol: Solution) -> bool:
    """Whether a solve gives the tracker a pose: a closed configuration of :data:`POSED_STATUSES`."""
    return sol.status in POSED_STATUSES and sol.closed


def characteristic_length(hexa: Hexapod) -> float:
    """Largest horizontal base anchor radius (m); for a URDF, of the legs' first joints."""
    g = hexa.geometry
    if g is not None:
        return float(np.max(np.linalg.norm(g.base_points()[:, :2], axis=1)))
    m = hexa.model
    pts = np.array([m.jointPlacements[leg.joints[0]].translation for leg in hexa.closed_loop.legs])
    return float(np.max(np.linalg.norm(pts[:, :2], axis=1))) or 0.25


def predictor_weights(predictor: str, samples: int) -> tuple[float, float]:
    """``(a1, a2)`` of ``X - P0 = a1 (P1 - P0) + a2 (P2 - P0)`` for ``predictor`` with ``samples`` in the history.

    With fewer samples than the predictor needs, the highest-order predictor the history
    allows is used (``eq24``/``eq23`` fall back to ``eq22``, which falls back to ``none``).
    """
    if predictor not in _COEFFS:
        raise InputError("predictor", predictor, f"choose one of {PREDICTORS}")
    if samples < 3 and predictor in ("eq23", "eq24"):
        predictor = "eq22"
    if samples < 2:
        predictor = "none"
    return _COEFFS[predictor]


def predict(model: pin.Model, history, predictor: str) -> np.ndarray:
    """Predicted configuration from ``history = [P0, P1, P2, ...]`` (newest first).

    With fewer samples than the predictor needs, the highest-order predictor the history
    allows is used (:func:`predictor_weights`).
    """
    a1, a2 = predictor_weights(predictor, len(history))
    p0 = history[0]
    if a1 == 0.0 and a2 == 0.0:
        return p0.copy()
    # dv = 0 + a1 d1 + a2 d2 in place: 0 + x is x but for -0 (+0): the "+= 0.0" below
    dv = pin.difference(model, p0, history[1] if a1 else history[2])
    dv *= a1 if a1 else a2
    dv += 0.0
    if a1 and a2:
        d2 = pin.difference(model, p0, history[2])
        d2 *= a2
        dv += d2
    return pin.integrate(model, p0, dv)


def predictor_layout(model: pin.Model) -> tuple[np.ndarray, np.ndarray, int, int] | None:
    """``(q_idx, v_idx, ffq, ffv)`` of :func:`.kernels.predict_into` for ``model``, or None.

    None unless every joint of ``model`` is a one-dof one (``nq == nv == 1``: the difference and
    the integration add) or its one free flyer: :func:`predict` (Pinocchio's) serves the others.
    """
    q_idx, v_idx, free_flyers = [], [], []
    for joint in list(model.joints)[1:]:
        if joint.nq == 1 and joint.nv == 1:
            q_idx.append(joint.idx_q)
            v_idx.append(joint.idx_v)
        elif joint.shortname() == "JointModelFreeFlyer":
            free_flyers.append((joint.idx_q, joint.idx_v))
        else:
            return None
    if len(free_flyers) != 1:
        return None
    (ffq, ffv), ints = free_flyers[0], np.int64
    return np.array(q_idx, dtype=ints), np.array(v_idx, dtype=ints), int(ffq), int(ffv)


@dataclass(frozen=True)
class TrackResult:
    """One tracked sample.

    A sample is *good* (:attr:`ok`) when ``status == "ok"`` and ``flags`` is empty; then its
    pose passed every check. With flags the pose is solved but must not be used blindly;
    without a pose (``status`` in :data:`FAILED_STATUSES`) :attr:`pose` is the last one.

    Attributes:
        solution: the solver's :class:`Solution` (pose 4x4 base -> platform, m).
        status: ``"ok"`` (a solved pose) or the failure's name (:data:`FAILED_STATUSES`).
        flags: subset of :data:`FLAGS`, in that order.
        legs: legs (0-based) named by ``jump`` or ``stuck``.
        innovation: largest normalised reading innovation ``|l - l^| / (noise * spread)``
            (``nan`` when the motion model was not available).
        sigma_translation: 1-sigma position uncertainty (m): ``noise * sqrt(trace)`` of the
            position block of ``J^-1 J^-T`` (``nan`` without a pose, ``inf`` when singular).
        sigma_rotation: 1-sigma orientation uncertainty (rad), likewise.
        condition_number: of the eliminated 6x6 Jacobian, rotations scaled by the tracker's length.
        singularity_margin: home condition number / ``condition_number`` (1 at home, 0 singular).
        solve_time: wall-clock seconds of the whole step.
    """

    solution: Solution
    status: str
    flags: tuple[str, ...]
    legs: tuple[int, ...]
    innovation: float
    sigma_translation: float
    sigma_rotation: float
    condition_number: float
    singularity_margin: float
    solve_time: float

    @property
    def ok(self) -> bool:
        """True when the pose is solved and passed every check (no flag)."""
        return self.status == "ok" and not self.flags

    @property
    def failed(self) -> bool:
        """True when the sample has no pose of its own."""
        return self.status != "ok"

    @property
    def pose(self) -> np.ndarray:
        """Platform pose of the sample (4x4, base frame, metres)."""
        return self.solution.pose

    @property
    def iterations(self) -> int:
        """Newton steps of the sample's solve."""
        return self.solution.iterations


def track_result(
    solution: Solution,
    status: str,
    flags: tuple[str, ...],
    legs: tuple[int, ...],
    innovation: float,
    sigma_translation: float,
    sigma_rotation: float,
    condition_number: float,
    singularity_margin: float,
    solve_time: float,
) -> TrackResult:
    """``TrackResult(...)`` of these fields, filled at once (the tracker's per-sample result).

    The same frozen object as the dataclass's ``__init__`` makes (equal, immutable), without its
    one ``object.__setattr__`` call per field.
    """
    r = _new(TrackResult)
    r.__dict__.update(
        solution=solution,
        status=status,
        flags=flags,
        legs=legs,
        innovation=innovation,
        sigma_translation=sigma_translation,
        sigma_rotation=sigma_rotation,
        condition_number=condition_number,
        singularity_margin=singularity_margin,
        solve_time=solve_time,
    )
    return r


_new = object.__new__
