"""The body limits of a hexapod in its MJCF: joint cones and ``min_clearance`` as custom numerics.

A URDF has no place for the joint cones or the collision bound of a geometry
(:class:`~hexapod_model.description.geometry.HexapodGeometry`: ``base_cone``,
``platform_cone``, ``min_clearance``); MJCF has ``<custom><numeric>``, data that MuJoCo keeps
without giving it a meaning. :func:`~hexapod_model.description.mjcf.geometry_to_mjcf` writes

* ``hexapod_leg<i>_base_cone`` and ``hexapod_leg<i>_platform_cone`` (rad): the half-angle of
  the cone of leg ``i``'s joint (1..6) at that end, about its home axis, one number; a joint
  without a cone has no numeric;
* ``hexapod_min_clearance`` (m): the distance between two collision bodies below which a pose
  is in ``collision``, one number.

Each is written as Python's shortest round-trip form of the float, so the loaded limits are the
geometry's to the bit.

:func:`read_body_limits` reads them back for the body check of a hexapod loaded from the MJCF
(:mod:`~hexapod_model.kinematics.body_check`), so that it judges as the geometry's does. The
collision bodies themselves are geoms of the collision group
(:func:`~hexapod_model.description.mjcf_loader.mjcf_collision_bodies`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from ..exceptions import MjcfError
from .geometry import HexapodGeometry

ENDS = ("base", "platform")
MIN_CLEARANCE = "hexapod_min_clearance"


def cone_name(leg: int, end: str) -> str:
    """The numeric's name of the cone of leg ``leg`` (0..5) at ``end`` (``"base"`` or ``"platform"``)."""
    return f"hexapod_leg{leg + 1}_{end}_cone"


@dataclass(frozen=True)
class BodyLimits:
    """The body limits an MJCF carries.

    Attributes:
        cones: (6, 2) cone half-angles (rad) of each leg's base and platform joint; ``inf``: none.
        min_clearance: the collision bound (m).
    """

    cones: np.ndarray
    min_clearance: float


def body_limits_element(geom: HexapodGeometry) -> ET.Element:
    """The ``<custom>`` element holding ``geom``'s cones and ``min_clearance`` (see the module doc)."""
    custom = ET.Element("custom")
    custom.append(ET.Comment(" the geometry's joint cones (rad) and collision bound (m), for the body check "))
    for k in range(6):
        for end, limit in zip(ENDS, geom.cones_of(k), strict=True):
            if limit is not None:
                ET.SubElement(custom, "numeric", name=cone_name(k, end), data=repr(float(limit)))
    ET.SubElement(custom, "numeric", name=MIN_CLEARANCE, data=repr(float(geom.min_clearance)))
    return custom


def _value(el: ET.Element, source: str, positive: bool) -> float:
    name, data = el.get("name"), el.get("data", "")
    try:
        values = [float(v) for v in data.split()]
    except ValueError:
        values = []
    if len(values) != 1 or not math.isfinite(values[0]) or (values[0] <= 0 if positive else values[0] < 0):
        limit = "one finite number > 0 (rad)" if positive else "one finite number >= 0 (m)"
        raise MjcfError(source, f"{name} data={data!r}", f"expected {limit}")
    return values[0]


def read_body_limits(mjcf_xml: str, source: str = "<string>") -> BodyLimits:
    """The cones and ``min_clearance`` an MJCF carries (none: no cones, a bound of 0).

    Raises:
        MjcfError: a numeric of these names whose data is not one finite number (a cone: > 0 rad;
            the bound: >= 0 m).
    """
    cones = np.full((6, 2), np.inf)
    bound = 0.0
    names = {cone_name(k, end): (k, e) for k in range(6) for e, end in enumerate(ENDS)}
    for el in ET.fromstring(mjcf_xml).iter("numeric"):
        name = el.get("name")
        if name == MIN_CLEARANCE:
            bound = _value(el, source, positive=False)
        elif name in names:
            cones[names[name]] = _value(el, source, positive=True)
    return BodyLimits(cones, bound)
