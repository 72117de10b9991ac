"""Geometry description of a hexapod: frozen, validated values, loadable from TOML, YAML or JSON.

Frames and units (SI throughout):

* **base frame B**: fixed to the base plate, z up.
* **platform frame P**: fixed to the top plate. At the *home pose* P is B translated by
  ``(0, 0, home_height)``.
* A leg's **base anchor** ``b_i`` (in B) and **platform anchor** ``p_i`` (in P) are the
  joint centres: for a Cardan joint with offset axes, the midpoint of the common normal of
  its two axes; for a ball joint, its centre; for a guideway leg, the slider's Cardan centre
  at home.
* The **leg reading** (the measured prismatic joint, metres) is zero at home and grows as
  the leg extends; ``stroke`` bounds it. A leg may carry an encoder model (``encoder_zero``,
  ``encoder_scale``, both 0 by default): its reading is then
  ``encoder_zero + (1 + encoder_scale) * d`` with ``d`` the leg's extension from home, which
  ``stroke`` bounds.
* Beside the six legs a geometry may declare redundant sensors: passive measuring legs and a
  platform inclinometer (:mod:`hexapod_model.description.sensors`), whose readings follow the
  six legs' (:attr:`HexapodGeometry.reading_names`).
* Joint axes need not be exactly perpendicular to the leg at home (a calibrated fixture's are
  not): the common normal of each Cardan joint is then the projection of the leg direction on
  the plane perpendicular to its fixed axis (see :mod:`hexapod_model.description.legs`).

Joint types (``joint_type``):

* ``"cardan"``: base Cardan (2 revolutes, axes offset by ``base_offset``) -> roll about the
  leg axis -> prismatic (the encoder) -> platform Cardan (2 revolutes, offset
  ``platform_offset``); closed by a 6-D frame constraint (Bem et al. (2026)).
* ``"spherical"``: base Cardan -> prismatic -> ball joint at the platform (3-D point closure).
* ``"guideway"``: prismatic slider on a fixed guideway (the measured joint) -> Cardan ->
  fixed-length strut -> ball joint at the platform (Jakobović and Jelenković (2002), model 2).
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import GeometryError
from . import body
from .plausibility import implausible
from .sensors import DEFAULT_ENCODER_SIGMA, TILT_NAMES, Inclinometer, MeasuringLeg, sensors_from_dict, sensors_to_dict
from .values import Vec3
from .values import number as _number
from .values import stroke as _stroke
from .values import vec3 as _vec3

JOINT_TYPES = ("cardan", "spherical", "guideway")
MAX_AXIS_TILT_DEG = 10.0  # largest angle between a fixed Cardan axis and the plane perpendicular to the leg
ENCODER_SCALE_LIMIT = 0.5  # |encoder_scale| bound (a relative scale error of the reading)
ENCODER_RESOLUTION_LIMIT = 1e-3  # m, the coarsest encoder count accepted


@dataclass(frozen=True)
class LegGeometry:
    """One leg. Vectors are tuples of 3 floats, in metres (points) or unit vectors (axes).

    Attributes:
        base_anchor: base joint centre ``b_i`` in the base frame (m).
        platform_anchor: platform joint centre ``p_i`` in the platform frame (m).
        stroke: ``(min, max)`` of the leg reading (m); 0 (home) must lie strictly inside.
        base_axis: base-fixed Cardan axis in the base frame; ``None`` picks the horizontal
            direction perpendicular to the home leg axis. Must be perpendicular to it.
        platform_axis: platform-fixed Cardan axis in the platform frame (cardan legs only);
            ``None`` picks the same direction as ``base_axis``.
        guideway: unit direction of the slider's guideway in the base frame (guideway legs).
        base_offset: this leg's distance between its two base Cardan axes (m); ``None`` uses
            the hexapod's ``base_offset``.
        platform_offset: same at the platform Cardan joint (m, cardan legs only).
        encoder_zero: the reading at home (m), 0 by default.
        encoder_scale: relative scale error of the reading (dimensionless, 0 by default):
            reading = ``encoder_zero + (1 + encoder_scale) * extension``.
        leg_radius: this leg's collision radius (m); ``None`` uses the hexapod's
            (:mod:`~hexapod_model.description.body`).
        base_cone: half-angle of this leg's base joint cone (rad); ``None`` uses the hexapod's.
        platform_cone: same at the platform joint (rad).
    """

    base_anchor: Vec3
    platform_anchor: Vec3
    stroke: tuple[float, float]
    base_axis: Vec3 | None = None
    platform_axis: Vec3 | None = None
    guideway: Vec3 | None = None
    base_offset: float | None = None
    platform_offset: float | None = None
    encoder_zero: float = 0.0
    encoder_scale: float = 0.0
    leg_radius: float | None = None
    base_cone: float | None = None
    platform_cone: float | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "base_anchor", _vec3("base_anchor", self.base_anchor))
        set_(self, "platform_anchor", _vec3("platform_anchor", self.platform_anchor))
        for name in ("base_axis", "platform_axis", "guideway"):
            if getattr(self, name) is not None:
                set_(self, name, _vec3(name, getattr(self, name), unit=True))
        set_(self, "stroke", _stroke("stroke", self.stroke))
        for name in ("base_offset", "platform_offset"):
            if getattr(self, name) is not None:
                set_(self, name, _number(name, getattr(self, name), 0.0, 10.0))
        set_(self, "encoder_zero", _number("encoder_zero", self.encoder_zero, -10.0, 10.0))
        lim = ENCODER_SCALE_LIMIT
        set_(self, "encoder_scale", _number("encoder_scale", self.encoder_scale, -lim, lim))
        for name, value in body.check_leg_body(self).items():
            set_(self, name, value)


@dataclass(frozen=True)
class HexapodGeometry:
    """A whole hexapod. Lengths in metres, angles in radians.

    Attributes:
        name: identifier used for URDF robot and file names.
        joint_type: ``"cardan"``, ``"spherical"`` or ``"guideway"`` (see module doc).
        legs: exactly six :class:`LegGeometry`, in leg order 1..6.
        home_height: z of the platform frame origin at home, in the base frame (m).
        base_offset: distance between the two non-intersecting base Cardan axes (m).
        platform_offset: same at the platform Cardan joint (m, cardan legs only).
        cardan_limit: bound on ``|angle|`` of every Cardan revolute (rad), < pi/2.
        roll_limit: bound on ``|angle|`` of the roll joint about the leg axis (rad).
        brake_capacity: axial force each leg's brake holds (N, tension or compression); ``None``: not given.
            ``hexapod statics`` states the load margin against it (docs/statics.md).
        description: one line for ``hexapod urdf --list-presets``.
        leg_radius: collision radius of every leg (m); the body fields below are described in
            :mod:`~hexapod_model.description.body`.
        housing_radius: radius of the sphere around each joint centre (m).
        plate_thickness: thickness of the base and platform discs (m).
        base_plate_radius: radius of the base disc (m); ``None``: largest anchor radius + housing.
        platform_plate_radius: same for the platform disc (m).
        base_cone: half-angle of every base joint's cone about its home axis (rad); ``None``: no cone.
        platform_cone: same at the platform joints (rad).
        min_clearance: smallest allowed distance between two bodies (m); below it a pose is in collision.
        envelope: operating box about home, half-widths ``(x, y, z [m], roll, pitch, yaw [rad])``, or ``None``.
        measuring_legs: passive measuring legs beside the six (readings ``leg7``, ...; see
            :mod:`~hexapod_model.description.sensors`).
        inclinometer: a two-axis platform inclinometer (readings ``tilt_x``, ``tilt_y``), or ``None``.
        encoder_sigma: standard deviation of every leg encoder's reading (m); weighs the
            readings of a hexapod with redundant sensors.
        encoder_resolution: the leg encoders' count (m of reading; 0, the default: continuous
            readings). The stream tracker takes it as its ``resolution`` unless told otherwise
            (:class:`~hexapod_model.tracking.reading_tests.TrackerSettings`).
    """

    name: str
    joint_type: str
    legs: tuple[LegGeometry, ...]
    home_height: float
    base_offset: float = 0.0
    platform_offset: float = 0.0
    cardan_limit: float = math.radians(45.0)
    roll_limit: float = math.pi
    description: str = ""
    brake_capacity: float | None = None
    leg_radius: float = body.BODY_DEFAULTS["leg_radius"]
    housing_radius: float = body.BODY_DEFAULTS["housing_radius"]
    plate_thickness: float = body.BODY_DEFAULTS["plate_thickness"]
    base_plate_radius: float | None = None
    platform_plate_radius: float | None = None
    base_cone: float | None = None
    platform_cone: float | None = None
    min_clearance: float = body.BODY_DEFAULTS["min_clearance"]
    envelope: tuple[float, ...] | None = None
    measuring_legs: tuple[MeasuringLeg, ...] = ()
    inclinometer: Inclinometer | None = None
    encoder_sigma: float = DEFAULT_ENCODER_SIGMA
    encoder_resolution: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.replace("-", "_").replace("_", "a").isalnum():
            raise GeometryError("name", self.name, "use letters, digits, '-' and '_'")
        if self.joint_type not in JOINT_TYPES:
            raise GeometryError("joint_type", self.joint_type, f"must be one of {JOINT_TYPES}")
        legs = tuple(self.legs)
        if len(legs) != 6:
            raise GeometryError("legs", len(legs), "a hexapod has exactly 6 legs")
        object.__setattr__(self, "legs", legs)
        _number("home_height", self.home_height, 0.0, 100.0, open_lo=True)
        _number("base_offset", self.base_offset, 0.0, 10.0)
        _number("platform_offset", self.platform_offset, 0.0, 10.0)
        _number("cardan_limit", self.cardan_limit, 0.0, math.pi / 2 - 1e-3, open_lo=True)
        _number("roll_limit", self.roll_limit, 0.0, math.pi, open_lo=True)
        if self.brake_capacity is not None:
            object.__setattr__(
                self, "brake_capacity", _number("brake_capacity", self.brake_capacity, 0.0, 1e9, open_lo=True)
            )
        if self.joint_type != "cardan" and self.platform_offset != 0.0:
            raise GeometryError(
                "platform_offset", self.platform_offset, "only cardan legs have a platform Cardan joint"
            )
        for i, leg in enumerate(legs):
            self._check_leg(i, leg)
        for name, value in body.check_body(self).items():
            object.__setattr__(self, name, value)
        extra = sensors_from_dict({"measuring_legs": self.measuring_legs, "inclinometer": self.inclinometer})
        object.__setattr__(self, "measuring_legs", extra["measuring_legs"])
        object.__setattr__(self, "inclinometer", extra["inclinometer"])
        for k, m in enumerate(self.measuring_legs):
            d = self.home_translation + np.asarray(m.platform_anchor) - np.asarray(m.base_anchor)
            if float(np.linalg.norm(d)) < 1e-6:
                raise GeometryError(
                    f"measuring_legs[{k}].platform_anchor", m.platform_anchor, "coincides with its base anchor at home"
                )
        object.__setattr__(self, "encoder_sigma", _number("encoder_sigma", self.encoder_sigma, 0.0, 1.0, open_lo=True))
        resolution = _number("encoder_resolution", self.encoder_resolution, 0.0, ENCODER_RESOLUTION_LIMIT)
        object.__setattr__(self, "encoder_resolution", resolution)

        self._check_scale()

    def leg_radius_of(self, i: int) -> float:
        """Collision radius (m) of leg ``i``: its own or the hexapod's."""
        r = self.legs[i].leg_radius
        return self.leg_radius if r is None else r

    def cones_of(self, i: int) -> tuple[float | None, float | None]:
        """Base and platform cone half-angles (rad, ``None``: no cone) of leg ``i``: its own or the hexapod's."""
        leg = self.legs[i]
        return (
            self.base_cone if leg.base_cone is None else leg.base_cone,
            self.platform_cone if leg.platform_cone is None else leg.platform_cone,
        )

    def _check_scale(self) -> None:
        """Every length within a plausible multiple of the base radius (a value in mm is refused here)."""
        r = self.base_radius
        lengths = [("home_height", self.home_height)]
        for i, leg in enumerate(self.legs):
            lengths.append((f"legs[{i}].platform_anchor", float(np.max(np.abs(leg.platform_anchor)))))
            lengths.append((f"legs[{i}].stroke", float(np.max(np.abs(leg.stroke)))))
        for name, value in lengths:
            why = implausible(name, value, r)
            if why:
                raise GeometryError(name, value, why)

    @property
    def redundant(self) -> bool:
        """Whether the geometry declares sensors beside the six legs (measuring legs, an inclinometer)."""
        return bool(self.measuring_legs) or self.inclinometer is not None

    @property
    def reading_names(self) -> tuple[str, ...]:
        """The names of the readings :meth:`hexapod_model.Hexapod.forward` takes, in their order.

        ``leg1`` .. ``leg6``, then ``leg7``, ... for the measuring legs, then ``tilt_x``, ``tilt_y``.
        """
        legs = tuple(f"leg{i + 1}" for i in range(6 + len(self.measuring_legs)))
        return legs + (TILT_NAMES if self.inclinometer is not None else ())

    def offsets(self, i: int) -> tuple[float, float]:
        """Base and platform Cardan axis offsets (m) of leg ``i``: its own or the hexapod's."""
        leg = self.legs[i]
        eb = self.base_offset if leg.base_offset is None else leg.base_offset
        return eb, self.platform_offset if leg.platform_offset is None else leg.platform_offset

    def _check_leg(self, i: int, leg: LegGeometry) -> None:
        where = f"legs[{i}]"
        if not isinstance(leg, LegGeometry):
            raise GeometryError(where, leg, "expected a LegGeometry")
        if self.joint_type != "cardan" and leg.platform_offset not in (None, 0.0):
            raise GeometryError(
                f"{where}.platform_offset", leg.platform_offset, "only cardan legs have a platform Cardan joint"
            )
        w, length = self.home_leg_axis(i)
        need = sum(self.offsets(i)) / 2
        if length <= need + 1e-6:
            raise GeometryError(
                f"{where}.platform_anchor",
                leg.platform_anchor,
                f"home leg length {length:.6g} m must exceed the joint offsets {need:.6g} m",
            )
        max_cos = math.sin(math.radians(MAX_AXIS_TILT_DEG))
        for name, axis in (("base_axis", leg.base_axis), ("platform_axis", leg.platform_axis)):
            if axis is not None and abs(float(np.dot(axis, w))) > max_cos:
                raise GeometryError(
                    f"{where}.{name}",
                    axis,
                    f"must be perpendicular to the home leg axis {tuple(np.round(w, 6))} "
                    f"within {MAX_AXIS_TILT_DEG:g} deg",
                )
        if self.joint_type == "guideway":
            if leg.guideway is None:
                raise GeometryError(f"{where}.guideway", None, "guideway legs need a guideway direction")
            if abs(float(np.dot(leg.guideway, w))) > 1 - 1e-3:
                raise GeometryError(f"{where}.guideway", leg.guideway, "must not be parallel to the strut")
        elif leg.guideway is not None:
            raise GeometryError(
                f"{where}.guideway", leg.guideway, f"only guideway legs have one, not {self.joint_type}"
            )

    # ----- derived quantities (base frame, home pose) -----
    @property
    def base_radius(self) -> float:
        """Largest horizontal distance (m) of a base anchor from the base origin: the hexapod's size."""
        return float(max(math.hypot(leg.base_anchor[0], leg.base_anchor[1]) for leg in self.legs))

    @property
    def home_translation(self) -> np.ndarray:
        """Platform origin at home in the base frame (m)."""
        return np.array([0.0, 0.0, self.home_height])

    def home_leg_axis(self, i: int) -> tuple[np.ndarray, float]:
        """Unit leg direction ``w_i`` (base frame) and anchor distance (m) at home."""
        d = self.home_translation + np.asarray(self.legs[i].platform_anchor) - np.asarray(self.legs[i].base_anchor)
        n = float(np.linalg.norm(d))
        if n < 1e-9:
            raise GeometryError(
                f"legs[{i}].platform_anchor", self.legs[i].platform_anchor, "coincides with the base anchor at home"
            )
        return d / n, n

    def base_points(self) -> np.ndarray:
        """(6, 3) base anchors in the base frame (m)."""
        return np.array([leg.base_anchor for leg in self.legs])

    def platform_points(self) -> np.ndarray:
        """(6, 3) platform anchors in the platform frame (m)."""
        return np.array([leg.platform_anchor for leg in self.legs])

    def to_dict(self) -> dict:
        """Plain dict (the file format of :func:`geometry_from_dict`).

        Leg fields left at their default (``None``, a zero encoder model) are omitted, and so
        are the body fields at their defaults, a zero ``encoder_resolution`` and, without
        redundant sensors, the default ``encoder_sigma``.
        """
        out: dict[str, Any] = {}
        defaults = {f.name: f.default for f in fields(LegGeometry)}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name in ("measuring_legs", "inclinometer"):
                continue
            if f.name == "encoder_sigma" and not self.redundant and v == DEFAULT_ENCODER_SIGMA:
                continue
            if f.name == "encoder_resolution" and v == 0.0:
                continue
            if f.name == "legs":
                v = [
                    {
                        k: (list(x) if isinstance(x, tuple) else x)
                        for k, x in vars(leg).items()
                        if x is not None and not (k.startswith("encoder_") and x == defaults[k])
                    }
                    for leg in v
                ]
            if f.name in body.BODY_DEFAULTS and v == body.BODY_DEFAULTS[f.name]:
                continue
            if v is not None:
                out[f.name] = list(v) if isinstance(v, tuple) and f.name != "legs" else v
        out.update(sensors_to_dict(self.measuring_legs, self.inclinometer))
        return out


def geometry_from_dict(data: dict, source: str = "<dict>") -> HexapodGeometry:
    """Build a geometry from a plain dict, naming the bad field on error.

    Keys are the fields of :class:`HexapodGeometry`; ``legs`` is a list of six tables with
    the fields of :class:`LegGeometry`. Angles may be given in degrees with a ``_deg``
    suffix (``cardan_limit_deg = 40``, ``platform_cone_deg = 45``), in the legs too.
    """
    if not isinstance(data, dict):
        raise GeometryError(source, type(data).__name__, "top level must be a table")
    data = body.degrees_to_radians(data, source)
    known = {f.name for f in fields(HexapodGeometry)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise GeometryError(unknown[0], data[unknown[0]], f"unknown field (known: {sorted(known)})")
    for req in ("name", "joint_type", "legs", "home_height"):
        if req not in data:
            raise GeometryError(req, None, "required field is missing")
    legs_raw = data["legs"]
    if not isinstance(legs_raw, list):
        raise GeometryError("legs", legs_raw, "expected a list of 6 leg tables")
    leg_fields = {f.name for f in fields(LegGeometry)}
    legs = []
    for i, raw in enumerate(legs_raw):
        if not isinstance(raw, dict):
            raise GeometryError(f"legs[{i}]", raw, "expected a table")
        try:
            raw = body.degrees_to_radians(raw, source)
        except GeometryError as exc:
            raise GeometryError(f"legs[{i}].{exc.field}", exc.value, exc.reason) from None
        bad = sorted(set(raw) - leg_fields)
        if bad:
            raise GeometryError(f"legs[{i}].{bad[0]}", raw[bad[0]], f"unknown leg field (known: {sorted(leg_fields)})")
        for req in ("base_anchor", "platform_anchor", "stroke"):
            if req not in raw:
                raise GeometryError(f"legs[{i}].{req}", None, "required field is missing")
        try:
            legs.append(LegGeometry(**raw))
        except GeometryError as exc:
            raise GeometryError(f"legs[{i}].{exc.field}", exc.value, exc.reason) from None
    data["legs"] = tuple(legs)
    return HexapodGeometry(**sensors_from_dict(data))


GEOMETRY_SUFFIXES = (".toml", ".yaml", ".yml", ".json")


def load_geometry(path: str | Path) -> HexapodGeometry:
    """Load a geometry file (``.toml``, ``.yaml`` or ``.json``); see ``docs/geometry.md`` for the format."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise GeometryError(str(path), None, f"cannot read file: {exc.strerror}") from None
    suffix = path.suffix.lower()
    try:
        if suffix == ".json":
            data = json.loads(text)
        elif suffix == ".toml":
            data = tomllib.loads(text)
        elif suffix in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
        else:
            raise GeometryError(str(path), path.suffix, "geometry files are .toml, .yaml or .json")
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise GeometryError(str(path), None, f"not valid {suffix[1:].upper()}: {exc}") from None
    except Exception as exc:  # yaml.YAMLError without importing yaml up front
        if type(exc).__module__.startswith("yaml"):
            raise GeometryError(str(path), None, f"not valid YAML: {exc}") from None
        raise
    return geometry_from_dict(data, source=str(path))
