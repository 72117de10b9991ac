"""Where to put a redundant sensor: candidate placements ranked by their worst detectable fault.

A measuring leg or an inclinometer added to a geometry
(:mod:`hexapod_model.description.sensors`) makes a single bad leg reading detectable; how small a
fault it detects depends on where it goes (docs/redundancy.md). :func:`score_section` maps every
reading's minimal detectable bias over the x-y section of the workspace at home height and home
orientation (:func:`hexapod_model.analysis.detectability.detectability_map`) and scores the
geometry by the largest bias of any leg reading there (m): the fault size the test is sure to see
(with the map's power) wherever the platform is on the section. :func:`rank_placements` scores
each candidate sensor added to a geometry; the best has the smallest score (``hexapod evaluate
--place-seventh-leg``, ``--place-inclinometer``; ``hexapod sweep`` with a ``[placement]`` table).

A candidate measuring leg is added after the geometry's own; a candidate inclinometer replaces
the geometry's (a geometry carries at most one). The candidates come in a TOML file of
``[[measuring_legs]]`` and ``[[inclinometers]]`` tables, each written as in a geometry file
(:func:`candidates_from_toml`) and each one candidate; an inclinometer candidate states its
mounting rotation (``rpy`` in rad or ``rpy_deg`` in deg).

What an inclinometer's mounting changes: its two readings depend on the platform's orientation
only, never on where on the platform it sits, and on the platform's rotation only through the
directions of its two sensing axes. Each reading's row of the whitened Jacobian is a horizontal
unit vector (perpendicular to the horizontal projection of that sensing axis) over ``sigma``.
Two mountings whose rows differ by an orthogonal 2x2 transformation give the same detectability
of every leg reading; this holds for every mounting whose two sensing axes project onto
perpendicular horizontal directions (any single rotation about one axis, e.g. a turn about the
vertical). Only a skewed mounting (roll and pitch together: the projected axes no longer
perpendicular) and the sensor's ``sigma`` change the score (docs/redundancy.md).
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..description.geometry import HexapodGeometry
from ..description.sensor_layout import rpy_matrix
from ..description.sensors import Inclinometer, MeasuringLeg, sensors_from_dict
from ..exceptions import GeometryError, InputError
from ..kinematics.hexapod import Hexapod
from .detectability import DEFAULT_HALF_WIDTH, detectability_map

DEFAULT_PLACEMENT_GRID = 5  # points along x and along y of each candidate's section
#: relative difference of two scores below which the ranking cannot tell them apart: the
#: Jacobian is taken by central differences, whose rounding moves a score by about 1e-12 relative
TIE_RTOL = 1e-6
#: the largest elevation (deg) of an inclinometer's sensing axis above the platform plane: near
#: the vertical a tilt reading (an arcsine) loses its slope and the axis's direction its meaning
MAX_AXIS_ELEVATION_DEG = 85.0
KINDS = ("measuring_legs", "inclinometers")

Sensor = MeasuringLeg | Inclinometer


@dataclass(frozen=True)
class SectionScore:
    """A geometry's detectability over the section (module doc).

    Attributes:
        names: the readings, reading order.
        largest: (m,) each reading's largest minimal detectable bias over the section (m for
            legs, rad for tilts; inf: a reading whose fault never shows; nan: no grid point
            inside the workspace).
        worst: the largest of the leg readings' (m): the score, smaller is better (inf when
            no grid point is inside the workspace).
        inside: grid points of the section inside the workspace.
    """

    names: tuple[str, ...]
    largest: np.ndarray
    worst: float
    inside: int


@dataclass(frozen=True)
class PlacementScore:
    """One candidate sensor's detectability over the section (the fields of :class:`SectionScore`).

    Attributes:
        index: the candidate's position in the list given (0-based).
        sensor: the candidate (a measuring leg or an inclinometer).
        names: the readings with the candidate added, reading order.
        largest: (m,) each reading's largest minimal detectable bias over the section (m, rad).
        worst: the largest of the leg readings' (m): the score, smaller is better.
        inside: grid points of the section inside the workspace.
    """

    index: int
    sensor: Sensor
    names: tuple[str, ...]
    largest: np.ndarray
    worst: float
    inside: int


def score_section(
    geometry: HexapodGeometry, half_width: float = DEFAULT_HALF_WIDTH, grid: int = DEFAULT_PLACEMENT_GRID
) -> SectionScore:
    """The detectability score of ``geometry`` as it is, with its redundant sensors (module doc).

    Args:
        geometry: a hexapod with measuring legs or an inclinometer.
        half_width: half side of the square x-y section at home height (m).
        grid: points along each side of the section (>= 2).

    Raises:
        InputError: a geometry without redundant sensors, or a bad section.
    """
    dmap = detectability_map(Hexapod.from_geometry(geometry), half_width=half_width, grid=grid)
    flat = dmap.mdb.reshape(-1, len(dmap.names))
    ok = ~np.any(np.isnan(flat), axis=1)  # nan: outside the workspace (inf: undetectable)
    largest = np.max(flat[ok], axis=0) if ok.any() else np.full(len(dmap.names), np.nan)
    legs = [j for j, n in enumerate(dmap.names) if n.startswith("leg")]
    worst = float(np.max(largest[legs])) if ok.any() else float("inf")
    return SectionScore(dmap.names, largest, worst, int(ok.sum()))


def with_sensor(geometry: HexapodGeometry, sensor: Sensor) -> HexapodGeometry:
    """``geometry`` with ``sensor`` added (a measuring leg, after its own) or in place of its inclinometer."""
    if isinstance(sensor, Inclinometer):
        return dataclasses.replace(geometry, inclinometer=sensor)
    return dataclasses.replace(geometry, measuring_legs=(*geometry.measuring_legs, sensor))


def rank_placements(
    geometry: HexapodGeometry,
    candidates: tuple[Sensor, ...],
    half_width: float = DEFAULT_HALF_WIDTH,
    grid: int = DEFAULT_PLACEMENT_GRID,
) -> list[PlacementScore]:
    """Score each candidate sensor added to ``geometry``; best (smallest worst bias) first.

    Args:
        geometry: the hexapod; a candidate measuring leg is added after the measuring legs it
            declares (its inclinometer, if any, stays); a candidate inclinometer replaces its
            inclinometer (its measuring legs stay).
        candidates: the measuring legs and inclinometers to compare (at least one).
        half_width: half side of the square x-y section at home height (m).
        grid: points along each side of the section (>= 2).

    Raises:
        InputError: no candidate, or a bad section.
    """
    if not candidates:
        raise InputError("candidates", candidates, "expected at least one measuring leg or inclinometer to place")
    scores = []
    for k, sensor in enumerate(candidates):
        s = score_section(with_sensor(geometry, sensor), half_width, grid)
        scores.append(PlacementScore(k, sensor, s.names, s.largest, s.worst, s.inside))
    return sorted(scores, key=lambda s: (s.worst, s.index))


def tied(a: float, b: float) -> bool:
    """Whether two scores are equal within :data:`TIE_RTOL` (the criterion cannot rank them)."""
    return a == b or abs(a - b) <= TIE_RTOL * max(abs(a), abs(b))


def check_inclinometer_rotation(where: str, rpy: tuple[float, float, float]) -> None:
    """Refuse a mounting rotation (rad) out of range or with a sensing axis near the vertical.

    Roll and yaw lie in [-pi, pi], pitch in [-pi/2, pi/2] (URDF rpy); each sensing axis stays
    within :data:`MAX_AXIS_ELEVATION_DEG` of the platform plane.

    Raises:
        GeometryError: naming the angle or the axis and the limit.
    """
    for name, v, lim in zip(("roll", "pitch", "yaw"), rpy, (math.pi, math.pi / 2, math.pi), strict=True):
        if abs(v) > lim:
            raise GeometryError(
                f"{where}.rpy", list(rpy), f"{name} {v:g} rad is beyond +-{lim:.6g} rad (degrees belong in rpy_deg)"
            )
    S = rpy_matrix(rpy)
    for axis, j in (("x", 0), ("y", 1)):
        elevation = math.degrees(math.asin(min(1.0, abs(float(S[2, j])))))
        if elevation > MAX_AXIS_ELEVATION_DEG:
            raise GeometryError(
                f"{where}.rpy",
                list(rpy),
                f"its {axis} axis rises {elevation:.4g} deg above the platform plane "
                f"(at most {MAX_AXIS_ELEVATION_DEG:g} deg: a tilt reading loses its slope near the vertical)",
            )


def _inclinometers(raw: Any, path: str | Path) -> tuple[Inclinometer, ...]:
    if not isinstance(raw, list):
        raise GeometryError("inclinometers", raw, f"expected [[inclinometers]] tables in {path}")
    out = []
    for i, table in enumerate(raw):
        where = f"inclinometers[{i}]"
        if not isinstance(table, dict):
            raise GeometryError(where, table, "expected a table")
        if "rpy" not in table and "rpy_deg" not in table:
            raise GeometryError(f"{where}.rpy_deg", None, "required: the mounting rotation (rpy in rad or rpy_deg)")
        if "rpy" in table and "rpy_deg" in table:
            raise GeometryError(f"{where}.rpy", table["rpy"], "give rpy (rad) or rpy_deg (deg), not both")
        try:
            incl = sensors_from_dict({"inclinometer": table})["inclinometer"]
        except GeometryError as exc:
            raise GeometryError(exc.field.replace("inclinometer", where, 1), exc.value, exc.reason) from None
        check_inclinometer_rotation(where, incl.rpy)
        out.append(incl)
    return tuple(out)


def candidates_from_toml(path: str | Path, kinds: tuple[str, ...] = KINDS) -> tuple[Sensor, ...]:
    """The candidate sensors of a TOML file: its ``[[measuring_legs]]``, then its ``[[inclinometers]]`` (module doc).

    Args:
        path: the file.
        kinds: the tables it may hold (of :data:`KINDS`).

    Raises:
        InputError: a file that cannot be read or is not TOML.
        GeometryError: no candidate table, another key, or a bad candidate (naming its field).
    """
    try:
        data = tomllib.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise InputError("candidates", str(path), f"cannot read it as TOML: {exc}") from None
    expected = " or ".join(f"[[{k}]]" for k in kinds)
    other = sorted(set(data) - set(kinds))
    if other:
        raise GeometryError(other[0], data[other[0]], f"unknown key in {path} (expected {expected} tables)")
    if not any(data.get(k) for k in kinds):
        raise GeometryError(kinds[0], None, f"{path} has no {expected} table: no candidate")
    legs: tuple[Sensor, ...] = ()
    if data.get("measuring_legs"):
        legs = sensors_from_dict({"measuring_legs": data["measuring_legs"]})["measuring_legs"]
    return legs + _inclinometers(data.get("inclinometers", []), path)
