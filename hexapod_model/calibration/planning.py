"""Choose the poses a calibration should measure: the best-conditioned identification.

Candidates are random poses of a box around home (the +-50 mm / +-25 deg test box by default)
that the nominal hexapod reaches within its stroke and joint limits. Each candidate
contributes 6 rows (its pose residual, whitened by the stated noise) to the identification
Jacobian, in scaled parameters with the frame convention applied and both frames unknown
(:mod:`~hexapod_model.calibration.identifiability`). Poses are picked greedily, each
maximising ``log det`` of the information matrix (D-optimality; the determinant lemma gives
every candidate's gain from one 6 x 6 determinant).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analysis.trajectories import box_poses
from ..description.geometry import HexapodGeometry
from ..exceptions import InputError
from ..lie import log3
from .derivatives import CalibrationModel
from .frames import Noise, frame_jacobian, twist_jacobian
from .identifiability import frame_free, free_basis
from .parameters import ParameterSet
from .problem import FRAME_SCALE


@dataclass(frozen=True)
class Plan:
    """Poses to visit (a robot program's order: each the nearest unvisited one).

    Attributes:
        poses: (n, 4, 4) platform poses in the base frame (m).
        readings: (n, 6) the nominal hexapod's readings there (m).
        candidates: how many reachable candidates the poses were chosen from.
        singular_values: of the scaled identification Jacobian of the plan, descending (a
            combination's 1-sigma is the inverse, in expected magnitudes of its parameters).
        singular_values_random: the same for as many random candidates (for comparison).
    """

    poses: np.ndarray
    readings: np.ndarray
    candidates: int
    singular_values: np.ndarray
    singular_values_random: np.ndarray


def _blocks(ps: ParameterSet, poses: np.ndarray, noise: Noise) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per reachable pose: its (6, P) scaled geometry rows and (6, 12) frame rows; the ok mask."""
    model = CalibrationModel(ps, np.zeros(ps.size))
    hexa = model.hexapod
    geo, frames, ok = [], [], np.zeros(len(poses), bool)
    eye = np.eye(4)[None]
    for k, T in enumerate(poses):
        ik = hexa.inverse(T, check=False)
        if not ik.converged:
            continue
        sol = hexa.forward(ik.lengths, guess=ik.q, check=False)
        if not sol.converged or sol.jacobian is None:
            continue
        ok[k] = True
        J = twist_jacobian(T[None], eye, T[None], noise)[0]
        geo.append(J @ model.pose_jacobian(sol.q, sol.jacobian) * ps.scales)
        frames.append(frame_jacobian(eye[0], T[None], eye[0], T[None], noise)[0] * FRAME_SCALE)
    return np.array(geo), np.array(frames), ok


def singular_values(geo: np.ndarray, frames: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """Singular values of stacked rows (gauge fixed, frames projected out), descending."""
    J = frame_free(geo.reshape(-1, geo.shape[-1]), frames.reshape(-1, 12)) @ basis
    return np.linalg.svd(np.linalg.qr(J, mode="r"), compute_uv=False)


def plan_poses(
    nominal: HexapodGeometry,
    n: int,
    candidates: int = 2000,
    seed: int = 0,
    noise: Noise = Noise(),
    translation: float = 0.05,
    angle_deg: float = 25.0,
) -> Plan:
    """Choose ``n`` of ``candidates`` random reachable poses for the best-conditioned identification.

    Raises:
        InputError: ``n`` too small for the unknowns, or fewer reachable candidates than ``n``.
    """
    ps = ParameterSet(nominal)
    need = int(np.ceil(2 * ps.size / 6))
    if n < need:
        raise InputError("--plan", n, f"{ps.size} unknowns need at least {need} poses (2 equations per unknown)")
    if candidates < n:
        raise InputError("candidates", candidates, f"need at least as many candidates as poses ({n})")
    home = np.eye(4)
    home[:3, 3] = nominal.home_translation
    drawn = box_poses(home, candidates, seed=seed, translation=translation, angle_deg=angle_deg)
    geo, frames, ok = _blocks(ps, drawn, noise)
    poses = drawn[ok]
    if len(poses) < n:
        raise InputError("--plan", n, f"only {len(poses)} of {candidates} candidate poses are reachable")
    basis = free_basis(ps.gauge_constraints() * ps.scales, (), ps.size)
    B = np.concatenate([geo @ basis, frames], axis=2)  # (K, 6, m)
    info = 1e-6 * np.eye(B.shape[2])
    chosen: list[int] = []
    free = np.ones(len(B), bool)
    for _ in range(n):
        T = B @ np.linalg.inv(info)  # (K, 6, m)
        gain = np.linalg.slogdet(np.eye(6) + T @ np.swapaxes(B, 1, 2))[1]
        gain[~free] = -np.inf
        k = int(np.argmax(gain))
        chosen.append(k)
        free[k] = False
        info += B[k].T @ B[k]
    order = _visiting_order(poses[chosen])
    chosen = [chosen[k] for k in order]
    random = np.random.default_rng(seed + 1).choice(len(poses), n, replace=False)
    model = CalibrationModel(ps, np.zeros(ps.size)).hexapod
    readings = np.array([model.inverse(T).lengths for T in poses[chosen]])
    return Plan(
        poses[chosen],
        readings,
        len(poses),
        singular_values(geo[chosen], frames[chosen], basis),
        singular_values(geo[random], frames[random], basis),
    )


def _visiting_order(poses: np.ndarray) -> list[int]:
    """Nearest-neighbour tour from the pose closest to home (position in m plus 0.1 m per rad)."""
    x = np.hstack([poses[:, :3, 3], 0.1 * log3(poses[:, :3, :3])])
    left = list(range(len(x)))
    order = [left.pop(int(np.argmin(np.linalg.norm(x[:, :3] - np.mean(x[:, :3], axis=0), axis=1))))]
    while left:
        k = int(np.argmin(np.linalg.norm(x[left] - x[order[-1]], axis=1)))
        order.append(left.pop(k))
    return order
