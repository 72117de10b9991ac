"""The redundant sensors of a loaded hexapod as arrays, from its geometry or from its URDF.

The URDF variant of a geometry with redundant sensors (``docs/urdf_contract.md``) carries:

* per measuring leg ``leg{k}`` (k = 7, 8, ...): a link ``leg{k}_base`` fixed to ``base_link``
  at the base anchor, a link ``leg{k}_anchor`` fixed to ``platform`` at the platform anchor,
  and a seventh (eighth, ...) loop closure between them::

      <loop_closure name="leg7" type="distance" link1="leg7_base" link2="leg7_anchor"
                    stroke="-0.16 0.2" zero="0" scale="0"/>

  ``distance``: the distance between the two link origins is the measured value (the
  encoder model ``zero + (1 + scale) * change from home``); it constrains nothing else.
* an inclinometer: a link ``inclinometer`` fixed to ``platform`` (its mounting frame) and
  ``<inclinometer link="inclinometer" sigma="2e-05"/>`` (rad);
* the leg encoders' noise: ``<redundant_sensing encoder_sigma="1e-06"/>`` (m).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..exceptions import UrdfError
from .geometry import HexapodGeometry
from .sensors import DEFAULT_ENCODER_SIGMA, TILT_NAMES


def rpy_matrix(rpy: tuple[float, float, float] | np.ndarray) -> np.ndarray:
    """Rotation matrix ``Rz(yaw) Ry(pitch) Rx(roll)`` of URDF angles (rad)."""
    r, p, y = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


@dataclass(frozen=True)
class SensorLayout:
    """Measuring legs and inclinometer of one hexapod, as arrays (see :mod:`.sensors`).

    Attributes:
        base: (k, 3) measuring legs' base anchors, base frame (m).
        platform: (k, 3) their platform anchors, platform frame (m).
        stroke: (k, 2) their reading limits (m).
        zero: (k,) their readings at home (m).
        scale: (k,) their relative scale errors.
        tilt_rotation: (3, 3) the inclinometer's mounting frame in the platform frame, or ``None``.
        tilt_sigma: standard deviation of an inclinometer angle (rad).
        encoder_sigma: standard deviation of a leg encoder's reading (m).
    """

    base: np.ndarray
    platform: np.ndarray
    stroke: np.ndarray
    zero: np.ndarray
    scale: np.ndarray
    tilt_rotation: np.ndarray | None
    tilt_sigma: float
    encoder_sigma: float

    @property
    def names(self) -> tuple[str, ...]:
        """Names of all readings, in the order ``Hexapod.forward`` takes them."""
        legs = tuple(f"leg{i + 1}" for i in range(6 + len(self.base)))
        return legs + (TILT_NAMES if self.tilt_rotation is not None else ())

    @property
    def sigmas(self) -> np.ndarray:
        """Standard deviation of each reading (m for legs, rad for tilts), reading order."""
        legs = np.full(6 + len(self.base), self.encoder_sigma)
        return np.concatenate([legs, np.full(2 if self.tilt_rotation is not None else 0, self.tilt_sigma)])

    @classmethod
    def from_geometry(cls, geometry: HexapodGeometry) -> SensorLayout | None:
        """The layout of ``geometry``'s redundant sensors, ``None`` without any."""
        if not geometry.redundant:
            return None
        ms = geometry.measuring_legs
        incl = geometry.inclinometer
        return cls(
            base=np.array([m.base_anchor for m in ms], dtype=float).reshape(-1, 3),
            platform=np.array([m.platform_anchor for m in ms], dtype=float).reshape(-1, 3),
            stroke=np.array([m.stroke for m in ms], dtype=float).reshape(-1, 2),
            zero=np.array([m.encoder_zero for m in ms], dtype=float),
            scale=np.array([m.encoder_scale for m in ms], dtype=float),
            tilt_rotation=None if incl is None else rpy_matrix(incl.rpy),
            tilt_sigma=1.0 if incl is None else incl.sigma,
            encoder_sigma=geometry.encoder_sigma,
        )


def write_sensors(robot: ET.Element, geometry: HexapodGeometry, fmt: Callable[[float], str]) -> None:
    """Append the URDF elements of ``geometry``'s redundant sensors (module doc) to ``robot``.

    ``fmt`` formats one number (the URDF writer's fixed decimals). Nothing without sensors.
    """
    if not geometry.redundant:
        return

    def fixed(name: str, parent: str, xyz, rpy=(0.0, 0.0, 0.0)) -> None:
        link = ET.SubElement(robot, "link", name=name)
        inertial = ET.SubElement(link, "inertial")  # as the other links: MJCF bodies need a mass
        ET.SubElement(inertial, "mass", value="0.01")
        ET.SubElement(inertial, "inertia", ixx="1e-6", iyy="1e-6", izz="1e-6", ixy="0", ixz="0", iyz="0")
        j = ET.SubElement(robot, "joint", name=f"{name}_joint", type="fixed")
        ET.SubElement(j, "parent", link=parent)
        ET.SubElement(j, "child", link=name)
        ET.SubElement(j, "origin", xyz=" ".join(fmt(v) for v in xyz), rpy=" ".join(fmt(v) for v in rpy))

    for k, m in enumerate(geometry.measuring_legs):
        n = f"leg{k + 7}"
        fixed(f"{n}_base", "base_link", m.base_anchor)
        fixed(f"{n}_anchor", "platform", m.platform_anchor)
        ET.SubElement(
            robot,
            "loop_closure",
            name=n,
            type="distance",
            link1=f"{n}_base",
            link2=f"{n}_anchor",
            stroke=" ".join(fmt(v) for v in m.stroke),
            zero=fmt(m.encoder_zero),
            scale=fmt(m.encoder_scale),
        )
    if geometry.inclinometer is not None:
        fixed("inclinometer", "platform", (0.0, 0.0, 0.0), geometry.inclinometer.rpy)
        ET.SubElement(robot, "inclinometer", link="inclinometer", sigma=repr(geometry.inclinometer.sigma))
    ET.SubElement(robot, "redundant_sensing", encoder_sigma=repr(geometry.encoder_sigma))


def _floats(el: ET.Element, key: str, n: int, source: str, default: str | None = None) -> np.ndarray:
    text = el.get(key, default)
    try:
        vals = np.array([float(v) for v in (text or "").split()])
    except ValueError:
        vals = np.array([])
    if vals.shape != (n,) or not np.all(np.isfinite(vals)):
        raise UrdfError(source, text, f"<{el.tag} {el.get('name', el.get('link', ''))}> {key}: expected {n} numbers")
    return vals


def read_sensors(urdf_xml: str, source: str = "<string>") -> SensorLayout | None:
    """The redundant sensors a URDF declares (module doc), ``None`` without any.

    Raises:
        UrdfError: a sensor element with a missing or malformed attribute, or naming a link
            that is not fixed to ``base_link`` / ``platform`` as the contract says.
    """
    try:
        root = ET.fromstring(urdf_xml)
    except ET.ParseError as exc:
        raise UrdfError(source, str(exc), "not well-formed XML") from None
    closures = [el for el in root.findall("loop_closure") if el.get("type") == "distance"]
    incl = root.find("inclinometer")
    if not closures and incl is None:
        return None
    fixed = {}
    for j in root.findall("joint"):
        child, parent, origin = j.find("child"), j.find("parent"), j.find("origin")
        if j.get("type") == "fixed" and child is not None and parent is not None:
            o = origin if origin is not None else ET.Element("origin")
            fixed[child.get("link")] = (parent.get("link"), _floats(o, "xyz", 3, source, "0 0 0"), o)

    def frame(link: str | None, parent: str) -> tuple[np.ndarray, ET.Element]:
        if link not in fixed or fixed[link][0] != parent:
            raise UrdfError(source, link, f"a sensor link must be fixed to {parent!r}")
        return fixed[link][1], fixed[link][2]

    base, plat, stroke, zero, scale = [], [], [], [], []
    for el in closures:
        base.append(frame(el.get("link1"), "base_link")[0])
        plat.append(frame(el.get("link2"), "platform")[0])
        stroke.append(_floats(el, "stroke", 2, source))
        zero.append(_floats(el, "zero", 1, source, "0")[0])
        scale.append(_floats(el, "scale", 1, source, "0")[0])
    rot, tilt_sigma = None, 1.0
    if incl is not None:
        origin = frame(incl.get("link"), "platform")[1]
        rot = rpy_matrix(_floats(origin, "rpy", 3, source, "0 0 0"))
        tilt_sigma = float(_floats(incl, "sigma", 1, source)[0])
    noise = root.find("redundant_sensing")
    sigma = DEFAULT_ENCODER_SIGMA if noise is None else float(_floats(noise, "encoder_sigma", 1, source)[0])
    return SensorLayout(
        base=np.array(base, dtype=float).reshape(-1, 3),
        platform=np.array(plat, dtype=float).reshape(-1, 3),
        stroke=np.array(stroke, dtype=float).reshape(-1, 2),
        zero=np.array(zero, dtype=float),
        scale=np.array(scale, dtype=float),
        tilt_rotation=rot,
        tilt_sigma=tilt_sigma,
        encoder_sigma=sigma,
    )
