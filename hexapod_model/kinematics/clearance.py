"""Clearance: the smallest distance between two bodies of a hexapod in a configuration.

The bodies are the ``<collision>`` elements of the hexapod's URDF
(:mod:`~hexapod_model.description.urdf_collision`), or the geoms an MJCF written from it carries
in their place, loaded as a Pinocchio ``GeometryModel``
with the pairs that touch by construction left out
(:mod:`~hexapod_model.description.collision`). A query places the bodies and measures every pair
in one compiled call (:mod:`~hexapod_model.kinematics.clearance_kernel`: capsules, spheres and
capsules against plates exactly; coal only for a body that enters a plate, where the depth
needs its EPA, and two plates a bound cannot keep apart): the distance (m, negative when two
bodies overlap: minus the penetration depth), the pair's names and the two witness points (base
frame, m). :meth:`ClearanceQuery.all_pairs` runs coal's distance on every pair (at
``GJK_TOLERANCE``); the query agrees with it to 1e-9 m.

:meth:`ClearanceQuery.check` is the body check's call (:mod:`.body_check`): the same kernel with
the geometry's ``min_clearance`` as the bound, so that only the pairs a cheap bound cannot keep
beyond it are measured, and the joints' cone angles in the same call.

A pose whose clearance is below the geometry's ``min_clearance`` is in ``collision``
(:attr:`Clearance.collision`).
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..description.collision import CollisionModel, collision_model
from ..description.geometry import HexapodGeometry
from ..description.mjcf_body import read_body_limits
from ..description.model import ClosedLoopModel
from ..exceptions import InputError, UrdfError
from . import clearance_kernel as kernel
from .body_tables import kernel_tables
from .cones import ConeGeometry
from .newton.entries import direct, plain
from .newton.first_compile import announce
from .newton.solver import Solution
from .placement_kernel import FLAGS, POINTS

#: coal's GJK tolerance for the distances it measures here (its default, 1e-6, leaves up to
#: 1.2 um on a capsule near a plate's rim; this one agrees with the exact distance to 1e-11 m)
GJK_TOLERANCE = 1e-12
GJK_MAX_ITERATIONS = 1000


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

    Each thread gets work arrays of its own at its first query; a query allocates nothing
    else unless it reports a pair (its :class:`Clearance`) or sends one to coal.

    Args:
        clm: the loaded hexapod (made from a URDF with collision bodies, two at least).
        min_clearance: the collision bound (m).
        compiled: run the fast query compiled by numba (else the same kernel in Python).
        cones: the joints' cone geometry, for :meth:`check` (None: no cone angles).
        limits: (6, 2) the cone half-angles (rad; ``inf``: none), with ``cones``.
    """

    def __init__(
        self,
        clm: ClosedLoopModel,
        min_clearance: float = 0.0,
        compiled: bool = True,
        cones: ConeGeometry | None = None,
        limits: np.ndarray | None = None,
    ):
        self.model = clm.model
        self.collision: CollisionModel = collision_model(clm)
        self.min_clearance = float(min_clearance)
        self.compiled = bool(compiled)
        g = self.collision.geometry
        self.pairs = tuple((self.collision.names[p.first], self.collision.names[p.second]) for p in g.collisionPairs)
        if not self.pairs:
            raise UrdfError(clm.source, "<collision>", "no pair of collision bodies to measure")
        self.tables = kernel_tables(self.model, g, cones, limits)
        self.with_cones = cones is not None
        self._kernel = kernel.compiled_measure() if self.compiled else kernel.measure_body
        # check()'s call: the kernel until its first call, then the machine code it ran (.newton.entries.direct)
        self._check, self._check_direct = self._kernel, False
        self._nj = self.model.njoints
        self._local = threading.local()

    def _buffers(self) -> tuple[pin.Data, pin.GeometryData]:
        buf = getattr(self._local, "buffers", None)
        if buf is None:
            gd = pin.GeometryData(self.collision.geometry)
            for request in gd.distanceRequests:
                request.gjk_tolerance = GJK_TOLERANCE
                request.gjk_max_iterations = GJK_MAX_ITERATIONS
            buf = self._local.buffers = (self.model.createData(), gd)
        return buf

    def _work(self) -> tuple[np.ndarray, np.ndarray]:
        work = getattr(self._local, "work", None)
        if work is None:
            ng, npairs = len(self.collision.names), len(self.pairs)
            work = self._local.work = (
                np.zeros((self._nj + 2 * ng + 2, 4, 4)),
                np.zeros(FLAGS + npairs + self._nj),
            )
        return work

    def check(self, q: np.ndarray) -> tuple[Clearance | None, np.ndarray | None]:
        """The body check of configuration ``q`` (``nq`` values) in one kernel call: collision and cones.

        Returns:
            ``(clearance, angles)``: the :class:`Clearance` when ``q`` is in collision (else
            None), and the (6, 2) cone angles (rad) when a joint lies beyond its cone (else
            None; always None without ``cones``).
        """
        work = getattr(self._local, "work", None) or self._work()
        ints, floats, frames = self.tables
        q = plain(q)
        args = (q, ints, floats, frames, work[0], work[1], self.min_clearance, self.with_cones)
        if self._check_direct:
            found = self._check(*args)
        else:  # its first call here: announced if it compiles (about 4 s after installation)
            if self.compiled:
                announce(self._kernel)
            found = self._kernel(*args)
            self._check, self._check_direct = direct(self._kernel, args), True  # the same types on every later call
        if found[1] < 0 and not found[2] and found[3]:  # nothing closer than min_clearance, every cone kept
            return None, None
        c = self._answer(q, found, *work)
        angles = None if found[3] else work[1][:12].reshape(6, 2).copy()
        return (c if c is not None and c.collision else None), angles

    def __call__(self, q: np.ndarray) -> Clearance:
        """The clearance of configuration ``q`` (``nq`` values, as a solve's ``Solution.q``).

        The kernel (:mod:`~hexapod_model.kinematics.clearance_kernel`); coal measures the
        overlaps of a body and a plate.
        """
        work, out = self._work()
        q = plain(np.asarray(q, dtype=float))  # the kernel's one compiled type
        if self.compiled:
            announce(self._kernel)  # (once per process: a set lookup after the first)
        found = self._kernel(q, *self.tables, work, out, np.inf, False)
        c = self._answer(q, found, work, out)
        assert c is not None  # every pair is measured against an infinite bound
        return c

    def _answer(self, q: np.ndarray, found: tuple, work: np.ndarray, out: np.ndarray) -> Clearance | None:
        """The :class:`Clearance` of a kernel call ``found``, with coal on the pairs it flagged; None if none."""
        best, k, flagged = found[0], found[1], found[2]
        if k < 0 and not flagged:
            return None
        points = out[POINTS:FLAGS].reshape(2, 3).copy()
        if flagged:
            _, gdata = self._buffers()
            geometry = self.collision.geometry
            for c in np.flatnonzero(out[FLAGS : FLAGS + len(self.pairs)]):
                pair = geometry.collisionPairs[int(c)]
                for g in (pair.first, pair.second):
                    gdata.oMg[g] = pin.SE3(work[self._nj + g])
                r = pin.computeDistance(geometry, gdata, int(c))
                if r.min_distance < best:
                    best, k = r.min_distance, int(c)
                    points = np.array([r.getNearestPoint1(), r.getNearestPoint2()])
            if k < 0:
                return None
        return Clearance(float(best), self.pairs[k], points, self.min_clearance)

    def all_pairs(self, q: np.ndarray) -> np.ndarray:
        """Every checked pair's distance (m) at ``q``, in the order of :attr:`pairs`, by coal on every pair."""
        data, gdata = self._buffers()
        pin.computeDistances(self.model, data, self.collision.geometry, gdata, q)
        return np.fromiter((r.min_distance for r in gdata.distanceResults), float, len(gdata.distanceResults))


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
    """The hexapod's :class:`ClearanceQuery`, built at the first call (the bound of its geometry or MJCF, else 0)."""
    query = _QUERIES.get(hexapod)  # a dict read needs no lock; building one does
    if query is not None:
        return query
    with _LOCK:
        query = _QUERIES.get(hexapod)
        if query is None:
            clm, geometry = hexapod.closed_loop, hexapod.geometry
            if geometry is not None:
                bound = geometry.min_clearance
            else:  # an MJCF carries its geometry's bound
                bound = 0.0 if clm.mjcf_xml is None else read_body_limits(clm.mjcf_xml, clm.source).min_clearance
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
    if not np.isfinite(arr).all():
        raise InputError("q_or_pose", q_or_pose, "values must be finite")
    return query_of(hexapod)(arr)
