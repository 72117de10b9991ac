"""Poses in the robot's frame: the hexapod base placed in the cell, the coupling on the plate, and locating the base.

``fixture.toml``, per fixture::

    [fixtures.cell]
    base_in_robot = [0.85, -0.30, 0.02, 0.0, 0.0, 90.0]   # x, y, z (m), roll, pitch, yaw (deg)
    coupling = [0.0, 0.0, 0.012, 0.0, 0.0, 0.0]           # the tool-changer frame in the platform frame

``pose_in_robot = base_in_robot * pose * coupling``: where the robot finds the coupling. Its
sigma: the rotation's is the platform's (rigid frames do not change the RMS angle); the
translation's is that of the coupling's origin, ``v + w x c`` for the platform twist ``(v, w)``
(platform frame) and the coupling's offset ``c``, so it grows with ``|c|`` times the angular
uncertainty.

:func:`locate` estimates ``base_in_robot`` from points known in the base frame and touched by the
robot (least squares over three or more points, not all on one line), with the residuals.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...exceptions import InputError
from ...lie import matrix_to_rpy, xyz_rpy_to_pose
from ..record.pose import pose_record
from .table import Table


@dataclass(frozen=True)
class Cell:
    """A fixture's placement in the robot cell.

    Attributes:
        base_in_robot: 4x4 hexapod base frame in the robot's base frame (m).
        coupling: 4x4 tool-changer (coupling) frame in the platform frame (m); identity: the platform frame.
    """

    base_in_robot: np.ndarray
    coupling: np.ndarray

    def pose_in_robot(self, pose: np.ndarray) -> np.ndarray:
        """The coupling's 4x4 pose in the robot frame for a platform ``pose`` in the base frame."""
        return self.base_in_robot @ pose @ self.coupling

    @property
    def offset(self) -> np.ndarray:
        """(3,) the coupling's origin in the platform frame (m)."""
        return self.coupling[:3, 3]

    def translation_sigma(self, propagation: np.ndarray, noise: float) -> float:
        """RMS length (m) of the coupling origin's error: ``noise`` (m) through ``propagation`` (J^-1, 6x6)."""
        c = self.offset
        cross = np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])
        A = np.hstack([np.eye(3), -cross])  # v + w x c = v - [c]x w
        M = A @ propagation
        return float(noise * np.sqrt(np.sum(M * M)))


SIGMA_REUSE = (0.5e-3, math.radians(0.05))  # m, rad: the coupling's sigma is reused this close to where computed


class InRobot:
    """A record's ``pose_in_robot`` (``{"pose", "sigma"}``) for one fixture's cell.

    Args:
        cell: the placement.
        noise: 1-sigma reading noise (m).
        propagation: ``propagation(q)`` -> ``J^-1`` (6x6) at configuration ``q``.
    """

    def __init__(self, cell: Cell, noise: float, propagation: Callable[[np.ndarray], np.ndarray]):
        self.cell, self.noise, self.propagation = cell, noise, propagation
        self._cached: tuple[np.ndarray, float] | None = None  # (pose, coupling translation sigma m)

    def record(self, pose: np.ndarray, q: np.ndarray | None, sigma: dict | None) -> dict:
        """``{"pose", "sigma"}`` for a solved ``pose`` (4x4 base -> platform, m) at configuration ``q``.

        ``sigma`` is the record's (``translation_mm``, ``rotation_deg``; None without one).
        """
        cell = self.cell
        out: dict = {"pose": pose_record(cell.pose_in_robot(pose)), "sigma": None}
        if sigma is None or q is None:
            return out
        translation = sigma["translation_mm"] * 1e-3
        if np.any(cell.offset != 0.0):  # the coupling's origin moves with the platform's rotation error too
            cached = self._cached
            if cached is None or not _near(cached[0], pose):
                X = self.propagation(q)
                self._cached = cached = (pose.copy(), cell.translation_sigma(X, self.noise))
            translation = cached[1]
        out["sigma"] = {"translation_mm": translation * 1e3, "rotation_deg": sigma["rotation_deg"]}
        return out


def _near(a: np.ndarray, b: np.ndarray) -> bool:
    """Within :data:`SIGMA_REUSE` of each other (4x4 poses)."""
    if np.linalg.norm(a[:3, 3] - b[:3, 3]) > SIGMA_REUSE[0]:
        return False
    return float(np.linalg.norm(pin.log3(a[:3, :3].T @ b[:3, :3]))) <= SIGMA_REUSE[1]


@dataclass(frozen=True)
class Located:
    """The base's placement estimated from touched points.

    Attributes:
        base_in_robot: 4x4 (m).
        residuals: (n,) distance (m) of each touched point from its placed base point.
        rms: RMS of the residuals (m).
    """

    base_in_robot: np.ndarray
    residuals: np.ndarray
    rms: float

    @property
    def values(self) -> list[float]:
        """``[x, y, z, roll, pitch, yaw]`` (m, deg): the ``base_in_robot`` of ``fixture.toml``."""
        T = self.base_in_robot
        return [*map(float, T[:3, 3]), *map(float, np.degrees(matrix_to_rpy(T[:3, :3])))]


def _placement_field(t: Table, key: str, default: list[float] | None = None) -> list[float]:
    v = t.take(key, default)
    ok = isinstance(v, list) and len(v) == 6
    ok = ok and all(not isinstance(x, bool) and isinstance(x, (int, float)) and math.isfinite(x) for x in v)
    if not ok or max(abs(x) for x in v[:3]) > 100.0:
        raise t.error(key, v, "expected [x, y, z, roll, pitch, yaw] in m (within 100) and degrees")
    return [float(x) for x in v]


def cell_from_table(t: Table) -> Cell:
    """``[fixtures.cell]`` of ``fixture.toml``: ``base_in_robot`` (required) and ``coupling`` (default none)."""
    cell = Cell(
        xyz_rpy_to_pose(_placement_field(t, "base_in_robot")),
        xyz_rpy_to_pose(_placement_field(t, "coupling", [0.0] * 6)),
    )
    t.finish()
    return cell


def locate(base_points: np.ndarray, robot_points: np.ndarray) -> Located:
    """Least-squares rigid placement ``T`` with ``robot = T base`` (Kabsch / Horn, proper rotation).

    Args:
        base_points: (n, 3) points in the hexapod's base frame (m), e.g. the base joint centres.
        robot_points: (n, 3) the same points touched by the robot, in its base frame (m).

    Raises:
        InputError: fewer than three points, shapes that differ, non-finite values, or points all
            on one line (the rotation about it is then unknown).
    """
    a, b = np.asarray(base_points, dtype=float), np.asarray(robot_points, dtype=float)
    if a.ndim != 2 or a.shape[1] != 3 or a.shape != b.shape:
        raise InputError("points", (a.shape, b.shape), "expected two (n, 3) arrays of the same n")
    if len(a) < 3:
        raise InputError("points", len(a), "at least three touched points are needed")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise InputError("points", "NaN/inf", "every coordinate must be finite")
    ca, cb = a.mean(0), b.mean(0)
    spread = np.linalg.svd(a - ca, compute_uv=False)
    if spread[1] <= 1e-6 * max(spread[0], 1e-12):
        raise InputError("points", a.tolist(), "the base points lie on one line: touch a point off it")
    U, _, Vt = np.linalg.svd((b - cb).T @ (a - ca))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    T = np.eye(4)
    T[:3, :3] = U @ D @ Vt
    T[:3, 3] = cb - T[:3, :3] @ ca
    residuals = np.linalg.norm(b - (a @ T[:3, :3].T + T[:3, 3]), axis=1)
    return Located(T, residuals, float(np.sqrt(np.mean(residuals**2))))
