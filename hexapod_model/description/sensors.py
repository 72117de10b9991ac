"""Redundant sensors a geometry may declare beside its six legs: measuring legs and an inclinometer.

Six leg readings determine the platform pose and nothing more; a seventh measurement makes
the readings over-determined, so that a faulty one shows as an inconsistency
(:mod:`hexapod_model.kinematics.redundant`, ``docs/redundancy.md``).

* A **measuring leg** is a passive strut with a ball joint (or intersecting-axis universal
  joint) at each end, an encoder on its stroke and no brake: its reading (m) is
  ``encoder_zero + (1 + encoder_scale) * (|t + R p - b| - |t_home + p - b|)``, the change of
  the distance between its base anchor ``b`` (base frame B) and its platform anchor ``p``
  (platform frame P) from home, ``(R, t)`` the platform pose. Readings follow the six legs
  as ``leg7``, ``leg8``, ...
* An **inclinometer** on the platform measures two tilt angles (rad) of its mounting frame S
  (orientation ``rpy`` in P, URDF convention ``Rz(yaw) Ry(pitch) Rx(roll)``):
  ``tilt_x = asin(x_S . z_B)`` and ``tilt_y = asin(y_S . z_B)``, the elevation of the
  sensor's x and y axes above the horizontal; the base frame's z axis is taken as vertical
  (a levelled base). Both are zero at home when ``rpy`` is zero. Its readings come last.

Noise: every leg encoder (the six legs' and the measuring legs') has standard deviation
``HexapodGeometry.encoder_sigma`` (m), the inclinometer ``Inclinometer.sigma`` (rad); the
least-squares solve weights each reading by the inverse of its variance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ..exceptions import GeometryError
from .values import Vec3, number, stroke, vec3

DEFAULT_ENCODER_SIGMA = 1e-6  # m: standard deviation of a leg encoder's reading
DEFAULT_TILT_SIGMA = 2e-5  # rad (about 0.001 deg): standard deviation of an inclinometer angle
TILT_NAMES = ("tilt_x", "tilt_y")


@dataclass(frozen=True)
class MeasuringLeg:
    """A passive measuring leg: ball joints at both ends, an encoder, no brake (see the module doc).

    Attributes:
        base_anchor: base joint centre ``b`` in the base frame (m).
        platform_anchor: platform joint centre ``p`` in the platform frame (m).
        stroke: ``(min, max)`` of the reading (m); 0 (home) strictly inside.
        encoder_zero: the reading at home (m).
        encoder_scale: relative scale error of the reading (dimensionless).
    """

    base_anchor: Vec3
    platform_anchor: Vec3
    stroke: tuple[float, float]
    encoder_zero: float = 0.0
    encoder_scale: float = 0.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "base_anchor", vec3("base_anchor", self.base_anchor))
        set_(self, "platform_anchor", vec3("platform_anchor", self.platform_anchor))
        set_(self, "stroke", stroke("stroke", self.stroke))
        set_(self, "encoder_zero", number("encoder_zero", self.encoder_zero, -10.0, 10.0))
        set_(self, "encoder_scale", number("encoder_scale", self.encoder_scale, -0.5, 0.5))


@dataclass(frozen=True)
class Inclinometer:
    """A two-axis inclinometer fixed to the platform (see the module doc).

    Attributes:
        rpy: orientation of its mounting frame S in the platform frame (rad, URDF roll, pitch, yaw).
        sigma: standard deviation of each of its two angles (rad).
    """

    rpy: Vec3 = (0.0, 0.0, 0.0)
    sigma: float = DEFAULT_TILT_SIGMA

    def __post_init__(self) -> None:
        object.__setattr__(self, "rpy", vec3("inclinometer.rpy", self.rpy))
        object.__setattr__(self, "sigma", number("inclinometer.sigma", self.sigma, 0.0, 1.0, open_lo=True))


def sensors_from_dict(data: dict[str, Any]) -> dict[str, Any]:
    """Replace the file form of ``measuring_legs`` (list of tables) and ``inclinometer`` (a table) by dataclasses.

    The inclinometer may give its orientation in degrees (``rpy_deg``). Returns a new dict.

    Raises:
        GeometryError: a table that is not one, an unknown or missing field, a bad value.
    """
    data = dict(data)
    raw_legs = data.get("measuring_legs", [])
    if not isinstance(raw_legs, (list, tuple)):
        raise GeometryError("measuring_legs", raw_legs, "expected a list of leg tables")
    legs = []
    for i, raw in enumerate(raw_legs):
        where = f"measuring_legs[{i}]"
        if isinstance(raw, MeasuringLeg):
            legs.append(raw)
            continue
        if not isinstance(raw, dict):
            raise GeometryError(where, raw, "expected a table")
        known = set(MeasuringLeg.__dataclass_fields__)
        bad = sorted(set(raw) - known)
        if bad:
            raise GeometryError(f"{where}.{bad[0]}", raw[bad[0]], f"unknown field (known: {sorted(known)})")
        for req in ("base_anchor", "platform_anchor", "stroke"):
            if req not in raw:
                raise GeometryError(f"{where}.{req}", None, "required field is missing")
        try:
            legs.append(MeasuringLeg(**raw))
        except GeometryError as exc:
            raise GeometryError(f"{where}.{exc.field}", exc.value, exc.reason) from None
    if "measuring_legs" in data:
        data["measuring_legs"] = tuple(legs)
    raw = data.get("inclinometer")
    if isinstance(raw, dict):
        raw = dict(raw)
        if "rpy_deg" in raw:
            deg = vec3("inclinometer.rpy_deg", raw.pop("rpy_deg"))
            raw["rpy"] = tuple(math.radians(v) for v in deg)
        bad = sorted(set(raw) - {"rpy", "sigma"})
        if bad:
            raise GeometryError(f"inclinometer.{bad[0]}", raw[bad[0]], "unknown field (known: ['rpy', 'sigma'])")
        data["inclinometer"] = Inclinometer(**raw)
    elif raw is not None and not isinstance(raw, Inclinometer):
        raise GeometryError("inclinometer", raw, "expected a table (rpy, sigma)")
    return data


def sensors_to_dict(measuring_legs: tuple[MeasuringLeg, ...], inclinometer: Inclinometer | None) -> dict[str, Any]:
    """The file form of the sensors (the inverse of :func:`sensors_from_dict`); empty without any."""
    out: dict[str, Any] = {}
    if measuring_legs:
        out["measuring_legs"] = [
            {
                k: (list(v) if isinstance(v, tuple) else v)
                for k, v in vars(leg).items()
                if not (k.startswith("encoder_") and v == 0.0)
            }
            for leg in measuring_legs
        ]
    if inclinometer is not None:
        out["inclinometer"] = {"rpy": list(inclinometer.rpy), "sigma": inclinometer.sigma}
    return out
