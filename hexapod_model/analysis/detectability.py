"""The smallest fault of each reading that redundant sensors detect, over a workspace section.

For a hexapod with measuring legs or an inclinometer (:attr:`hexapod_model.Hexapod.redundancy`),
the minimal detectable bias of reading ``j`` at a pose is ``sigma_j sqrt(lambda0 / P_jj)``
(:mod:`hexapod_model.kinematics.consistency`): the bias the chi-square test at false-alarm
rate ``alpha`` detects with probability ``power``. It depends on the pose through the
Jacobian; :func:`detectability_map` evaluates it on a grid of platform positions at one
height and orientation (``hexapod evaluate --detectability``, docs/redundancy.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import InputError, SolverError
from ..kinematics.consistency import DEFAULT_ALPHA, DEFAULT_POWER, minimal_detectable_bias
from ..kinematics.hexapod import Hexapod

DEFAULT_HALF_WIDTH = 0.05  # m: the section spans home +- this in x and y
DEFAULT_GRID = 21  # points along x and along y


@dataclass(frozen=True)
class DetectabilityMap:
    """Minimal detectable biases on a horizontal section of the workspace.

    Attributes:
        names: the readings, reading order.
        xs: (nx,) platform x positions (m, base frame).
        ys: (ny,) platform y positions (m, base frame).
        z: the section's platform height (m, base frame).
        mdb: (ny, nx, m) minimal detectable bias of each reading (m for legs, rad for tilts;
            nan outside the workspace).
        alpha: false-alarm rate of the test.
        power: detection probability.
    """

    names: tuple[str, ...]
    xs: np.ndarray
    ys: np.ndarray
    z: float
    mdb: np.ndarray
    alpha: float
    power: float

    def summary(self) -> list[tuple[str, float, float, float]]:
        """``(name, smallest, median, largest)`` minimal detectable bias of each reading over the section."""
        out = []
        for j, name in enumerate(self.names):
            v = self.mdb[:, :, j]
            v = v[np.isfinite(v)]
            if v.size == 0:
                out.append((name, float("nan"), float("nan"), float("nan")))
            else:
                out.append((name, float(np.min(v)), float(np.median(v)), float(np.max(v))))
        return out


def detectability_map(
    hexa: Hexapod,
    half_width: float = DEFAULT_HALF_WIDTH,
    grid: int = DEFAULT_GRID,
    rotation: np.ndarray | None = None,
    alpha: float = DEFAULT_ALPHA,
    power: float = DEFAULT_POWER,
) -> DetectabilityMap:
    """Minimal detectable bias of every reading on the grid ``home +- half_width`` in x and y.

    Args:
        hexa: a hexapod with redundant sensors.
        half_width: half side of the square section (m).
        grid: points along each side (>= 2).
        rotation: platform orientation over the section (3x3, base frame), default home's.
        alpha: false-alarm rate of the test, in (0, 1).
        power: detection probability, in (alpha, 1).

    Raises:
        InputError: a hexapod without redundant sensors, or a bad argument.
    """
    red = hexa.redundancy
    if red is None:
        raise InputError(
            "hexapod", hexa.closed_loop.source, "declares no redundant sensors (measuring legs, inclinometer)"
        )
    if type(grid) is not int or grid < 2:
        raise InputError("grid", grid, "an int >= 2")
    if not (isinstance(half_width, (int, float)) and 0.0 < half_width < 10.0):
        raise InputError("half_width", half_width, "metres, in (0, 10)")
    if not 0.0 < alpha < power < 1.0:
        raise InputError("power", power, f"need 0 < alpha ({alpha:g}) < power < 1")
    home = hexa.home_pose
    xs = home[0, 3] + np.linspace(-half_width, half_width, grid)
    ys = home[1, 3] + np.linspace(-half_width, half_width, grid)
    mdb = np.full((grid, grid, red.m), np.nan)
    T = home.copy()
    if rotation is not None:
        T[:3, :3] = rotation
    for iy, y in enumerate(ys):
        for ix, x in enumerate(xs):
            T[0, 3], T[1, 3] = x, y
            try:
                A = red.whitened_jacobian(T)
            except SolverError:
                continue  # outside the workspace: nan
            mdb[iy, ix] = minimal_detectable_bias(A, red.sigmas, alpha, power)
    return DetectabilityMap(red.names, xs, ys, float(home[2, 3]), mdb, alpha, power)
