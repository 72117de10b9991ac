"""Write a hexapod geometry as a URDF tree, and read the loop closures back.

The generated file follows the contract in ``docs/urdf_contract.md``:

* root link ``base_link``; the platform link ``platform`` hangs from it on one ``floating``
  joint ``platform_joint`` whose origin is the home pose;
* leg ``i`` (1..6) is an open chain of links ``leg{i}_*`` from ``base_link`` to its tip
  link ``leg{i}_tip``; it holds exactly one ``prismatic`` joint, ``leg{i}_prismatic``,
  whose value is the leg reading (m, zero at home);
* all leg joints at zero close every loop at home;
* the closures are declared at robot level, in leg order::

      <loop_closure name="leg1" type="6d" link1="leg1_tip" link2="leg1_anchor"/>

  ``6d``: the two link frames coincide; ``3d``: their origins coincide (ball joints).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .exceptions import UrdfError
from .geometry import HexapodGeometry

COLOURS = {
    "base": (0.25, 0.27, 0.30, 1.0),
    "platform": (0.20, 0.45, 0.75, 1.0),
    "cylinder": (0.95, 0.55, 0.10, 1.0),
    "rod": (0.75, 0.76, 0.78, 1.0),
    "joint": (0.70, 0.12, 0.15, 1.0),
    "axis": (0.10, 0.10, 0.10, 1.0),
    "rail": (0.45, 0.45, 0.40, 1.0),
    "x_axis": (0.85, 0.10, 0.10, 1.0),
    "y_axis": (0.10, 0.65, 0.10, 1.0),
    "z_axis": (0.10, 0.25, 0.90, 1.0),
}
TRIAD_LENGTH = 0.10  # m, platform frame triad drawn in the URDF visuals


@dataclass(frozen=True)
class Closure:
    """One declared loop closure: ``link1`` (leg tip) must meet ``link2`` (platform anchor).

    ``kind`` is ``"6d"`` (frames coincide) or ``"3d"`` (origins coincide).
    """

    name: str
    kind: str
    link1: str
    link2: str


def _f(x: float) -> str:
    return repr(float(x)) if x != 0 else "0"


def _xyz(v) -> str:
    return " ".join(_f(x) for x in v)


def _rpy(R: np.ndarray) -> str:
    """URDF rpy (R = Rz(y) Ry(p) Rx(r)) of a rotation matrix."""
    pitch = np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0]))
    roll = np.arctan2(R[2, 1], R[2, 2])
    yaw = np.arctan2(R[1, 0], R[0, 0])
    return _xyz((roll, pitch, yaw))


def leg_frame(geom: HexapodGeometry, i: int) -> np.ndarray:
    """Rotation (base frame) of leg ``i``'s home frame: z along the leg, x the base Cardan axis."""
    w, _ = geom.home_leg_axis(i)
    a = geom.legs[i].base_axis
    if a is None:
        a = np.cross([0.0, 0.0, 1.0], w)
        if np.linalg.norm(a) < 1e-9:
            a = np.array([1.0, 0.0, 0.0])
    a = np.asarray(a, float) - np.dot(a, w) * w
    a /= np.linalg.norm(a)
    return np.column_stack([a, np.cross(w, a), w])


class _Writer:
    def __init__(self, name: str):
        self.robot = ET.Element("robot", name=name)
        for key, rgba in COLOURS.items():
            ET.SubElement(ET.SubElement(self.robot, "material", name=key), "color", rgba=_xyz(rgba))

    def link(self, name: str, visuals=()) -> None:
        link = ET.SubElement(self.robot, "link", name=name)
        for shape, size, xyz, rpy, colour in visuals:
            vis = ET.SubElement(link, "visual")
            ET.SubElement(vis, "origin", xyz=_xyz(xyz), rpy=_xyz(rpy))
            geo = ET.SubElement(vis, "geometry")
            if shape == "box":
                ET.SubElement(geo, "box", size=_xyz(size))
            else:
                ET.SubElement(geo, "cylinder", radius=_f(size[0]), length=_f(size[1]))
            ET.SubElement(vis, "material", name=colour)
        # a tiny inertia keeps every parser (and Pinocchio's dynamics) happy
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "mass", value="0.1")
        ET.SubElement(inertial, "inertia", ixx="1e-4", iyy="1e-4", izz="1e-4", ixy="0", ixz="0", iyz="0")

    def joint(self, name, kind, parent, child, xyz, rpy="0 0 0", axis=None, limit=None) -> None:
        j = ET.SubElement(self.robot, "joint", name=name, type=kind)
        ET.SubElement(j, "origin", xyz=_xyz(xyz), rpy=rpy)
        ET.SubElement(j, "parent", link=parent)
        ET.SubElement(j, "child", link=child)
        if axis is not None:
            ET.SubElement(j, "axis", xyz=_xyz(axis))
        if limit is not None:
            ET.SubElement(j, "limit", lower=_f(limit[0]), upper=_f(limit[1]), effort="1000", velocity="1")


def geometry_to_urdf(geom: HexapodGeometry) -> str:
    """URDF text of ``geom`` (deterministic: the same geometry gives the same bytes)."""
    w_ = _Writer(geom.name)
    base_r = float(np.max(np.linalg.norm(geom.base_points()[:, :2], axis=1)))
    plat_r = float(np.max(np.linalg.norm(geom.platform_points()[:, :2], axis=1)))
    zb = float(np.min(geom.base_points()[:, 2]))
    if geom.joint_type == "guideway":  # the plate goes under the lowest end of the rails
        zb = min(zb, min(leg.base_anchor[2] + min(s * leg.guideway[2] for s in leg.stroke) for leg in geom.legs))
    zp = float(np.max(geom.platform_points()[:, 2]))
    w_.link("base_link", [("cyl", (base_r + 0.04, 0.02), (0, 0, zb - 0.03), (0, 0, 0), "base")])
    top, half = zp + 0.035, TRIAD_LENGTH / 2
    w_.link("platform", [
        ("cyl", (plat_r + 0.03, 0.015), (0, 0, zp + 0.0275), (0, 0, 0), "platform"),
        ("cyl", (0.005, TRIAD_LENGTH), (half, 0, top), (0, np.pi / 2, 0), "x_axis"),  # frame triad on the plate
        ("cyl", (0.005, TRIAD_LENGTH), (0, half, top), (np.pi / 2, 0, 0), "y_axis"),
        ("cyl", (0.005, TRIAD_LENGTH), (0, 0, top + half), (0, 0, 0), "z_axis"),
    ])
    w_.joint("platform_joint", "floating", "base_link", "platform", geom.home_translation)
    lim = geom.cardan_limit
    closures = []
    for i in range(6):
        closures.append(_write_leg(w_, geom, i, lim))
    for c in closures:
        ET.SubElement(w_.robot, "loop_closure", name=c.name, type=c.kind, link1=c.link1, link2=c.link2)
    ET.indent(w_.robot)
    header = (f"<?xml version=\"1.0\"?>\n<!-- Generated by hexapod_model from geometry {geom.name!r} "
              f"({geom.joint_type} legs); do not edit, regenerate with `hexapod urdf`. -->\n")
    return header + ET.tostring(w_.robot, encoding="unicode") + "\n"


def _write_leg(w_: _Writer, geom: HexapodGeometry, i: int, lim: float) -> Closure:
    leg = geom.legs[i]
    n = f"leg{i + 1}"
    R = leg_frame(geom, i)
    w, length = geom.home_leg_axis(i)
    eb, ep = geom.base_offset, geom.platform_offset
    b = np.asarray(leg.base_anchor)
    block = 0.022  # m, Cardan joint blocks; their axis pins show the offset between the two axes
    blk = ("box", (block, block, block), (0, 0, 0), (0, 0, 0), "joint")
    ax_x = ("cyl", (0.005, 3 * block), (0, 0, 0), (0, np.pi / 2, 0), "axis")
    ax_y = ("cyl", (0.005, 3 * block), (0, 0, 0), (np.pi / 2, 0, 0), "axis")
    rpy = _rpy(R)
    parent, start = "base_link", b - eb / 2 * w
    if geom.joint_type == "guideway":
        g = np.asarray(leg.guideway)
        lo, hi = leg.stroke
        z = g
        x = np.cross([0.0, 0.0, 1.0], z) if abs(z[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
        x /= np.linalg.norm(x)
        rail_rot = np.column_stack([x, np.cross(z, x), z])
        rail = ("box", (0.012, 0.012, hi - lo + 0.04), (0, 0, (hi + lo) / 2), (0, 0, 0), "rail")
        w_.joint(f"{n}_rail_joint", "fixed", parent, f"{n}_rail", start - 0.015 * R[:, 1], _rpy(rail_rot))
        w_.link(f"{n}_rail", [rail])
        w_.joint(f"{n}_prismatic", "prismatic", parent, f"{n}_slider", start, rpy, axis=R.T @ g, limit=leg.stroke)
        w_.link(f"{n}_slider", [blk])
        parent, start = f"{n}_slider", np.zeros(3)
        rpy = "0 0 0"
    w_.joint(f"{n}_cardan_base_1", "revolute", parent, f"{n}_base_yoke", start, rpy, (1, 0, 0), (-lim, lim))
    w_.link(f"{n}_base_yoke", [blk, ax_x])
    w_.joint(f"{n}_cardan_base_2", "revolute", f"{n}_base_yoke", f"{n}_base_cross", (0, 0, eb), "0 0 0", (0, 1, 0), (-lim, lim))
    rest = length - eb / 2 - ep / 2  # from the 2nd base axis to the 1st platform axis
    tube = ("cyl", (0.02, 0.55 * rest), (0, 0, 0.275 * rest + 0.02), (0, 0, 0), "cylinder")
    rod = ("cyl", (0.011, 0.55 * rest), (0, 0, rest - 0.275 * rest - 0.01), (0, 0, 0), "rod")
    if geom.joint_type == "guideway":
        strut = ("cyl", (0.012, rest), (0, 0, rest / 2), (0, 0, 0), "rod")
        w_.link(f"{n}_base_cross", [ax_y, strut])
        w_.joint(f"{n}_tip_joint", "fixed", f"{n}_base_cross", f"{n}_tip", (0, 0, rest))
        w_.link(f"{n}_tip", [("cyl", (block / 1.5, 0.001), (0, 0, 0), (0, 0, 0), "joint")])
        return _anchor(w_, geom, i, np.eye(3), "3d")
    if geom.joint_type == "spherical":
        w_.link(f"{n}_base_cross", [ax_y, tube])
        w_.joint(f"{n}_prismatic", "prismatic", f"{n}_base_cross", f"{n}_rod", (0, 0, 0), axis=(0, 0, 1), limit=leg.stroke)
        w_.link(f"{n}_rod", [rod])
        w_.joint(f"{n}_tip_joint", "fixed", f"{n}_rod", f"{n}_tip", (0, 0, rest))
        w_.link(f"{n}_tip", [("cyl", (block / 1.5, 0.001), (0, 0, 0), (0, 0, 0), "joint")])
        return _anchor(w_, geom, i, np.eye(3), "3d")
    # cardan: roll + prismatic, then the platform Cardan joint
    w_.link(f"{n}_base_cross", [ax_y])
    w_.joint(f"{n}_roll", "revolute", f"{n}_base_cross", f"{n}_cylinder", (0, 0, 0), axis=(0, 0, 1),
             limit=(-geom.roll_limit, geom.roll_limit))
    w_.link(f"{n}_cylinder", [tube])
    w_.joint(f"{n}_prismatic", "prismatic", f"{n}_cylinder", f"{n}_rod", (0, 0, 0), axis=(0, 0, 1), limit=leg.stroke)
    w_.link(f"{n}_rod", [rod])
    c = leg.platform_axis if leg.platform_axis is not None else R[:, 0]
    phi = float(np.arctan2(np.dot(c, R[:, 1]), np.dot(c, R[:, 0])))
    Rz = np.array([[np.cos(phi), -np.sin(phi), 0], [np.sin(phi), np.cos(phi), 0], [0, 0, 1]])
    w_.joint(f"{n}_cardan_platform_1", "revolute", f"{n}_rod", f"{n}_platform_cross", (0, 0, rest),
             _xyz((0, 0, phi)), (0, 1, 0), (-lim, lim))
    w_.link(f"{n}_platform_cross", [blk, ax_y])
    w_.joint(f"{n}_cardan_platform_2", "revolute", f"{n}_platform_cross", f"{n}_platform_yoke", (0, 0, ep),
             "0 0 0", (1, 0, 0), (-lim, lim))
    w_.link(f"{n}_platform_yoke", [ax_x])
    w_.joint(f"{n}_tip_joint", "fixed", f"{n}_platform_yoke", f"{n}_tip", (0, 0, -ep / 2))
    w_.link(f"{n}_tip")
    return _anchor(w_, geom, i, R @ Rz, "6d")


def _anchor(w_: _Writer, geom: HexapodGeometry, i: int, rot: np.ndarray, kind: str) -> Closure:
    n = f"leg{i + 1}"
    w_.joint(f"{n}_anchor_joint", "fixed", "platform", f"{n}_anchor", geom.legs[i].platform_anchor, _rpy(rot))
    w_.link(f"{n}_anchor")
    return Closure(n, kind, f"{n}_tip", f"{n}_anchor")


def write_urdf(geom: HexapodGeometry, path: str | Path) -> Path:
    """Write ``geometry_to_urdf(geom)`` to ``path``; returns the path."""
    path = Path(path)
    path.write_text(geometry_to_urdf(geom))
    return path


def read_closures(urdf_xml: str, source: str = "<string>") -> list[Closure]:
    """The ``<loop_closure>`` elements of a URDF, in file order, validated.

    Raises:
        UrdfError: malformed XML, a closure with a missing attribute, a bad ``type``, or a
            link that the URDF does not define.
    """
    try:
        root = ET.fromstring(urdf_xml)
    except ET.ParseError as exc:
        raise UrdfError(source, str(exc), "not well-formed XML") from None
    links = {el.get("name") for el in root.findall("link")}
    out = []
    for el in root.findall("loop_closure"):
        attrs = {k: el.get(k) for k in ("name", "type", "link1", "link2")}
        missing = [k for k, v in attrs.items() if not v]
        if missing:
            raise UrdfError(source, ET.tostring(el, encoding="unicode").strip(), f"loop_closure lacks {missing}")
        if attrs["type"] not in ("6d", "3d"):
            raise UrdfError(source, attrs["type"], "loop_closure type must be '6d' or '3d'")
        for key in ("link1", "link2"):
            if attrs[key] not in links:
                raise UrdfError(source, attrs[key], f"loop_closure {attrs['name']!r} names a missing {key}")
        out.append(Closure(attrs["name"], attrs["type"], attrs["link1"], attrs["link2"]))
    if not out:
        raise UrdfError(source, "loop_closure", "the URDF declares no <loop_closure> element")
    return out
