"""The collision bodies of a loaded hexapod as a Pinocchio ``GeometryModel``, with the pairs to check.

:func:`collision_model` reads the ``<collision>`` elements of the URDF a
:class:`~hexapod_model.description.model.ClosedLoopModel` was made from (Pinocchio's
``buildGeomFromUrdfString``; capsules through the ``<collision_checking>`` convention) and names
each body after its ``<collision name=...>``; for a hexapod loaded from an MJCF, the geoms of
the collision group that ``hexapod mjcf`` writes from those elements
(:func:`~hexapod_model.description.mjcf_loader.mjcf_collision_bodies`), the same bodies under
the same names. The pairs whose distance is checked are all
pairs of bodies except those that touch by construction, found from the model, not from a list
of names:

* two bodies of the same leg (a leg and its own joint housings, its cylinder and its rod);
* a plate and the body of a leg nearest to it along the leg's chain (the joint housing that
  sits on the plate): the first link with a body from the base, the last one towards the
  closure;
* two legs whose closures meet the platform at the same point, or whose first joints sit at the
  same base point (a shared joint, as in the 3-6 sensor or a 3-3 platform): all pairs between
  their bodies.
"""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import MjcfError, UrdfError
from .mjcf import COLLISION_GROUP
from .mjcf_loader import mjcf_collision_bodies
from .model import ClosedLoopModel

SHARED_JOINT = 1e-9  # m: closure anchors closer than this at home are one joint


@dataclass(frozen=True)
class CollisionModel:
    """The collision bodies of a hexapod and the pairs checked.

    Attributes:
        geometry: Pinocchio's ``GeometryModel``; its collision pairs are the pairs checked.
        owners: per body, the leg index (0..5), ``-1`` for the base, ``-2`` for the platform.
        names: per body, its name (the URDF ``<collision name>``).
    """

    geometry: pin.GeometryModel
    owners: tuple[int, ...]
    names: tuple[str, ...]


def _collision_names(urdf_xml: str) -> dict[str, list[str]]:
    """Link name -> the ``name`` of its ``<collision>`` elements, in file order (``""`` when unnamed)."""
    root = ET.fromstring(urdf_xml)
    return {str(el.get("name")): [c.get("name") or "" for c in el.findall("collision")] for el in root.findall("link")}


def _owner(clm: ClosedLoopModel, joint: int) -> int:
    if joint == 0:
        return -1
    if joint == clm.platform_joint:
        return -2
    for k, leg in enumerate(clm.legs):
        if joint in leg.joints:
            return k
    raise UrdfError(clm.source, clm.model.names[joint], "a collision body on a joint outside the legs")


def _shared_anchors(clm: ClosedLoopModel) -> set[tuple[int, int]]:
    """Pairs of legs whose closure anchors, or first joints, coincide at home (one joint shared by two legs)."""
    m = clm.model
    data = m.createData()
    pin.framesForwardKinematics(m, data, clm.q_home)
    out = set()
    for points in (
        [data.oMf[leg.anchor_frame].translation.copy() for leg in clm.legs],
        [data.oMi[leg.joints[0]].translation.copy() for leg in clm.legs],
    ):
        out |= {
            (a, b)
            for a, b in itertools.combinations(range(len(points)), 2)
            if np.linalg.norm(points[a] - points[b]) < SHARED_JOINT
        }
    return out


def has_collision_bodies(clm: ClosedLoopModel) -> bool:
    """Whether the file ``clm`` was loaded from declares collision bodies (read without building them).

    A URDF: a ``<collision>`` element in a link; an MJCF: a named geom of the collision group.
    """
    if clm.urdf_xml is not None:
        return any(link.find("collision") is not None for link in ET.fromstring(clm.urdf_xml).iter("link"))
    if clm.mjcf_xml is not None:
        group = str(COLLISION_GROUP)
        return any(g.get("group") == group and g.get("name") for g in ET.fromstring(clm.mjcf_xml).iter("geom"))
    return False


def collision_model(clm: ClosedLoopModel) -> CollisionModel:
    """The collision bodies of ``clm``'s URDF and the pairs to check (see the module doc).

    Raises:
        UrdfError: the hexapod was loaded from neither a URDF nor an MJCF, or its URDF has no
            ``<collision>`` element (regenerate it with ``hexapod urdf``).
        MjcfError: its MJCF has no named geom of the collision group (regenerate it with
            ``hexapod mjcf``).
    """
    m = clm.model
    names: list[str] = []
    owners: list[int] = []
    if clm.urdf_xml is not None:
        geometry = pin.buildGeomFromUrdfString(m, clm.urdf_xml, pin.GeometryType.COLLISION)
        if geometry.ngeoms == 0:
            raise UrdfError(
                clm.source, "<collision>", "the URDF has no collision bodies; regenerate it with hexapod urdf"
            )
        declared = _collision_names(clm.urdf_xml)
        seen: dict[str, int] = {}
        for go in geometry.geometryObjects:
            link = m.frames[go.parentFrame].name
            k = seen.get(link, 0)
            seen[link] = k + 1
            given = declared.get(link, [])
            go.name = given[k] if k < len(given) and given[k] else go.name
    elif clm.mjcf_xml is not None:
        geometry = mjcf_collision_bodies(clm)
        if geometry.ngeoms == 0:
            raise MjcfError(
                clm.source,
                f"group {COLLISION_GROUP}",
                "the MJCF has no collision bodies (named geoms of that group); regenerate it with hexapod mjcf",
            )
    else:
        raise UrdfError(clm.source, "<collision>", "clearance needs a URDF or MJCF with collision bodies")
    for go in geometry.geometryObjects:
        names.append(go.name)
        owners.append(_owner(clm, go.parentJoint))
    # per leg: the bodies nearest to the base and to the platform along its chain
    ends: dict[int, tuple[int, int]] = {}
    for k, leg in enumerate(clm.legs):
        mine = [g for g, o in enumerate(owners) if o == k]
        if mine:
            order = sorted(
                {(leg.joints.index(geometry.geometryObjects[g].parentJoint), geometry.geometryObjects[g].parentFrame)
                 for g in mine}
            )  # fmt: skip
            ends[k] = (order[0][1], order[-1][1])
    shared = _shared_anchors(clm)
    for a, b in itertools.combinations(range(geometry.ngeoms), 2):
        oa, ob = owners[a], owners[b]
        if oa == ob or (min(oa, ob), max(oa, ob)) in shared:
            continue
        if min(oa, ob) < 0 <= max(oa, ob):  # a plate and a leg body
            plate, g = (oa, b) if oa < 0 else (ob, a)
            if geometry.geometryObjects[g].parentFrame == ends[max(oa, ob)][0 if plate == -1 else 1]:
                continue
        geometry.addCollisionPair(pin.CollisionPair(a, b))
    return CollisionModel(geometry, tuple(owners), tuple(names))
