"""Workspace for a cone of tool orientations and its kinematic figures (Jakobović and Jelenković (2002) §II-III).

A platform position ``x`` (tool point = platform origin, Jakobović and Jelenković's ``l_tool = 0``)
belongs to the workspace when the inverse kinematics succeeds within the stroke and Cardan limits
(``status == "converged"``: also free of collision and within the joint cones when the hexapod
checks its body, :mod:`~hexapod_model.kinematics.body_check`) for EVERY orientation of a cone
(Jakobović and Jelenković (2002) Fig. 4): the tool axis (platform z) upright and tilted by
``cone_deg`` towards ``cone_samples`` equally spaced azimuths, with no rotation about the tool
axis. For ``spherical`` and ``guideway`` legs, whose platform ball joint has no limit in the
model, the leg must also stay within ``cardan_limit`` of its home direction as seen from the
platform (the paper's joint cone ``phi_max``).

At each workspace point the three figures of :mod:`hexapod_model.analysis.jacobian` (condition number,
sigma_min, |det J|) are averaged over the orientations; their workspace averages are
Jakobović and Jelenković's Table II. Lengths are expressed in ``length_unit`` metres (see docs/evaluate.md).

The grid is computed slice by slice (one z per task) so that the work spreads over processes
and finished slices can be checkpointed (:func:`compute_slice` is the unit of work).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.hexapod import Hexapod
from ..kinematics.newton.solver import Solution
from .jacobian import evaluate_jacobian, leg_jacobian
from .statics import force_per_unit_wrench, stiffness_of

#: inverse-kinematics statuses within the stroke and joint limits (the last two: the body check's)
BODY_OK = ("converged", "cone_limit", "collision")
#: the per-point worst cases over the orientations that :class:`SliceResult` keeps, in ``worst`` order
WORST = (
    "kappa_max",
    "sigma_min_min",
    "sigma_max_max",
    "force_per_force_max",
    "force_per_moment_max",
    "stiffness_translational_min",
    "stiffness_rotational_min",
)


def cone_rotations(cone_deg: float, samples: int) -> np.ndarray:
    """Tool orientations of a cone.

    (1 + samples, 3, 3) tool orientations: upright, then tilted by ``cone_deg`` about the
    horizontal axes ``(-sin a, cos a, 0)`` for ``samples`` azimuths ``a`` (base frame).
    """
    out = [np.eye(3)]
    th = np.radians(cone_deg)
    if th > 0:
        for a in np.linspace(0.0, 2 * np.pi, samples, endpoint=False):
            k = np.array([-np.sin(a), np.cos(a), 0.0])
            K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            out.append(np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K)
    return np.array(out)


def platform_cone_ok(hexa: Hexapod, q: np.ndarray, pose: np.ndarray) -> bool:
    """Whether the leg directions stay within the Cardan limit.

    Leg directions seen from the platform within ``cardan_limit`` of their home direction
    (only checked for ``spherical``/``guideway`` geometries; always True otherwise).
    """
    g = hexa.geometry
    if g is None or g.joint_type == "cardan":
        return True
    b, p = g.base_points(), g.platform_points()
    lengths = hexa.lengths_of(q)
    if g.joint_type == "guideway":
        b = b + lengths[:, None] * np.array([leg.guideway for leg in g.legs])
    R, t = pose[:3, :3], pose[:3, 3]
    d = (t + p @ R.T - b) @ R  # leg vectors in the platform frame
    home = g.home_translation + p - g.base_points()
    cosang = np.einsum("ij,ij->i", d, home) / (np.linalg.norm(d, axis=1) * np.linalg.norm(home, axis=1))
    return bool(np.all(cosang >= np.cos(g.cardan_limit) - 1e-12))


@dataclass(frozen=True)
class SliceResult:
    """One z-slice of the grid.

    Arrays of shape (ny, nx); figures are orientation averages (NaN outside the workspace).
    ``worst`` (7, ny, nx) holds the worst case over the orientations of each point, in :data:`WORST`
    order: largest condition number, smallest and largest singular value (lengths in the evaluation's
    unit), largest leg force per unit force (N/N) and per unit moment (N per N m, SI) at the platform
    origin (:func:`~hexapod_model.analysis.statics.force_per_unit_wrench`), smallest translational
    (N/m) and rotational (N m/rad) stiffness of the locked fixture per N/m of leg stiffness
    (:func:`~hexapod_model.analysis.statics.stiffness_of`; it scales with a common leg stiffness).
    ``inside`` counts a point only when every orientation is also free of collision and within
    the joint cones (the hexapod's body check); ``inside_limits`` (same shape) the points within
    the stroke and joint limits alone, whatever the body: the difference is what the body removes.
    """

    index: int
    inside: np.ndarray
    kappa: np.ndarray
    sigma_min: np.ndarray
    abs_det: np.ndarray
    worst: np.ndarray
    inside_limits: np.ndarray | None = None


def compute_slice(
    hexa: Hexapod, index: int, z: float, xs: np.ndarray, ys: np.ndarray, rotations: np.ndarray, length_unit: float
) -> SliceResult:
    """Test every (x, y) of the slice at height ``z`` (m, base frame) for all ``rotations``."""
    ny, nx = len(ys), len(xs)
    inside = np.zeros((ny, nx), dtype=bool)
    inside_limits = np.zeros((ny, nx), dtype=bool)
    figs = np.full((3, ny, nx), np.nan)
    worst = np.full((len(WORST), ny, nx), np.nan)
    guesses: list[Solution | None] = [None] * len(rotations)
    T = np.eye(4)
    for iy, y in enumerate(ys):
        for ix in range(nx) if iy % 2 == 0 else range(nx - 1, -1, -1):  # serpentine: warm starts stay near
            T[:3, 3] = (xs[ix], y, z)
            sols = []
            for k, R in enumerate(rotations):
                T[:3, :3] = R
                sol = hexa.inverse(T, guess=guesses[k], check=False)
                if sol.status not in BODY_OK and guesses[k] is not None:
                    sol = hexa.inverse(T, check=False)  # retry from home: the warm start may mislead
                if sol.status in BODY_OK:
                    guesses[k] = sol
                if sol.status not in BODY_OK or not platform_cone_ok(hexa, sol.q, sol.pose):
                    break
                sols.append(sol)
            if len(sols) != len(rotations):
                continue
            inside_limits[iy, ix] = True
            if any(sol.status != "converged" for sol in sols):
                continue  # in collision or beyond a cone at some orientation
            inside[iy, ix] = True
            Js = [leg_jacobian(hexa, s.q) for s in sols]
            ev = [evaluate_jacobian(J, length_unit) for J in Js]
            figs[:, iy, ix] = np.mean([[e.condition_number, e.sigma_min, e.abs_det] for e in ev], axis=0)
            forces = np.array([force_per_unit_wrench(J) for J in Js])
            stiff = [stiffness_of(J, 1.0) for J in Js]
            worst[:, iy, ix] = (
                max(e.condition_number for e in ev),
                min(e.sigma_min for e in ev),
                max(float(e.singular_values[0]) for e in ev),
                forces[:, 0].max(),
                forces[:, 1].max(),
                min(k.translational for k in stiff),
                min(k.rotational for k in stiff),
            )
    return SliceResult(index, inside, figs[0], figs[1], figs[2], worst, inside_limits)


def probe_extent(hexa: Hexapod, step: float, max_steps: int = 400) -> np.ndarray:
    """Box around home reachable along the axes.

    (3, 2) box (m, base frame) around home reachable along +-x, +-y, +-z with the platform
    upright, found by marching outward in ``step`` increments; used to size the grid. Within
    the stroke and joint limits alone (a pose beyond a cone or in collision still extends the
    box), so that the grid, and the limits-only count on it, do not depend on the body check.
    """
    home = hexa.home_pose
    box = np.tile(home[:3, 3][:, None], (1, 2)).astype(float)
    for axis in range(3):
        for side, sign in ((0, -1.0), (1, 1.0)):
            sol, T = None, home.copy()
            for n in range(1, max_steps + 1):
                T[axis, 3] = home[axis, 3] + sign * n * step
                sol = hexa.inverse(T, guess=sol, check=False)
                if sol.status not in BODY_OK:
                    break
                box[axis, side] = T[axis, 3]
    return box
