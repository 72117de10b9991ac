"""The ``<collision>`` elements of a generated URDF: the machine's body (docs/urdf_contract.md).

Every body is a shape the distance queries of coal handle exactly:

* each **leg** is two capsules of the leg's ``leg_radius`` on its axis: the cylinder, fixed to
  the leg's base side, from the base joint (the second base Cardan axis) over the retracted
  length ``rest + stroke_min``, and the rod, fixed to the platform side, the same length down
  from the platform joint. They overlap at every reading up to
  ``stroke_min + (rest + stroke_min)``; a leg whose stroke runs beyond that (its stroke longer
  than its retracted length, which a one-stage telescope cannot have) has a gap between them
  at the longest readings. A guideway leg's strut is one capsule from its Cardan joint to its
  ball joint;
* each **joint housing** is a sphere of ``housing_radius`` about the joint centre, on the leg's
  first and last link;
* the two **plates** are discs (cylinders) of ``plate_thickness``, their faces
  ``housing_radius`` below the lowest base joint centre (or the lowest end of a guideway) and
  above the highest platform joint centre.

URDF has no capsule element: a capsule is written as a ``<cylinder>`` (its straight part)
named in the link's ``<collision_checking><capsule name=.../></collision_checking>`` block,
the convention Pinocchio's URDF parser reads as a capsule. Tools that do not know it see a
cylinder of the same radius and length.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from .geometry import HexapodGeometry
from .legs import axes_of


def _rpy(R: np.ndarray) -> tuple[float, float, float]:
    """URDF rpy (``R = Rz(y) Ry(p) Rx(r)``, rad) of a rotation matrix."""
    pitch = np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0]))
    return float(np.arctan2(R[2, 1], R[2, 2])), float(pitch), float(np.arctan2(R[1, 0], R[0, 0]))


def _z_to(d: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is the unit vector ``d`` (identity for ``d`` = z)."""
    d = d / np.linalg.norm(d)
    if abs(d[2] - 1.0) < 1e-15:
        return np.eye(3)
    x = np.cross([0.0, 1.0, 0.0], d) if abs(d[1]) < 0.9 else np.cross([1.0, 0.0, 0.0], d)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(d, x), d])


#: one collision body: (link, name, shape, size, origin xyz, origin rotation)
#: shape "capsule" or "cylinder": size (radius, length); "sphere": (radius,)
Body = tuple[str, str, str, tuple[float, ...], np.ndarray, np.ndarray]


def plate_levels(geom: HexapodGeometry) -> tuple[float, float]:
    """Heights (m): the lowest base joint centre (base frame), the highest platform joint centre (platform frame)."""
    zb = float(np.min(geom.base_points()[:, 2]))
    if geom.joint_type == "guideway":
        assert all(leg.guideway is not None for leg in geom.legs)
        zb = min(zb, min(leg.base_anchor[2] + min(s * leg.guideway[2] for s in leg.stroke) for leg in geom.legs))  # type: ignore[index]
    return zb, float(np.max(geom.platform_points()[:, 2]))


def collision_bodies(geom: HexapodGeometry) -> list[Body]:
    """The collision bodies of ``geom``'s URDF, link by link (see the module doc)."""
    zb, zp = plate_levels(geom)
    h, t = geom.housing_radius, geom.plate_thickness
    rb = geom.base_plate_radius
    if rb is None:
        rb = float(np.max(np.linalg.norm(geom.base_points()[:, :2], axis=1))) + h
    rp = geom.platform_plate_radius
    if rp is None:
        rp = float(np.max(np.linalg.norm(geom.platform_points()[:, :2], axis=1))) + h
    eye = np.eye(3)
    out: list[Body] = [
        ("base_link", "base_plate", "cylinder", (rb, t), np.array([0.0, 0.0, zb - h - t / 2]), eye),
        ("platform", "platform_plate", "cylinder", (rp, t), np.array([0.0, 0.0, zp + h + t / 2]), eye),
    ]
    for i, leg in enumerate(geom.legs):
        n = f"leg{i + 1}"
        axes = axes_of(geom, i)
        eb, _ = geom.offsets(i)
        r, rest = geom.leg_radius_of(i), float(axes.rest)
        out.append((f"{n}_base_yoke", f"{n}_base_housing", "sphere", (h,), np.array([0.0, 0.0, eb / 2]), eye))
        w = np.asarray(axes.roll[:, 2], dtype=float)  # the leg axis in the base cross frame
        along = _z_to(w)
        if geom.joint_type == "guideway":
            out.append((f"{n}_base_cross", f"{n}_strut", "capsule", (r, rest), w * rest / 2, along))
        else:
            short = rest + leg.stroke[0]  # the retracted length (m)
            tube_link = f"{n}_cylinder" if geom.joint_type == "cardan" else f"{n}_base_cross"
            tube_frame = (np.array([0.0, 0.0, 1.0]), eye) if geom.joint_type == "cardan" else (w, along)
            out.append((tube_link, f"{n}_cylinder", "capsule", (r, short), tube_frame[0] * short / 2, tube_frame[1]))
            out.append((f"{n}_rod", f"{n}_rod", "capsule", (r, short), np.array([0.0, 0.0, rest - short / 2]), eye))
        out.append((f"{n}_tip", f"{n}_platform_housing", "sphere", (h,), np.zeros(3), eye))
    return out


def add_collisions(robot: ET.Element, geom: HexapodGeometry, fmt) -> None:
    """Append ``geom``'s :func:`collision_bodies` to the ``<link>`` elements of ``robot``.

    Args:
        robot: the ``<robot>`` element, its links already written.
        geom: the geometry.
        fmt: the number formatter of the URDF writer (fixed decimals).
    """
    links = {el.get("name"): el for el in robot.findall("link")}
    capsules: dict[str, list[str]] = {}
    for link, name, shape, size, xyz, R in collision_bodies(geom):
        el = links[link]
        col = ET.Element("collision", name=name)
        el.insert(len(el.findall("visual")), col)
        ET.SubElement(col, "origin", xyz=" ".join(fmt(v) for v in xyz), rpy=" ".join(fmt(v) for v in _rpy(R)))
        shape_el = ET.SubElement(col, "geometry")
        if shape == "sphere":
            ET.SubElement(shape_el, "sphere", radius=fmt(size[0]))
        else:
            ET.SubElement(shape_el, "cylinder", radius=fmt(size[0]), length=fmt(size[1]))
        if shape == "capsule":
            capsules.setdefault(link, []).append(name)
    for link, names in capsules.items():
        block = ET.SubElement(links[link], "collision_checking")
        for name in names:
            ET.SubElement(block, "capsule", name=name)
