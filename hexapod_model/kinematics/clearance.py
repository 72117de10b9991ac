"""Clearance: the smallest distance between two bodies of a hexapod in a configuration.

The bodies are the ``<collision>`` elements of the hexapod's URDF
(:mod:`~hexapod_model.description.urdf_collision`), loaded as a Pinocchio ``GeometryModel``
with the pairs that touch by construction left out
(:mod:`~hexapod_model.description.collision`). A query places the bodies and measures every pair
(:mod:`~hexapod_model.kinematics.clearance_kernel`: capsules and spheres exactly, the plates by
coal where a bound cannot rule them out; :meth:`ClearanceQuery.all_pairs` runs coal's
distance on every pair): the distance (m, negative when two bodies overlap: minus the penetration depth),
the pair's names and the two witness points (base frame, m).

A pose whose clearance is below the geometry's ``min_clearance`` is in ``collision``
(:attr:`Clearance.collision`).
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass
from typing import Protocol

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..description.collision import CollisionModel, collision_model
from ..description.geometry import HexapodGeometry
from ..description.model import ClosedLoopModel
from ..exceptions import InputError, UrdfError
from . import clearance_kernel as kernel
from .newton.solver import Solution


@dataclass(frozen=True)
class Clearance:
    """The closest pair of bodies in one configuration.

    Attributes:
        distance: smallest distance between two bodies (m); negative: they overlap by that much.
        pair: the two bodies' names (``leg2_rod``, ``leg3_cylinder``, ``base_plate``, ...).
        points: (2, 3) the nearest point on each body, base frame (m).
        min_clearance: the geometry's bound (m).
    """

    distance: float
    pair: tuple[str, str]
    points: np.ndarray
    min_clearance: float

    @property
    def collision(self) -> bool:
        """Whether the clearance is below ``min_clearance`` (the pose is in ``collision``)."""
        return self.distance < self.min_clearance

    def message(self) -> str:
        """One line naming the pair and the distance against the bound."""
        verb = "collision" if self.collision else "clearance"
        return (
            f"{verb}: {self.pair[0]} - {self.pair[1]} at {self.distance * 1e3:.3f} mm "
            f"(min_clearance {self.min_clearance * 1e3:.3f} mm)"
        )

    def to_dict(self) -> dict:
        """JSON-ready dict (metres, base frame)."""
        return {
            "distance_m": self.distance,
            "pair": list(self.pair),
            "points_m": self.points.tolist(),
            "min_clearance_m": self.min_clearance,
            "collision": self.collision,
        }


class ClearanceQuery:
    """Clearance queries on one hexapod model; one object may be shared by threads.

    Args:
        clm: the loaded hexapod (made from a URDF with collision bodies).
        min_clearance: the collision bound (m).
        compiled: run the fast query compiled by numba (else the same kernel in Python).
    """

    def __init__(self, clm: ClosedLoopModel, min_clearance: float = 0.0, compiled: bool = True):
        self.model = clm.model
        self.collision: CollisionModel = collision_model(clm)
        self.min_clearance = float(min_clearance)
        self.compiled = bool(compiled)
        g = self.collision.geometry
        self.pairs = tuple((self.collision.names[p.first], self.collision.names[p.second]) for p in g.collisionPairs)
        self._arrays = _kernel_arrays(self.model, g)
        self._local = threading.local()

    def _buffers(self) -> tuple[pin.Data, pin.GeometryData]:
        buf = getattr(self._local, "buffers", None)
        if buf is None:
            gd = pin.GeometryData(self.collision.geometry)
            buf = self._local.buffers = (self.model.createData(), gd)
        return buf

    def __call__(self, q: np.ndarray) -> Clearance:
        """The clearance of configuration ``q`` (``nq`` values, as a solve's ``Solution.q``).

        The fast kernel (:mod:`~hexapod_model.kinematics.clearance_kernel`); coal measures the
        plate pairs it cannot rule out.
        """
        fn = kernel.compiled_nearest_pair() if self.compiled else kernel.nearest_pair
        best, k, points, placements, candidates = fn(np.ascontiguousarray(q, dtype=float), *self._arrays)
        if np.any(candidates):
            _, gdata = self._buffers()
            geometry = self.collision.geometry
            for c in np.flatnonzero(candidates):
                pair = geometry.collisionPairs[int(c)]
                for g in (pair.first, pair.second):
                    gdata.oMg[g] = pin.SE3(placements[g])
                r = pin.computeDistance(geometry, gdata, int(c))
                if r.min_distance < best:
                    best, k = r.min_distance, int(c)
                    points = np.array([r.getNearestPoint1(), r.getNearestPoint2()])
        return Clearance(float(best), self.pairs[k], points, self.min_clearance)

    def all_pairs(self, q: np.ndarray) -> np.ndarray:
        """Every checked pair's distance (m) at ``q``, in the order of :attr:`pairs`, by coal on every pair."""
        data, gdata = self._buffers()
        pin.computeDistances(self.model, data, self.collision.geometry, gdata, q)
        return np.fromiter((r.min_distance for r in gdata.distanceResults), float, len(gdata.distanceResults))


def _kernel_arrays(model: pin.Model, geometry: pin.GeometryModel) -> tuple[np.ndarray, ...]:
    """The model's joint tree and bodies as the arrays :func:`~.clearance_kernel.nearest_pair` takes."""
    nj = model.njoints
    kind = np.zeros(nj, dtype=np.int64)
    axis = np.zeros((nj, 3))
    data = model.createData()
    q0 = pin.neutral(model)
    for j in range(1, nj):
        name = model.joints[j].shortname()
        if name == "JointModelFreeFlyer":
            kind[j] = kernel.FREE
            continue
        J = pin.computeJointJacobian(model, data, q0, j)[:, model.joints[j].idx_v]  # local frame: (v, w)
        kind[j] = kernel.REVOLUTE if np.linalg.norm(J[3:]) > 0.5 else kernel.PRISMATIC
        axis[j] = J[3:] if kind[j] == kernel.REVOLUTE else J[:3]
    parent = np.array(model.parents, dtype=np.int64)
    placement = np.array([M.homogeneous for M in model.jointPlacements])
    idx_q = np.array([max(model.joints[j].idx_q, 0) for j in range(nj)], dtype=np.int64)
    objects = geometry.geometryObjects
    body_joint = np.array([o.parentJoint for o in objects], dtype=np.int64)
    body_placement = np.array([o.placement.homogeneous for o in objects])
    half, radius, shape = np.zeros(len(objects)), np.zeros(len(objects)), np.zeros(len(objects), dtype=np.int64)
    for g, o in enumerate(objects):
        shape_ = o.geometry
        if isinstance(shape_, coal.Capsule):
            half[g], radius[g] = shape_.halfLength, shape_.radius
        elif isinstance(shape_, coal.Sphere):
            radius[g] = shape_.radius
        elif isinstance(shape_, coal.Cylinder):
            half[g], radius[g], shape[g] = shape_.halfLength, shape_.radius, kernel.DISC
        else:
            raise UrdfError("<collision>", o.name, "the clearance query handles capsules, spheres and cylinders")
    first = np.array([p.first for p in geometry.collisionPairs], dtype=np.int64)
    second = np.array([p.second for p in geometry.collisionPairs], dtype=np.int64)
    return parent, placement, kind, axis, idx_q, body_joint, body_placement, half, radius, shape, first, second


class _Solves(Protocol):
    """What :func:`clearance` needs of a :class:`~hexapod_model.kinematics.hexapod.Hexapod`."""

    closed_loop: ClosedLoopModel
    geometry: HexapodGeometry | None
    nq: int
    compiled: bool

    def inverse(self, pose: np.ndarray, guess=None, *, check: bool = True) -> Solution: ...  # noqa: D102


_QUERIES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_LOCK = threading.Lock()


def query_of(hexapod: _Solves) -> ClearanceQuery:
    """The hexapod's :class:`ClearanceQuery`, built at the first call (the bound from its geometry, 0 without one)."""
    with _LOCK:
        query = _QUERIES.get(hexapod)
        if query is None:
            bound = 0.0 if hexapod.geometry is None else hexapod.geometry.min_clearance
            query = _QUERIES[hexapod] = ClearanceQuery(hexapod.closed_loop, bound, hexapod.compiled)
    return query


def clearance(hexapod: _Solves, q_or_pose: ArrayLike) -> Clearance:
    """The clearance of a configuration (``nq`` values) or of a platform pose (4x4, base frame, m).

    A pose is placed by an inverse solve (``check=False``: a pose outside the joint limits
    still has a clearance).

    Raises:
        InputError: neither a configuration nor a 4x4 pose, values not finite, or a pose
            whose inverse solve did not give a configuration.
    """
    arr = np.asarray(q_or_pose, dtype=float)
    if arr.shape == (4, 4):
        sol = hexapod.inverse(arr, check=False)
        if sol.status not in ("converged", "out_of_limits", "cone_limit", "collision"):
            raise InputError("pose", sol.status, "its inverse solve gave no configuration to measure")
        arr = sol.q
    elif arr.shape != (hexapod.nq,):
        raise InputError("q_or_pose", arr.shape, f"expected a configuration of {hexapod.nq} values or a 4x4 pose")
    if not np.all(np.isfinite(arr)):
        raise InputError("q_or_pose", q_or_pose, "values must be finite")
    return query_of(hexapod)(arr)
