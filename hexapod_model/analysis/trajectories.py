"""Test trajectories (Jakobović and Jelenković 2002, eqs. 20-21) and the +-50 mm / +-25 deg box (Bem et al. 2026).

Angles follow Jakobović and Jelenković (2002): roll-pitch-yaw ``alpha, beta, gamma`` about fixed x, y, z, so
``R = Rz(gamma) Ry(beta) Rx(alpha)``. Jakobović and Jelenković's positions are in the units of its model 1
(base radius 50); :func:`trajectory_poses` scales them by ``scale`` (metres per paper unit)
and centres them on the hexapod's home pose.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import InputError
from ..lie import rpy_to_matrix

DURATION_S = 4.0


def trajectory_coordinates(name: str, t: np.ndarray) -> np.ndarray:
    """(n, 6) paper coordinates ``x, y, z - z0`` (paper units) and ``alpha, beta, gamma`` (deg).

    ``z0`` (7 for A, 8 for B) is the paper's home height; it is removed so the trajectory can
    be centred on any hexapod's home. ``t`` in seconds, ``0 <= t <= 4``.
    """
    t = np.asarray(t, dtype=float)
    if name == "A":
        z, a, b = 1.5 * np.sin(2 * t), 25 * np.sin(1.8 * t), 20 * np.sin(t / 2) + 5 * np.cos(4 * t)
    elif name == "B":
        z, a, b = 3 * np.sin(2 * t), 55 * np.sin(1.8 * t), 30 * np.sin(t / 2) + 5 * np.cos(4 * t)
    else:
        raise InputError("trajectory", name, "Jakobović and Jelenković (2002) defines 'A' and 'B'")
    return np.stack([2 * np.sin(t * np.pi / 2), 2.2 * np.cos(t * np.pi / 2), z, a, b, 15 * np.arctan(2 * t - 4)], -1)


def trajectory_poses(
    name: str, home: np.ndarray, scale: float, rate_hz: float = 1000.0, speed: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    """Sample trajectory ``name`` at ``rate_hz``; returns times (s) and (n, 4, 4) poses.

    ``speed`` > 1 runs the same path faster (Jakobović and Jelenković (2002) accelerates B by 2, 4 and 8).
    """
    t = np.arange(0.0, DURATION_S / speed + 0.5 / rate_hz, 1.0 / rate_hz)
    c = trajectory_coordinates(name, np.minimum(t * speed, DURATION_S))
    poses = np.tile(np.eye(4), (len(t), 1, 1))
    poses[:, :3, :3] = home[:3, :3] @ rpy_to_matrix(*np.radians(c[:, 3:6]).T)
    poses[:, :3, 3] = home[:3, 3] + scale * c[:, :3]
    return t, poses


def box_poses(
    home: np.ndarray, n: int, seed: int = 0, translation: float = 0.05, angle_deg: float = 25.0
) -> np.ndarray:
    """Random poses in a box around home.

    (n, 4, 4) random poses: home + uniform translation in +-``translation`` (m) and
    roll/pitch/yaw uniform in +-``angle_deg`` (Bem et al. (2026) §5.2).
    """
    rng = np.random.default_rng(seed)
    d = rng.uniform(-translation, translation, (n, 3))
    a = np.radians(rng.uniform(-angle_deg, angle_deg, (n, 3)))
    poses = np.tile(np.eye(4), (n, 1, 1))
    poses[:, :3, :3] = home[:3, :3] @ rpy_to_matrix(a[:, 0], a[:, 1], a[:, 2])
    poses[:, :3, 3] = home[:3, 3] + d
    return poses
