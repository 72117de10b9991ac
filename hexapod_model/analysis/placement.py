"""Where to put a measuring leg: candidate placements ranked by their worst detectable fault.

A measuring leg added to a geometry (:class:`hexapod_model.description.sensors.MeasuringLeg`)
makes a single bad reading detectable; how small a fault it detects depends on where it goes
(docs/redundancy.md). For each candidate, :func:`rank_placements` adds it to the geometry's
sensors, maps every reading's minimal detectable bias over the x-y section of the workspace at
home height (:func:`hexapod_model.analysis.detectability.detectability_map`) and scores it by
the largest bias of any leg reading there: the fault size the test is sure to see (with the map's
power) wherever the platform is on the section. The best placement has the smallest score
(``hexapod evaluate --place-seventh-leg``).

The candidates come in a TOML file of ``[[measuring_legs]]`` tables, each written as in a
geometry file (:func:`candidates_from_toml`) and each one candidate.
"""

from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..description.geometry import HexapodGeometry
from ..description.sensors import MeasuringLeg, sensors_from_dict
from ..exceptions import GeometryError, InputError
from ..kinematics.hexapod import Hexapod
from .detectability import DEFAULT_HALF_WIDTH, detectability_map

DEFAULT_PLACEMENT_GRID = 5  # points along x and along y of each candidate's section


@dataclass(frozen=True)
class PlacementScore:
    """One candidate measuring leg's detectability over the section.

    Attributes:
        index: the candidate's position in the list given (0-based).
        leg: the candidate.
        names: the readings with the candidate added, reading order.
        largest: (m,) each reading's largest minimal detectable bias over the section (m for
            legs, rad for tilts; inf: a reading whose fault never shows; nan: no grid point
            inside the workspace).
        worst: the largest of the leg readings' (m): the score, smaller is better (inf when
            no grid point is inside the workspace).
        inside: grid points of the section inside the workspace.
    """

    index: int
    leg: MeasuringLeg
    names: tuple[str, ...]
    largest: np.ndarray
    worst: float
    inside: int


def rank_placements(
    geometry: HexapodGeometry,
    candidates: tuple[MeasuringLeg, ...],
    half_width: float = DEFAULT_HALF_WIDTH,
    grid: int = DEFAULT_PLACEMENT_GRID,
) -> list[PlacementScore]:
    """Score each candidate measuring leg added to ``geometry``; best (smallest worst bias) first.

    Args:
        geometry: the hexapod; a candidate is added after the measuring legs it declares (its
            inclinometer, if any, stays).
        candidates: the measuring legs to compare (at least one).
        half_width: half side of the square x-y section at home height (m).
        grid: points along each side of the section (>= 2).

    Raises:
        InputError: no candidate, or a bad section.
    """
    if not candidates:
        raise InputError("candidates", candidates, "expected at least one measuring leg to place")
    scores = []
    for k, leg in enumerate(candidates):
        geom = dataclasses.replace(geometry, measuring_legs=(*geometry.measuring_legs, leg))
        dmap = detectability_map(Hexapod.from_geometry(geom), half_width=half_width, grid=grid)
        flat = dmap.mdb.reshape(-1, len(dmap.names))
        ok = ~np.any(np.isnan(flat), axis=1)  # nan: outside the workspace (inf: undetectable)
        largest = np.max(flat[ok], axis=0) if ok.any() else np.full(len(dmap.names), np.nan)
        legs = [j for j, n in enumerate(dmap.names) if n.startswith("leg")]
        worst = float(np.max(largest[legs])) if ok.any() else float("inf")
        scores.append(PlacementScore(k, leg, dmap.names, largest, worst, int(ok.sum())))
    return sorted(scores, key=lambda s: (s.worst, s.index))


def candidates_from_toml(path: str | Path) -> tuple[MeasuringLeg, ...]:
    """The candidate measuring legs of a TOML file: its ``[[measuring_legs]]`` tables (module doc).

    Raises:
        InputError: a file that cannot be read or is not TOML.
        GeometryError: no ``[[measuring_legs]]`` table, another key, or a bad leg (naming its field).
    """
    try:
        data = tomllib.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise InputError("candidates", str(path), f"cannot read it as TOML: {exc}") from None
    other = sorted(set(data) - {"measuring_legs"})
    if other:
        raise GeometryError(other[0], data[other[0]], f"unknown key in {path} (expected [[measuring_legs]] tables)")
    if not data.get("measuring_legs"):
        raise GeometryError("measuring_legs", None, f"{path} has no [[measuring_legs]] table: no candidate")
    return sensors_from_dict({"measuring_legs": data["measuring_legs"]})["measuring_legs"]
