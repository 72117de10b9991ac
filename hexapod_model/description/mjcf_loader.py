"""Load a hexapod MJCF through Pinocchio's MJCF parser and the constraint models it returns.

``pin.buildModelAndConstraintsFromMJCF`` gives the kinematic tree and one Pinocchio constraint
model per ``<equality>`` (``FrameAnchorConstraintModel`` for ``weld``, ``PointAnchorConstraintModel``
for ``connect``). :func:`load_mjcf` matches them to the equalities of the file by the sites they
join and hands both to :meth:`ClosedLoopModel.from_pinocchio`, after two adjustments:

* MuJoCo's free joint holds the platform's pose in the world frame, so Pinocchio's configuration
  of the MJCF model is absolute and its zero is not assembled. The home pose (MuJoCo's ``qpos0``,
  the platform body's ``pos``/``quat``) becomes the free flyer's joint placement instead, as for a
  URDF ``floating`` joint: configurations of both loaders then mean the same thing.
* Pinocchio 4.1 places that free flyer at ``(I, p - R p)`` for a platform body at ``(R, p)``
  instead of the identity (files of ``hexapod mjcf`` have ``R = I``, where both agree), and
  bounds its position to +-1.01 m; the placement becomes the home pose whatever Pinocchio gave,
  and the position is unbounded as with a URDF ``floating`` joint.

The file must follow docs/mjcf.md: the whole tree in the first body under ``<worldbody>``, the
platform on the only free joint, six ``weld`` or ``connect`` equalities naming ``site1`` (leg
tip) and ``site2`` (platform anchor), and all leg joints at zero in the body poses as written.
"""

from __future__ import annotations

import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import MjcfError, UrdfError
from .mjcf import COLLISION_GROUP
from .mjcf_body import read_body_limits
from .model import ClosedLoopModel, same_placement
from .urdf import Closure

MJCF_SUFFIXES = (".xml", ".mjcf")  # file names that Hexapod.load reads as MJCF
_KINDS = {"weld": "6d", "connect": "3d"}


def read_equalities(mjcf_xml: str, source: str = "<string>") -> list[Closure]:
    """The ``weld``/``connect`` equalities of an MJCF, in file order, as closures between sites.

    ``link1``/``link2`` of each :class:`~hexapod_model.description.urdf.Closure` are the names of
    ``site1``/``site2``.

    Raises:
        MjcfError: malformed XML, not an MJCF, an equality without name or sites, a site that
            the first body under ``<worldbody>`` (the tree Pinocchio reads) does not hold
            (Pinocchio 4.1's parser crashes on one), another type of equality, an inactive one.
    """
    try:
        root = ET.fromstring(mjcf_xml)
    except ET.ParseError as exc:
        raise MjcfError(source, str(exc), "not well-formed XML") from None
    if root.tag != "mujoco":
        raise MjcfError(source, root.tag, "an MJCF file has <mujoco> as its root element")
    world = root.find("worldbody")
    tree = world.find("body") if world is not None else None
    if tree is None:
        raise MjcfError(source, "worldbody", "the MJCF has no <body> under <worldbody>")
    sites = {el.get("name") for el in tree.iter("site")}  # Pinocchio reads the first body only
    out = []
    for eq in root.iter("equality"):
        for el in eq:
            if not isinstance(el.tag, str):
                continue  # a comment
            if el.tag not in _KINDS:
                raise MjcfError(source, el.tag, "only weld and connect equalities close hexapod legs")
            attrs = {k: el.get(k) for k in ("name", "site1", "site2")}
            missing = [k for k, v in attrs.items() if not v]
            if missing:
                raise MjcfError(source, ET.tostring(el, encoding="unicode").strip()[:120], f"equality lacks {missing}")
            if el.get("active", "true") != "true":
                raise MjcfError(source, attrs["name"], "an inactive equality does not close a leg")
            for key in ("site1", "site2"):
                if attrs[key] not in sites:
                    raise MjcfError(
                        source,
                        attrs[key],
                        f"equality {attrs['name']!r} names a site missing from the first body under <worldbody>",
                    )
            out.append(Closure(str(attrs["name"]), _KINDS[el.tag], str(attrs["site1"]), str(attrs["site2"])))
    if not out:
        raise MjcfError(source, "equality", "the MJCF declares no weld or connect equality")
    return out


def load_mjcf(path: str | Path) -> ClosedLoopModel:
    """A :class:`ClosedLoopModel` of the MJCF file ``path`` (see the module docstring).

    Raises:
        MjcfError: unreadable file, or a file that breaks the contract of docs/mjcf.md (the
            message names the element, joint or closure).
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise MjcfError(str(path), str(path), f"cannot read MJCF: {exc.strerror}") from None
    return _load(text, path, str(path))


def load_mjcf_text(mjcf_xml: str, source: str = "<string>") -> ClosedLoopModel:
    """:func:`load_mjcf` of MJCF text (Pinocchio's parser reads files: through a temporary one)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "hexapod.xml"
        path.write_text(mjcf_xml)
        return _load(mjcf_xml, path, source)


def _load(text: str, path: Path, source: str) -> ClosedLoopModel:
    closures = read_equalities(text, source)
    read_body_limits(text, source)  # a bad cone or bound is named at loading, not at the first check
    try:
        model, points, frames = pin.buildModelAndConstraintsFromMJCF(str(path))
    except (RuntimeError, ValueError) as exc:
        raise MjcfError(source, str(exc).strip()[:200], "Pinocchio cannot parse the MJCF") from None
    _place_home(model, source)
    constraints = [_constraint_of(model, c, list(frames) + list(points), source) for c in closures]
    try:
        clm = ClosedLoopModel.from_pinocchio(model, closures, constraints, source)
    except UrdfError as exc:
        raise MjcfError(source, exc.value, exc.reason) from None
    clm.mjcf_xml = text
    return clm


def mjcf_collision_bodies(clm: ClosedLoopModel) -> pin.GeometryModel:
    """The collision bodies of the MJCF ``clm`` was loaded from, on its model, named as in the file.

    They are the named geoms of group :data:`~hexapod_model.description.mjcf.COLLISION_GROUP`,
    in file order (the ``<collision>`` bodies of the URDF ``hexapod mjcf`` translated).

    Pinocchio's parser files a geom with ``contype`` and ``conaffinity`` 0 (the writer's inert
    collision geoms) under the visual model and any other under the collision model: both are
    read, and the group decides. Empty for a model not loaded from an MJCF or an MJCF without such
    geoms.
    """
    if clm.mjcf_xml is None:
        return pin.GeometryModel()
    wanted = [
        str(el.get("name"))
        for el in ET.fromstring(clm.mjcf_xml).iter("geom")
        if el.get("group") == str(COLLISION_GROUP) and el.get("name")
    ]
    found: dict[str, pin.GeometryObject] = {}
    with tempfile.TemporaryDirectory() as tmp:  # Pinocchio reads MJCF from files only
        path = Path(tmp) / "hexapod.xml"
        path.write_text(clm.mjcf_xml)
        for kind in (pin.GeometryType.VISUAL, pin.GeometryType.COLLISION):
            for go in pin.buildGeomFromMJCF(clm.model, str(path), kind).geometryObjects:
                found.setdefault(go.name, go)
    out = pin.GeometryModel()
    for name in wanted:
        if name in found:
            out.addGeometryObject(found[name].copy())
    return out


def _place_home(model: pin.Model, source: str) -> None:
    """Move the free flyer's ``qpos0`` (the home pose, world frame) into its joint placement."""
    ff = [j for j in range(1, model.njoints) if model.joints[j].shortname() == "JointModelFreeFlyer"]
    q0 = np.asarray(model.referenceConfigurations["qpos0"]) if "qpos0" in model.referenceConfigurations else None
    if len(ff) != 1 or model.parents[ff[0]] != 0 or q0 is None:
        return  # ClosedLoopModel names what is wrong
    for j in range(1, model.njoints):
        jm = model.joints[j]
        if j != ff[0] and np.any(q0[jm.idx_q : jm.idx_q + jm.nq] != 0.0):
            raise MjcfError(source, model.names[j], "leg joints must be zero in the model as written (no joint 'ref')")
    jm = model.joints[ff[0]]
    model.jointPlacements[ff[0]] = pin.XYZQUATToSE3(q0[jm.idx_q : jm.idx_q + 7])
    model.lowerPositionLimit[jm.idx_q : jm.idx_q + 3] = -np.inf  # a free joint has no limits (Pinocchio: +-1.01 m)
    model.upperPositionLimit[jm.idx_q : jm.idx_q + 3] = np.inf
    model.referenceConfigurations["qpos0"] = pin.neutral(model)


def _constraint_of(model: pin.Model, closure: Closure, candidates: list, source: str):
    """The Pinocchio constraint model that joins the two sites of ``closure``."""
    sites = []
    for name in (closure.link1, closure.link2):
        if not model.existFrame(name, pin.FrameType.OP_FRAME):
            raise MjcfError(source, name, f"equality {closure.name!r} names a site that Pinocchio did not load")
        sites.append(model.frames[model.getFrameId(name, pin.FrameType.OP_FRAME)])
    kind = pin.FrameAnchorConstraintModel if closure.kind == "6d" else pin.PointAnchorConstraintModel
    for c in candidates:
        if (
            isinstance(c, kind)
            and (c.joint1_id, c.joint2_id) == (sites[0].parentJoint, sites[1].parentJoint)
            and same_placement(c.joint1_placement, sites[0].placement)
            and same_placement(c.joint2_placement, sites[1].placement)
        ):
            return c
    raise MjcfError(source, closure.name, "Pinocchio's MJCF parser returned no constraint model joining its sites")


def mujoco_qpos(clm: ClosedLoopModel, q: np.ndarray, mj_model) -> np.ndarray:
    """MuJoCo's ``qpos`` for configuration ``q`` of ``clm``, for ``mj_model`` built from the same MJCF.

    Joints are matched by name. ``q`` holds the platform relative to home with a quaternion
    ``x, y, z, w`` (Pinocchio); MuJoCo's free joint holds it in the world (base) frame, position
    in metres then the quaternion ``w, x, y, z``.

    Args:
        clm: the hexapod (from :func:`load_mjcf`, or from the URDF the MJCF was written from).
        q: its configuration (``clm.nq``).
        mj_model: a ``mujoco.MjModel`` (only ``qpos0`` and ``joint(name).qposadr`` are used).
    """
    q = np.asarray(q, dtype=float)
    out = np.array(mj_model.qpos0, dtype=float)
    m = clm.model
    for j in range(1, m.njoints):
        jm, a = m.joints[j], int(mj_model.joint(m.names[j]).qposadr[0])
        if j == clm.platform_joint:
            x, y, z, qx, qy, qz, qw = pin.SE3ToXYZQUAT(clm.home * pin.XYZQUATToSE3(q[jm.idx_q : jm.idx_q + 7]))
            out[a : a + 7] = (x, y, z, qw, qx, qy, qz)
        else:
            out[a : a + jm.nq] = q[jm.idx_q : jm.idx_q + jm.nq]
    return out


def q_of_mujoco_qpos(clm: ClosedLoopModel, qpos: np.ndarray, mj_model) -> np.ndarray:
    """The inverse of :func:`mujoco_qpos`: configuration of ``clm`` for MuJoCo's ``qpos``."""
    qpos = np.asarray(qpos, dtype=float)
    q = np.empty(clm.nq)
    m = clm.model
    for j in range(1, m.njoints):
        jm, a = m.joints[j], int(mj_model.joint(m.names[j]).qposadr[0])
        if j == clm.platform_joint:
            quat = qpos[a + 3 : a + 7] / np.linalg.norm(qpos[a + 3 : a + 7])  # w, x, y, z
            world = pin.XYZQUATToSE3(np.r_[qpos[a : a + 3], quat[1:], quat[0]])
            q[jm.idx_q : jm.idx_q + 7] = pin.SE3ToXYZQUAT(clm.home.inverse() * world)
        else:
            q[jm.idx_q : jm.idx_q + jm.nq] = qpos[a : a + jm.nq]
    return q
