"""The body check of a solve's answer: joint cones, collisions and the operating envelope.

A configuration that closes the loops within the stroke and joint limits may still be one the
machine cannot reach: a joint beyond its cone (:mod:`.cones`), two bodies closer than the
geometry's ``min_clearance`` (:mod:`.clearance`). :class:`BodyCheck` judges the answer of every
path that returns a pose:

* **inverse and hybrid kinematics** (a commanded pose or joint set): status ``cone_limit`` or
  ``collision`` instead of ``converged`` (the first found, cones first; the message names the
  joint, or the pair and the distance);
* **direct kinematics** (a measured pose: the platform is there): the status stays, the flags
  ``cone_limit`` / ``collision`` say what the pose violates and the message names it.

The cones and ``min_clearance`` come from the geometry, or for a hexapod loaded from an MJCF
from the file (:func:`body_limits`); the collision bodies from the URDF or the MJCF
(:mod:`~hexapod_model.description.collision`).

The **operating envelope** (``HexapodGeometry.envelope``: half-widths ``x, y, z`` (m) and
``roll, pitch, yaw`` (rad) of a box about the home pose; the translation in the base frame,
the angles those of :func:`hexapod_model.lie.matrix_to_rpy` of ``R_home^T R``) says where the
platform works. It does not judge a single answer: it decides between assemblies
(:mod:`.all_assemblies`), where only the assemblies within the limits, the cones, the
collision-free set and the envelope compete.

The check is one compiled call (:meth:`.clearance.ClearanceQuery.check`: the placements, the
cone angles and the pairs closer than ``min_clearance``), about 5 us on the reference preset;
``Hexapod.check_body = False`` skips it (docs/solver.md): the warm forward path then costs
what it did without it. A file without collision bodies (a URDF or MJCF written without them)
cannot be checked: :class:`BodyCheck` refuses it, so that ``check_body=False`` is asked for
explicitly rather than collisions silently left out; a geometry without cones has no cone check.
"""

from __future__ import annotations

import threading
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..description.collision import has_collision_bodies
from ..description.geometry import HexapodGeometry
from ..description.mjcf import COLLISION_GROUP
from ..description.mjcf_body import read_body_limits
from ..description.model import ClosedLoopModel
from ..exceptions import MjcfError, UrdfError
from ..lie import matrix_to_rpy
from .cones import ConeAngles, ConeGeometry, cone_limits
from .newton.solver import Solution

if TYPE_CHECKING:
    from .clearance import Clearance, ClearanceQuery

#: the statuses (inverse, hybrid) and flags (direct kinematics) of the body check
BODY_STATUSES = ("cone_limit", "collision")


def body_limits(clm: ClosedLoopModel, geometry: HexapodGeometry | None) -> tuple[np.ndarray, float]:
    """(6, 2) cone half-angles (rad, ``inf``: none) and ``min_clearance`` (m) of a loaded hexapod.

    From its geometry; without one, from the MJCF it was loaded from
    (:mod:`~hexapod_model.description.mjcf_body`); else no cones and a bound of 0.
    """
    if geometry is None and clm.mjcf_xml is not None:
        found = read_body_limits(clm.mjcf_xml, clm.source)
        return found.cones, found.min_clearance
    return cone_limits(geometry), 0.0 if geometry is None else geometry.min_clearance


def message_of(found: list[tuple[str, str]], forward: bool) -> str:
    """The message of :meth:`BodyCheck.violations`: each names its flag; a status's own name is left to the status."""
    first, *rest = found
    head = first[1] if forward else first[1].removeprefix(f"{first[0]}: ")
    return "; ".join([head, *(m for _, m in rest)])


class BodyCheck:
    """Cones, clearance and envelope of one loaded hexapod (see the module doc).

    Args:
        clm: the loaded hexapod.
        geometry: its geometry (cones, ``min_clearance``, envelope), if any.
        compiled: run the compiled clearance kernel.

    Raises:
        UrdfError: the file ``clm`` was loaded from declares no collision bodies (an
            :class:`~hexapod_model.exceptions.MjcfError` for an MJCF): a check that cannot look
            for collisions would pass poses in collision; ``check_body=False`` says so.
    """

    def __init__(self, clm: ClosedLoopModel, geometry: HexapodGeometry | None, compiled: bool = True):
        if not has_collision_bodies(clm):
            error, what = (
                (MjcfError, f"geoms of group {COLLISION_GROUP}") if clm.mjcf_xml else (UrdfError, "<collision>")
            )
            raise error(
                clm.source,
                what,
                "the file has no collision bodies, so the body check cannot look for collisions: pass "
                "check_body=False (--no-body-check) to solve without it, or load a file with them "
                "(hexapod urdf, hexapod mjcf)",
            )
        self.clm = clm
        self.geometry = geometry
        self.compiled = compiled
        #: (6, 2) cone half-angles (rad, ``inf``: none), and the collision bound (m)
        self.limits, self.min_clearance = body_limits(clm, geometry)
        self.has_cones = bool(np.isfinite(self.limits).any())
        self._cones = ConeGeometry(clm) if self.has_cones else None
        self._local = threading.local()
        #: operating box half-widths (x, y, z [m], roll, pitch, yaw [rad]) about home, or None
        self.envelope = None if geometry is None else geometry.envelope
        self._home = clm.home.homogeneous.copy()
        self._query: ClearanceQuery | None = None
        self._no_bodies = False
        self._lock = threading.Lock()

    def query(self) -> ClearanceQuery | None:
        """The clearance query, built at the first call; None for a model without collision bodies."""
        if self._query is None and not self._no_bodies:
            from .clearance import ClearanceQuery  # coal loads with the first check

            with self._lock:
                if self._query is None and not self._no_bodies:
                    try:
                        self._query = ClearanceQuery(
                            self.clm, self.min_clearance, self.compiled, self._cones, self.limits
                        )
                    except UrdfError:
                        self._no_bodies = True
        return self._query

    def violations(self, q: np.ndarray) -> list[tuple[str, str]]:
        """``(status, message)`` of each limit configuration ``q`` violates: ``cone_limit``, ``collision``.

        One kernel call (:meth:`.clearance.ClearanceQuery.check`) takes the cone angles and the
        pairs closer than ``min_clearance``; the NumPy cones of :mod:`.cones` serve a model without
        collision bodies.
        """
        out = []
        query = self.query()
        if query is None:
            if self._cones is not None:
                data = getattr(self._local, "data", None)
                if data is None:
                    data = self._local.data = self.clm.model.createData()
                cones = ConeAngles(self._cones.angles(q, data), self.limits)
                if not cones.within:
                    out.append(("cone_limit", cones.message()))
            return out
        return self._found(*query.check(q))

    def _found(self, c: Clearance | None, angles: np.ndarray | None) -> list[tuple[str, str]]:
        """:meth:`violations` of a :meth:`.clearance.ClearanceQuery.check` answer."""
        out = []
        if angles is not None:
            out.append(("cone_limit", ConeAngles(angles, self.limits).message()))
        if c is not None:
            out.append(("collision", c.message()))
        return out

    def judged(self, sol: Solution, forward: bool) -> Solution:
        """``sol`` with the body check's status (``forward`` False) or flags (True); unchanged if it passes.

        Only a ``converged`` answer is checked (the others carry no pose to vouch for).
        """
        if sol.status != "converged":
            return sol
        query = self._query
        if query is None:
            found = self.violations(sol.q)
        else:  # the hot path: one kernel call, nothing built when the answer passes
            c, angles = query.check(sol.q)
            if c is None and angles is None:
                return sol
            found = self._found(c, angles)
        if not found:
            return sol
        msg = message_of(found, forward)
        msg = f"{sol.message}; {msg}" if sol.message else msg
        if forward:
            return replace(sol, flags=sol.flags + tuple(k for k, _ in found if k not in sol.flags), message=msg)
        return replace(sol, status=found[0][0], message=msg)

    def offset(self, pose: np.ndarray) -> np.ndarray:
        """(6,) ``x, y, z`` (m, base frame) and ``roll, pitch, yaw`` (rad) of ``pose`` from home."""
        pose = np.asarray(pose, dtype=float)
        rpy = matrix_to_rpy(self._home[:3, :3].T @ pose[:3, :3])
        return np.concatenate([pose[:3, 3] - self._home[:3, 3], rpy])

    def within_envelope(self, pose: np.ndarray) -> bool:
        """Whether ``pose`` (4x4, base frame, m) lies in the operating envelope (True without one)."""
        if self.envelope is None:
            return True
        return bool(np.all(np.abs(self.offset(pose)) <= np.asarray(self.envelope)))

    def acceptable(self, sol: Solution) -> bool:
        """Whether a converged answer lies within the cones, the collision-free set and the envelope."""
        return not any(f in BODY_STATUSES for f in sol.flags) and self.within_envelope(sol.pose)
