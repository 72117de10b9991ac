"""Write a hexapod as MJCF (MuJoCo's format), loop closures included, from its URDF tree.

MJCF can hold what URDF cannot: the six loop closures, as ``<equality>`` elements that MuJoCo
and Pinocchio's MJCF parser both read. The writer translates a URDF that follows
``docs/urdf_contract.md`` element by element, so both files hold the same decimal numbers:

* every URDF link is a ``<body>`` (same name) whose ``pos``/``quat`` is its joint's origin;
  ``revolute`` -> ``hinge``, ``prismatic`` -> ``slide`` (same name, axis and ``range``),
  ``fixed`` -> a body without joint, ``floating`` -> ``<freejoint>``;
* the root link is a static body fused into the world (``fusestatic``), so that MuJoCo sees the
  platform's free joint at top level while Pinocchio, which reads only the first body under
  ``<worldbody>``, still finds the whole tree in it;
* children are sorted by joint name, as Pinocchio's URDF parser orders them: both loaders give
  the same configuration layout;
* a closure's ``link1``/``link2`` get a site ``<link>_site`` at their origin, and a ``weld``
  (``6d``: the site frames coincide) or ``connect`` (``3d``: their origins coincide) joins the
  two sites, named after the closure, with :data:`EQUALITY_SOLREF` / :data:`EQUALITY_SOLIMP`
  and a comment naming the leg;
* every ``<collision>`` body is a geom named after it, in group :data:`COLLISION_GROUP`, a
  ``capsule`` where the URDF's ``<collision_checking>`` names one; with ``contype`` and
  ``conaffinity`` 0, as the visuals: MuJoCo computes no contacts between the parts of a
  mechanism whose loops it closes softly (the clearance is measured, not simulated);
* from a geometry (:func:`geometry_to_mjcf`), a ``<custom>`` element holding its joint cones and
  ``min_clearance`` (:mod:`~hexapod_model.description.mjcf_body`);
* with ``actuated``, one ``position`` actuator per measured (prismatic) joint, its control
  range the stroke (m).

Rotations are written as quaternions (w first) computed from the URDF ``rpy``; numbers have
at most :data:`~hexapod_model.description.urdf.DECIMALS` decimals, so the bytes are the same
on every machine. Angles are radians (``<compiler angle="radian">``).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

from ..exceptions import UrdfError
from ..lie import rpy_to_quaternion
from .geometry import HexapodGeometry
from .mjcf_body import body_limits_element
from .urdf import format_number, geometry_to_urdf, read_closures

#: closure constraint softness (MuJoCo ``solref``: time constant s, damping ratio); see docs/mjcf.md
EQUALITY_SOLREF = (0.005, 1.0)
#: closure constraint impedance (MuJoCo ``solimp``: dmin, dmax, width m, midpoint, power)
EQUALITY_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
ACTUATOR_KP = 3.0e4  # N/m: position actuator stiffness on a leg reading
ACTUATOR_KV = 600.0  # N s/m: its damping
JOINT_DAMPING = 0.2  # N m s/rad (hinge) or N s/m (slide) on every joint, so that a simulation comes to rest
TIMESTEP = 0.001  # s, with the implicitfast integrator
COLLISION_GROUP = 3  # MuJoCo geom group of the collision bodies (the visuals are group 1)

_JOINT_TYPES = {"revolute": "hinge", "prismatic": "slide"}
_f = format_number


def _numbers(text: str | None, default: tuple[float, ...], what: str, source: str) -> tuple[float, ...]:
    if text is None:
        return default
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        raise UrdfError(source, text, f"{what}: expected numbers") from None
    if len(values) != len(default) or not all(math.isfinite(v) for v in values):
        raise UrdfError(source, text, f"{what}: expected {len(default)} finite numbers")
    return values


def site_name(link: str) -> str:
    """Name of the MJCF site at the origin of closure link ``link`` (Pinocchio wants frame names unique)."""
    return f"{link}_site"


def _vec(values) -> str:
    return " ".join(_f(v) for v in values)


def _place(body: ET.Element, origin: ET.Element | None, what: str, source: str) -> None:
    """``pos`` and ``quat`` attributes of an MJCF element from a URDF ``<origin>`` (left out at zero)."""
    xyz = _numbers(origin.get("xyz") if origin is not None else None, (0.0, 0.0, 0.0), f"{what} xyz", source)
    rpy = _numbers(origin.get("rpy") if origin is not None else None, (0.0, 0.0, 0.0), f"{what} rpy", source)
    if any(_f(v) != "0" for v in xyz):
        body.set("pos", _vec(xyz))
    if any(_f(v) != "0" for v in rpy):
        x, y, z, w = rpy_to_quaternion(*rpy)
        body.set("quat", _vec((w, x, y, z)))


class _Converter:
    """One URDF tree translated into the ``<worldbody>`` of an MJCF document."""

    def __init__(self, urdf_xml: str, source: str):
        self.source = source
        try:
            self.robot = ET.fromstring(urdf_xml)
        except ET.ParseError as exc:
            raise UrdfError(source, str(exc), "not well-formed XML") from None
        self.closures = read_closures(urdf_xml, source)
        self.links = {str(el.get("name")): el for el in self.robot.findall("link")}
        self.joints = self.robot.findall("joint")
        self.children: dict[str, list[ET.Element]] = {}
        for j in self.joints:
            parent, child = j.find("parent"), j.find("child")
            if parent is None or child is None or child.get("link") not in self.links:
                raise UrdfError(source, j.get("name"), "joint without a valid <parent>/<child> link")
            self.children.setdefault(str(parent.get("link")), []).append(j)
        child_links = {j.find("child").get("link") for j in self.joints}  # type: ignore[union-attr]
        roots = [name for name in self.links if name not in child_links]
        if len(roots) != 1:
            raise UrdfError(source, roots, "need exactly one root link")
        self.root = roots[0]
        self.rgba = {
            m.get("name"): m.find("color").get("rgba")  # type: ignore[union-attr]
            for m in self.robot.findall("material")
            if m.find("color") is not None
        }
        self.sites = {c.link1 for c in self.closures} | {c.link2 for c in self.closures}
        self.skipped: list[str] = []
        self.ranges: dict[str, str] = {}  # joint name -> MJCF range

    def body(self, parent: ET.Element, link: str, joint: ET.Element | None) -> None:
        body = ET.SubElement(parent, "body", name=link)
        if joint is not None:
            name, kind = joint.get("name"), joint.get("type")
            _place(body, joint.find("origin"), f"joint {name} origin", self.source)
            if kind == "floating":
                ET.SubElement(body, "freejoint", name=str(name))
            elif kind in _JOINT_TYPES:
                limit = joint.find("limit")
                if limit is None or limit.get("lower") is None or limit.get("upper") is None:
                    raise UrdfError(self.source, name, "a revolute or prismatic joint needs <limit lower upper>")
                lo = _numbers(limit.get("lower"), (0.0,), f"joint {name} lower limit", self.source)[0]
                hi = _numbers(limit.get("upper"), (0.0,), f"joint {name} upper limit", self.source)[0]
                axis_el = joint.find("axis")
                xyz = axis_el.get("xyz") if axis_el is not None else None
                axis = _numbers(xyz, (1.0, 0.0, 0.0), f"joint {name} axis", self.source)
                self.ranges[str(name)] = f"{_f(lo)} {_f(hi)}"
                ET.SubElement(
                    body,
                    "joint",
                    name=str(name),
                    type=_JOINT_TYPES[kind],
                    axis=_vec(axis),
                    range=self.ranges[str(name)],
                )
            elif kind != "fixed":
                raise UrdfError(self.source, name, f"joint type {kind!r} has no MJCF counterpart here")
        self.inertial(body, self.links[link])
        for k, vis in enumerate(self.links[link].findall("visual")):
            self.geom(body, vis, f"{link}_visual{k}")
        self.collisions(body, self.links[link])
        if link in self.sites:
            ET.SubElement(body, "site", name=site_name(link))
        for j in sorted(self.children.get(link, []), key=lambda j: str(j.get("name"))):
            self.body(body, str(j.find("child").get("link")), j)  # type: ignore[union-attr]

    def inertial(self, body: ET.Element, link: ET.Element) -> None:
        el = link.find("inertial")
        if el is None:
            return
        out = ET.SubElement(body, "inertial")
        _place(out, el.find("origin"), f"link {link.get('name')} inertial", self.source)
        out.set("pos", out.get("pos", "0 0 0"))  # required by MuJoCo
        mass = el.find("mass")
        out.set("mass", _f(_numbers(mass.get("value") if mass is not None else None, (0.0,), "mass", self.source)[0]))
        i = el.find("inertia")
        keys = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
        values = [float(i.get(k, "0")) if i is not None else 0.0 for k in keys]
        if any(values[3:]):
            out.set("fullinertia", _vec(values))
        else:
            out.set("diaginertia", _vec(values[:3]))

    def geom(self, body: ET.Element, vis: ET.Element, name: str) -> None:
        shape = vis.find("geometry")
        kids = list(shape) if shape is not None else []
        if not kids or kids[0].tag not in ("box", "cylinder", "sphere"):
            self.skipped.append(f"{name} ({kids[0].tag if kids else 'no geometry'})")
            return
        g, kind = kids[0], kids[0].tag
        if kind == "box":
            size = _vec(v / 2 for v in _numbers(g.get("size"), (0.0,) * 3, f"{name} size", self.source))
        elif kind == "cylinder":
            r, length = (_numbers(g.get(k), (0.0,), f"{name} {k}", self.source)[0] for k in ("radius", "length"))
            size = f"{_f(r)} {_f(length / 2)}"
        else:
            size = _f(_numbers(g.get("radius"), (0.0,), f"{name} radius", self.source)[0])
        geom = ET.SubElement(body, "geom", name=name, type=kind, size=size)
        _place(geom, vis.find("origin"), name, self.source)
        material = vis.find("material")
        if material is not None:
            colour = material.find("color")
            rgba = colour.get("rgba") if colour is not None else self.rgba.get(material.get("name"))
            if rgba is not None:
                geom.set("rgba", _vec(_numbers(rgba, (0.0,) * 4, f"{name} rgba", self.source)))
        geom.set("contype", "0")  # visual only: no contacts between the parts of the mechanism
        geom.set("conaffinity", "0")
        geom.set("group", "1")

    def collisions(self, body: ET.Element, link: ET.Element) -> None:
        """The link's ``<collision>`` bodies as inert geoms of :data:`COLLISION_GROUP` (capsules stay capsules)."""
        block = link.find("collision_checking")
        capsules = {c.get("name") for c in block.findall("capsule")} if block is not None else set()
        for k, col in enumerate(link.findall("collision")):
            name = col.get("name") or f"{link.get('name')}_collision{k}"
            shape = col.find("geometry")
            kids = list(shape) if shape is not None else []
            if not kids or kids[0].tag not in ("cylinder", "sphere"):
                self.skipped.append(f"{name} ({kids[0].tag if kids else 'no geometry'})")
                continue
            g = kids[0]
            r = _numbers(g.get("radius"), (0.0,), f"{name} radius", self.source)[0]
            if g.tag == "sphere":
                kind, size = "sphere", _f(r)
            else:
                length = _numbers(g.get("length"), (0.0,), f"{name} length", self.source)[0]
                kind, size = ("capsule" if name in capsules else "cylinder"), f"{_f(r)} {_f(length / 2)}"
            geom = ET.SubElement(body, "geom", name=name, type=kind, size=size)
            _place(geom, col.find("origin"), name, self.source)
            geom.set("contype", "0")  # MuJoCo's contacts would fight the closures: measured, not simulated
            geom.set("conaffinity", "0")
            geom.set("group", str(COLLISION_GROUP))

    def measured_joint(self, tip: str) -> str:
        """The prismatic joint on the chain from the root to link ``tip``."""
        parents = {str(j.find("child").get("link")): j for j in self.joints}  # type: ignore[union-attr]
        link, found = tip, []
        while link in parents:
            j = parents[link]
            if j.get("type") == "prismatic":
                found.append(str(j.get("name")))
            link = str(j.find("parent").get("link"))  # type: ignore[union-attr]
        if len(found) != 1:
            raise UrdfError(self.source, found or tip, "the leg chain must hold exactly one prismatic joint")
        return found[0]


def urdf_to_mjcf(urdf_xml: str, *, actuated: bool = False, source: str = "<string>") -> str:
    """MJCF text of a hexapod URDF (see the module docstring); deterministic.

    Args:
        urdf_xml: a URDF following ``docs/urdf_contract.md``, ``<loop_closure>`` elements included.
        actuated: add a ``position`` actuator (named after the joint) on every measured joint.
        source: file name used in error messages.

    Raises:
        UrdfError: the URDF is malformed or uses a joint type or limit the translation needs,
            or it carries an ``<encoder>`` reading model (a calibrated geometry), which MJCF
            has no place for: the exported file would read joint values as readings.
    """
    return _to_mjcf(urdf_xml, actuated, source, None)


def _to_mjcf(urdf_xml: str, actuated: bool, source: str, custom: ET.Element | None) -> str:
    """:func:`urdf_to_mjcf`, with a ``<custom>`` element (the body limits) after the equalities."""
    conv = _Converter(urdf_xml, source)
    if conv.robot.find("encoder") is not None:
        raise UrdfError(source, "<encoder>", "MJCF cannot carry the encoder zero/scale of a calibrated geometry")
    name = conv.robot.get("name", "hexapod")
    root = ET.Element("mujoco", model=name)
    ET.SubElement(root, "compiler", angle="radian", autolimits="true", fusestatic="true", inertiafromgeom="false")
    ET.SubElement(root, "option", timestep=_f(TIMESTEP), integrator="implicitfast")
    ET.SubElement(ET.SubElement(root, "default"), "joint", damping=_f(JOINT_DAMPING))
    world = ET.SubElement(root, "worldbody")
    conv.body(world, conv.root, None)
    _light_and_floor(world)
    equality = ET.SubElement(root, "equality")
    legs = []
    for c in conv.closures:
        leg = conv.measured_joint(c.link1)
        legs.append(leg)
        what = "frames coincide (6d)" if c.kind == "6d" else "origins coincide (3d, ball joint)"
        equality.append(
            ET.Comment(
                f" {c.name}: the tip of the leg of {leg} ({c.link1}) meets its platform anchor ({c.link2}): {what} "
            )
        )
        ET.SubElement(
            equality,
            "weld" if c.kind == "6d" else "connect",
            name=c.name,
            site1=site_name(c.link1),
            site2=site_name(c.link2),
            solref=_vec(EQUALITY_SOLREF),
            solimp=_vec(EQUALITY_SOLIMP),
        )
    if custom is not None:
        root.append(custom)
    if actuated:
        actuator = ET.SubElement(root, "actuator")
        actuator.append(ET.Comment(" one position actuator per leg: ctrl is the leg reading (m, zero at home) "))
        for leg in legs:
            ET.SubElement(
                actuator,
                "position",
                name=leg,
                joint=leg,
                kp=_f(ACTUATOR_KP),
                kv=_f(ACTUATOR_KV),
                ctrlrange=conv.ranges[leg],
            )
    ET.indent(root)
    header = (
        f'<?xml version="1.0"?>\n<!-- Generated by hexapod_model from the URDF of {name!r}; do not edit, regenerate '
        f"with `hexapod mjcf`. Units: m, rad, kg. The body poses are the home pose (all leg joints zero). -->\n"
    )
    if conv.skipped:
        header += (
            f"<!-- visuals left out (only boxes, cylinders and spheres are translated): {', '.join(conv.skipped)} -->\n"
        )
    return header + ET.tostring(root, encoding="unicode") + "\n"


#: the name of the exported floor plane (a scene geom: the hexapod's visual model leaves it out)
FLOOR = "floor"


def _light_and_floor(world: ET.Element) -> None:
    """A light above the model and a floor plane just below its base, both after the model's tree.

    Without a light MuJoCo renders the scene dark. The floor is visual only (``contype`` and
    ``conaffinity`` 0: no contact with the model) and sits below the lowest base geom, so it
    hides nothing. Pinocchio's parser reads only the first ``<body>``: neither changes the model.
    """
    base = world.find("body")
    geoms = [] if base is None else base.findall("geom")
    extent, lowest = 0.1, 0.0  # m
    for g in geoms:
        pos = [float(v) for v in g.get("pos", "0 0 0").split()]
        size = [float(v) for v in g.get("size", "0").split()]
        reach = max(size) if size else 0.0
        extent = max(extent, math.hypot(pos[0], pos[1]) + reach)
        lowest = min(lowest, pos[2] - reach)
    floor_z = lowest - 0.01 * extent
    ET.SubElement(world, "light", name="light", pos=_vec((0.0, 0.0, 6.0 * extent)), dir="0 0 -1", directional="true")
    ET.SubElement(
        world,
        "geom",
        name=FLOOR,
        type="plane",
        pos=_vec((0.0, 0.0, floor_z)),
        size=_vec((4.0 * extent, 4.0 * extent, 0.1 * extent)),
        rgba="0.85 0.85 0.85 1",
        contype="0",
        conaffinity="0",
    )


def geometry_to_mjcf(geom: HexapodGeometry, *, actuated: bool = False) -> str:
    """MJCF text of ``geom``: :func:`urdf_to_mjcf` of :func:`~hexapod_model.description.urdf.geometry_to_urdf`.

    The file carries the geometry's joint cones and ``min_clearance`` too, which a URDF cannot
    (:mod:`~hexapod_model.description.mjcf_body`).
    """
    return _to_mjcf(geometry_to_urdf(geom), actuated, f"<geometry {geom.name}>", body_limits_element(geom))
