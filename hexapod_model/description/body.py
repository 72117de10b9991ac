"""The machine's body in a geometry: collision radii, plates, joint cones, clearance and envelope.

The kinematics need only the joint centres and axes; a real hexapod also stops where two of
its parts touch or a joint runs out of its cone. These fields of
:class:`~hexapod_model.description.geometry.HexapodGeometry` (and the per-leg ``leg_radius``,
``base_cone``, ``platform_cone`` of :class:`~hexapod_model.description.geometry.LegGeometry`)
describe that body:

* ``leg_radius`` (m): each leg is a capsule of this radius around its axis, from the base joint
  to the platform joint (the cylinder and the rod, two capsules that overlap at every stroke);
* ``housing_radius`` (m): each joint housing is a sphere of this radius around the joint centre;
* ``plate_thickness`` (m), ``base_plate_radius`` / ``platform_plate_radius`` (m, ``None``: the
  largest anchor radius plus ``housing_radius``): the plates are discs whose faces lie
  ``housing_radius`` beyond the nearest joint centre (below the base joints, above the
  platform joints);
* ``base_cone`` / ``platform_cone`` (rad, ``None``: no cone): the half-angle of each joint's cone
  about its home axis (a Cardan joint: its combined deflection; a ball joint: the angle
  between the leg and its home direction);
* ``min_clearance`` (m): a pose whose smallest distance between two bodies is below it is in
  ``collision``;
* ``envelope``: an optional operating box about the home pose, half-widths
  ``(x, y, z [m], roll, pitch, yaw [rad])``.

Files may give the angles in degrees with a ``_deg`` suffix (``platform_cone_deg = 45``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..exceptions import GeometryError

#: geometry fields in radians that a file may give in degrees (``<name>_deg``)
ANGLE_FIELDS = ("cardan_limit", "roll_limit", "base_cone", "platform_cone")
#: hexapod-level body fields and their defaults (``to_dict`` leaves out the default values)
BODY_DEFAULTS: dict[str, Any] = {
    "leg_radius": 0.02,
    "housing_radius": 0.025,
    "plate_thickness": 0.02,
    "base_plate_radius": None,
    "platform_plate_radius": None,
    "base_cone": None,
    "platform_cone": None,
    "min_clearance": 0.0,
    "envelope": None,
}
MAX_LENGTH = 10.0  # m, bound on every body length
MAX_CONE = math.pi / 2  # rad: a cone half-angle lies in (0, pi/2]


def length(name: str, value: Any, *, zero: bool = False) -> float:
    """A length (m) in ``(0, MAX_LENGTH]`` (``[0, ...]`` with ``zero``), else one-line :class:`GeometryError`."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise GeometryError(name, value, "expected a number (m)")
    v = float(value)
    if not math.isfinite(v) or v < 0.0 or v > MAX_LENGTH or (v == 0.0 and not zero):
        raise GeometryError(name, value, f"must lie in {'[' if zero else '('}0, {MAX_LENGTH:g}] m")
    return v


def cone(name: str, value: Any) -> float | None:
    """A cone half-angle (rad) in ``(0, pi/2]``, or ``None`` (no cone)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise GeometryError(name, value, "expected a number (rad) or none")
    v = float(value)
    if not math.isfinite(v) or not 0.0 < v <= MAX_CONE:
        raise GeometryError(name, value, f"a cone half-angle must lie in (0, {MAX_CONE:.6g}] rad (90 deg)")
    return v


def envelope(value: Any) -> tuple[float, ...] | None:
    """Six positive half-widths ``(x, y, z [m], roll, pitch, yaw [rad])``, or ``None``."""
    if value is None:
        return None
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise GeometryError("envelope", value, "expected 6 numbers (x, y, z [m], roll, pitch, yaw [rad])") from None
    if arr.shape != (6,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise GeometryError(
            "envelope", value, "expected 6 finite half-widths > 0 (x, y, z [m], roll, pitch, yaw [rad])"
        )
    return tuple(float(v) for v in arr)


def check_body(geom: Any) -> dict[str, Any]:
    """Validated hexapod-level body fields of ``geom`` (a geometry under construction), by name.

    Raises:
        GeometryError: a field outside its range, or a housing that does not hold its leg
            (``housing_radius`` must exceed every leg radius).
    """
    out: dict[str, Any] = {
        "leg_radius": length("leg_radius", geom.leg_radius),
        "housing_radius": length("housing_radius", geom.housing_radius),
        "plate_thickness": length("plate_thickness", geom.plate_thickness),
        "min_clearance": length("min_clearance", geom.min_clearance, zero=True),
        "base_cone": cone("base_cone", geom.base_cone),
        "platform_cone": cone("platform_cone", geom.platform_cone),
        "envelope": envelope(geom.envelope),
    }
    for name in ("base_plate_radius", "platform_plate_radius"):
        value = getattr(geom, name)
        out[name] = None if value is None else length(name, value)
    for i, leg in enumerate(geom.legs):
        r = out["leg_radius"] if leg.leg_radius is None else leg.leg_radius
        if r >= out["housing_radius"]:
            raise GeometryError(f"legs[{i}].leg_radius", r, f"must be below housing_radius {out['housing_radius']:g} m")
    return out


def check_leg_body(leg: Any) -> dict[str, Any]:
    """Validated per-leg body fields of ``leg`` (``None`` keeps the hexapod's value)."""
    return {
        "leg_radius": None if leg.leg_radius is None else length("leg_radius", leg.leg_radius),
        "base_cone": cone("base_cone", leg.base_cone),
        "platform_cone": cone("platform_cone", leg.platform_cone),
    }


def degrees_to_radians(data: dict, source: str) -> dict:
    """``data`` with every ``<angle>_deg`` key of :data:`ANGLE_FIELDS` turned into ``<angle>`` (rad)."""
    out = dict(data)
    for key in ANGLE_FIELDS:
        deg = f"{key}_deg"
        if deg in out:
            if key in out:
                raise GeometryError(deg, out[deg], f"give {key} or {deg}, not both ({source})")
            value = out.pop(deg)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise GeometryError(deg, value, "expected a number (deg)")
            out[key] = math.radians(value)
    return out
