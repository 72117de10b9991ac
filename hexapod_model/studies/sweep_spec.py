"""A design sweep's specification (docs/sweep.md): a base geometry, the parameters to vary, the evaluation.

A spec is a TOML file::

    base = "reference"                 # preset name or geometry file (relative to the spec)
    [evaluate]                         # as hexapod evaluate's options
    grid = 7
    cone_deg = 15.0
    cone_samples = 4
    [statics]
    leg_stiffness = 2.0e7              # N/m, each locked leg (optional)
    [sample]
    mode = "grid"                      # every combination, or "random": `count` candidates, `seed`
    [parameters]
    base_radius = [0.22, 0.25, 0.28]                 # these values
    home_height = { min = 0.35, max = 0.45, steps = 3 }   # a range (grid: steps values; random: uniform)

:data:`PARAMETERS` lists what may vary and how a value changes the base geometry.
"""

from __future__ import annotations

import itertools
import math
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..description.geometry import HexapodGeometry, load_geometry
from ..description.plausibility import check_length
from ..description.presets import PRESETS, get_preset, symmetric_legs
from ..exceptions import InputError
from .evaluate import Settings
from .sweep_placement import (
    SENSOR_LENGTHS,
    SENSOR_PARAMETERS,
    PlacementSettings,
    apply_sensors,
    check_sensor_parameter,
    placement_settings,
)

#: what a sweep may vary: name -> meaning (SI; angles in degrees where the name says so)
PARAMETERS = {
    "home_height": "platform origin above the base origin at home (m)",
    "base_offset": "distance between the two base Cardan axes (m)",
    "platform_offset": "distance between the two platform Cardan axes (m)",
    "cardan_limit_deg": "bound on every Cardan angle (deg)",
    "roll_limit_deg": "bound on the roll joint (deg)",
    "brake_capacity": "axial force a brake holds (N)",
    "stroke_min": "lower leg reading limit of every leg (m, < 0)",
    "stroke_max": "upper leg reading limit of every leg (m, > 0)",
    "base_radius": "radius of the base anchors (m): the legs become the three-fold symmetric layout",
    "platform_radius": "radius of the platform anchors (m), same layout",
    "base_spread_deg": "angle between the two base anchors of a pair (deg), same layout",
    "platform_spread_deg": "angle between the two platform anchors of a pair (deg), same layout",
    **SENSOR_PARAMETERS,
}
#: the parameters in metres, checked against the base geometry's base radius (a value in mm is refused)
LENGTHS = (
    "home_height",
    "base_offset",
    "platform_offset",
    "stroke_min",
    "stroke_max",
    "base_radius",
    "platform_radius",
    *SENSOR_LENGTHS,
)
LAYOUT = ("base_radius", "platform_radius", "base_spread_deg", "platform_spread_deg")
MODES = ("grid", "random")
MAX_CANDIDATES = 100_000


@dataclass(frozen=True)
class SweepSpec:
    """A parsed spec.

    Attributes:
        base: the base geometry.
        base_source: what ``base`` named (preset or resolved path).
        parameters: name -> candidate values (grid) or ``(min, max)`` (random ranges as 2 values).
        ranges: names given as a ``{min, max}`` range (sampled uniformly in random mode).
        mode: ``"grid"`` or ``"random"``.
        count: candidates of a random sample.
        seed: the random sample's seed.
        settings: the evaluation's settings (as ``hexapod evaluate``).
        leg_stiffness: N/m of each locked leg, or ``None``.
        leg_clearance: smallest distance between two legs at home (m) below which they cross.
        placement: the ``[placement]`` table (score and rank each candidate's sensors), or ``None``.
    """

    base: HexapodGeometry
    base_source: str
    parameters: dict[str, tuple[float, ...]]
    ranges: frozenset[str]
    mode: str = "grid"
    count: int = 0
    seed: int = 0
    settings: Settings = Settings()
    leg_stiffness: float | None = None
    leg_clearance: float = 0.0
    placement: PlacementSettings | None = None

    def candidates(self) -> list[dict[str, float]]:
        """The parameter sets, in a fixed order (grid: row-major over the parameters as written)."""
        names = list(self.parameters)
        if self.mode == "grid":
            return [dict(zip(names, combo)) for combo in itertools.product(*(self.parameters[n] for n in names))]
        rng = np.random.default_rng(self.seed)
        out = []
        for _ in range(self.count):
            row = {}
            for n in names:
                values = self.parameters[n]
                if n in self.ranges:
                    row[n] = float(rng.uniform(values[0], values[1]))
                else:
                    row[n] = float(values[int(rng.integers(len(values)))])
            out.append(row)
        return out


def _measured_layout(g: HexapodGeometry) -> dict[str, float]:
    """The symmetric layout's parameters read off ``g`` (legs 1 and 2 as :func:`symmetric_legs` places them)."""
    b, p = g.base_points(), g.platform_points()
    ang = [math.degrees(math.atan2(v[1], v[0])) for v in (b[0], b[1], p[0], p[1])]
    return {
        "base_radius": float(np.linalg.norm(b[0, :2])),
        "platform_radius": float(np.linalg.norm(p[0, :2])),
        "base_spread_deg": (ang[1] - ang[0]) % 360.0,
        "platform_spread_deg": 120.0 - (ang[3] - ang[2]) % 360.0,
    }


def apply_parameters(base: HexapodGeometry, values: dict[str, float], name: str) -> HexapodGeometry:
    """``base`` with ``values`` (names of :data:`PARAMETERS`) applied, named ``name``.

    Raises:
        GeometryError: the result is not a valid geometry (its message names the field).
    """
    g = base
    fields: dict[str, Any] = {"name": name}
    for key in ("home_height", "base_offset", "platform_offset", "brake_capacity"):
        if key in values:
            fields[key] = values[key]
    for key in ("cardan_limit", "roll_limit"):
        if f"{key}_deg" in values:
            fields[key] = math.radians(values[f"{key}_deg"])
    legs = g.legs
    if any(k in values for k in LAYOUT):
        layout = _measured_layout(g) | {k: values[k] for k in LAYOUT if k in values}
        legs = symmetric_legs(
            layout["base_radius"],
            layout["platform_radius"],
            layout["base_spread_deg"],
            layout["platform_spread_deg"],
            legs[0].stroke,
        )
    if "stroke_min" in values or "stroke_max" in values:
        legs = tuple(
            replace(leg, stroke=(values.get("stroke_min", leg.stroke[0]), values.get("stroke_max", leg.stroke[1])))
            for leg in legs
        )
    return apply_sensors(replace(g, legs=tuple(legs), **fields), values)


def _values(name: str, raw: Any, mode: str) -> tuple[tuple[float, ...], bool]:
    where = f"parameters.{name}"
    if isinstance(raw, list):
        if not raw or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in raw):
            raise InputError(where, raw, "expected a non-empty list of numbers")
        return tuple(float(v) for v in raw), False
    if isinstance(raw, dict) and {"min", "max"} <= set(raw) and set(raw) <= {"min", "max", "steps"}:
        lo, hi = raw["min"], raw["max"]
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in (lo, hi)) or lo > hi:
            raise InputError(where, raw, "need finite min <= max")
        if mode == "random":
            return (float(lo), float(hi)), True
        steps = raw.get("steps", 2)
        if not isinstance(steps, int) or steps < 1:
            raise InputError(where, raw, "steps: expected an integer >= 1")
        return tuple(float(v) for v in np.linspace(lo, hi, steps)), False
    raise InputError(where, raw, "expected a list of values or a table {min, max, steps}")


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _table(data: dict, key: str) -> dict:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise InputError(key, value, "expected a table")
    return value


def load_spec(path: str | Path) -> SweepSpec:
    """Read a sweep spec (TOML); every bad value is an :class:`InputError` naming it."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except OSError as exc:
        raise InputError("spec", str(path), f"cannot read file: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError("spec", str(path), f"not valid TOML: {exc}") from None
    unknown = sorted(set(data) - {"base", "evaluate", "statics", "sample", "parameters", "checks", "placement"})
    if unknown:
        raise InputError(unknown[0], data[unknown[0]], "unknown table or key of a sweep spec")
    base_name = data.get("base")
    if not isinstance(base_name, str):
        raise InputError("base", base_name, "expected a preset name or a geometry file")
    if base_name in PRESETS:
        base, source = get_preset(base_name), base_name
    else:
        file = (path.parent / base_name).resolve()
        base, source = load_geometry(file), str(file)
    sample = _table(data, "sample")
    mode = sample.get("mode", "grid")
    if mode not in MODES:
        raise InputError("sample.mode", mode, f"expected one of {MODES}")
    count, seed = sample.get("count", 0), sample.get("seed", 0)
    if mode == "random" and (not isinstance(count, int) or not 1 <= count <= MAX_CANDIDATES):
        raise InputError("sample.count", count, f"expected an integer in [1, {MAX_CANDIDATES}]")
    if not isinstance(seed, int):
        raise InputError("sample.seed", seed, "expected an integer")
    raw = _table(data, "parameters")
    if not raw:
        raise InputError("parameters", raw, f"name at least one of {sorted(PARAMETERS)}")
    params, ranges = {}, set()
    for name, value in raw.items():
        if name not in PARAMETERS:
            raise InputError(f"parameters.{name}", value, f"unknown parameter (known: {sorted(PARAMETERS)})")
        params[name], is_range = _values(name, value, mode)
        if is_range:
            ranges.add(name)
        if name in SENSOR_PARAMETERS:
            check_sensor_parameter(name, params[name], base)
        if name in LENGTHS:  # metres: a value in mm would rate a platform 1000 times the base's size
            for v in params[name]:
                check_length(f"parameters.{name}", name, v, base.base_radius)
    if mode == "grid" and math.prod(len(v) for v in params.values()) > MAX_CANDIDATES:
        raise InputError("parameters", "grid", f"more than {MAX_CANDIDATES} candidates")
    ev = _table(data, "evaluate")
    bad = sorted(set(ev) - {"grid", "cone_deg", "cone_samples", "length_unit"})
    if bad:
        raise InputError(f"evaluate.{bad[0]}", ev[bad[0]], "unknown setting")
    settings = replace(Settings(), **ev)
    if not isinstance(settings.grid, int) or isinstance(settings.grid, bool) or not 2 <= settings.grid <= 401:
        raise InputError("evaluate.grid", settings.grid, "expected an integer in [2, 401]")
    if (
        not isinstance(settings.cone_samples, int)
        or isinstance(settings.cone_samples, bool)
        or settings.cone_samples < 1
    ):
        raise InputError("evaluate.cone_samples", settings.cone_samples, "expected an integer >= 1")
    if not _is_number(settings.cone_deg) or not 0 <= settings.cone_deg < 90:
        raise InputError("evaluate.cone_deg", settings.cone_deg, "expected a half-angle in [0, 90) deg")
    if settings.length_unit is not None and not (_is_number(settings.length_unit) and settings.length_unit > 0):
        raise InputError("evaluate.length_unit", settings.length_unit, "expected a positive length in m")
    statics = _table(data, "statics")
    k = statics.get("leg_stiffness")
    if k is not None and not (isinstance(k, (int, float)) and math.isfinite(k) and k > 0):
        raise InputError("statics.leg_stiffness", k, "expected a positive stiffness in N/m")
    clearance = _table(data, "checks").get("leg_clearance", 0.0)
    if not (isinstance(clearance, (int, float)) and 0 <= clearance < 1):
        raise InputError("checks.leg_clearance", clearance, "expected a distance in [0, 1) m")
    placement = placement_settings(data["placement"], base) if "placement" in data else None
    stiffness = k and float(k)
    return SweepSpec(
        base, source, params, frozenset(ranges), mode, count, seed, settings, stiffness, float(clearance), placement
    )
