"""A sweep over sensor placements (docs/sweep.md): the sensor parameters, the ``[placement]`` table, the ranking.

A spec whose base declares a measuring leg or an inclinometer may vary them as it varies the
legs: the ``measuring_*`` parameters move the base geometry's last measuring leg's anchors, the
``inclinometer_*`` ones turn its inclinometer or change its noise (:data:`SENSOR_PARAMETERS`). A
``[placement]`` table scores every candidate by the placement criterion of
:func:`hexapod_model.analysis.placement.score_section` (the largest minimal detectable fault of
any leg reading over the x-y section at home height, m; smaller is better) and ranks them::

    [placement]
    grid = 5             # points along x and y of the section (>= 2)
    half_width = 0.05    # m: the section spans home +- this in x and y
    workspace = false    # skip the workspace figures (the sensors do not change them)

Each candidate's score is computed in its Dask task from the candidate's geometry file by the
same function ``hexapod evaluate --place-seventh-leg`` / ``--place-inclinometer`` calls, so the
two rank the same candidates identically.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ..analysis.detectability import DEFAULT_HALF_WIDTH
from ..analysis.placement import DEFAULT_PLACEMENT_GRID, check_inclinometer_rotation, score_section
from ..description.geometry import HexapodGeometry
from ..exceptions import InputError
from ..files import atomic_write_csv

#: sensor parameters: name -> meaning (SI; angles in degrees where the name says so)
SENSOR_PARAMETERS = {
    "measuring_base_x": "x of the last measuring leg's base anchor (m, base frame)",
    "measuring_base_y": "y of the last measuring leg's base anchor (m, base frame)",
    "measuring_base_z": "z of the last measuring leg's base anchor (m, base frame)",
    "measuring_platform_x": "x of the last measuring leg's platform anchor (m, platform frame)",
    "measuring_platform_y": "y of the last measuring leg's platform anchor (m, platform frame)",
    "measuring_platform_z": "z of the last measuring leg's platform anchor (m, platform frame)",
    "inclinometer_roll_deg": "the inclinometer's mounting roll in the platform frame (deg, URDF rpy)",
    "inclinometer_pitch_deg": "its mounting pitch (deg)",
    "inclinometer_yaw_deg": "its mounting yaw (deg)",
    "inclinometer_sigma": "standard deviation of each of its angles (rad)",
}
SENSOR_LENGTHS = tuple(n for n in SENSOR_PARAMETERS if n.startswith("measuring_"))
ANGLE_LIMITS_DEG = {"inclinometer_roll_deg": 180.0, "inclinometer_pitch_deg": 90.0, "inclinometer_yaw_deg": 180.0}
#: the columns a ``[placement]`` sweep adds: the score (m), the section's points inside, the rank (1: best)
PLACEMENT_METRICS = ("placement_worst_m", "placement_points_inside", "placement_rank")


@dataclass(frozen=True)
class PlacementSettings:
    """The ``[placement]`` table of a spec (module doc).

    Attributes:
        grid: points along x and along y of the section.
        half_width: half side of the section (m).
        workspace: whether each candidate also gets the workspace and statics figures.
    """

    grid: int = DEFAULT_PLACEMENT_GRID
    half_width: float = DEFAULT_HALF_WIDTH
    workspace: bool = True


def placement_settings(raw: Any, base: HexapodGeometry) -> PlacementSettings:
    """The ``[placement]`` table checked against the base geometry.

    Raises:
        InputError: an unknown key, a bad value, or a base without redundant sensors (naming it).
    """
    if not isinstance(raw, dict):
        raise InputError("placement", raw, "expected a table")
    bad = sorted(set(raw) - {"grid", "half_width", "workspace"})
    if bad:
        raise InputError(f"placement.{bad[0]}", raw[bad[0]], "unknown key (known: grid, half_width, workspace)")
    s = replace(PlacementSettings(), **raw)
    if type(s.grid) is not int or not 2 <= s.grid <= 101:
        raise InputError("placement.grid", s.grid, "expected an integer in [2, 101]")
    hw = s.half_width
    if not (isinstance(hw, (int, float)) and not isinstance(hw, bool) and math.isfinite(hw) and 0 < hw < 10):
        raise InputError("placement.half_width", hw, "expected a half side in (0, 10) m")
    if not isinstance(s.workspace, bool):
        raise InputError("placement.workspace", s.workspace, "expected true or false")
    if not base.redundant:
        raise InputError("placement", raw, f"the base {base.name} declares no measuring leg or inclinometer to place")
    return replace(s, half_width=float(hw))


def check_sensor_parameter(name: str, values: tuple[float, ...], base: HexapodGeometry) -> None:
    """Refuse a sensor parameter the base has no sensor for, or an angle out of its range.

    Raises:
        InputError: naming the parameter and the limit.
    """
    if name.startswith("measuring_") and not base.measuring_legs:
        raise InputError(
            f"parameters.{name}", list(values), f"the base {base.name} has no measuring leg to move (e.g. reference7)"
        )
    if name.startswith("inclinometer_") and base.inclinometer is None:
        raise InputError(
            f"parameters.{name}", list(values), f"the base {base.name} declares no inclinometer (e.g. reference_tilt)"
        )
    lim = ANGLE_LIMITS_DEG.get(name)
    for v in values:
        if lim is not None and abs(v) > lim:
            raise InputError(f"parameters.{name}", v, f"beyond +-{lim:g} deg")


def apply_sensors(g: HexapodGeometry, values: dict[str, float]) -> HexapodGeometry:
    """``g`` with the sensor parameters of ``values`` applied (the others are ignored).

    Raises:
        GeometryError: the result is not a valid sensor (its message names the field).
    """
    legs = g.measuring_legs
    if legs and any(n.startswith("measuring_") for n in values):
        last = legs[-1]
        bx, by, bz = (values.get(f"measuring_base_{c}", last.base_anchor[i]) for i, c in enumerate("xyz"))
        px, py, pz = (values.get(f"measuring_platform_{c}", last.platform_anchor[i]) for i, c in enumerate("xyz"))
        legs = (*legs[:-1], replace(last, base_anchor=(bx, by, bz), platform_anchor=(px, py, pz)))
    incl = g.inclinometer
    if incl is not None and any(n.startswith("inclinometer_") for n in values):
        r, p, y = (
            math.radians(values[f"inclinometer_{a}_deg"]) if f"inclinometer_{a}_deg" in values else incl.rpy[i]
            for i, a in enumerate(("roll", "pitch", "yaw"))
        )
        rpy = (r, p, y)
        check_inclinometer_rotation("inclinometer", rpy)
        incl = replace(incl, rpy=rpy, sigma=values.get("inclinometer_sigma", incl.sigma))
    return replace(g, measuring_legs=legs, inclinometer=incl)


def placement_figures(g: HexapodGeometry, settings: PlacementSettings) -> dict[str, Any]:
    """A candidate's placement columns (without its rank): the score (m) and the section's points inside."""
    s = score_section(g, settings.half_width, settings.grid)
    return {"placement_worst_m": s.worst, "placement_points_inside": s.inside}


def rank_rows(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The valid rows best first (smallest score, then spec order), each given its ``placement_rank``."""
    ok = [(float(r["placement_worst_m"]), k, r) for k, r in enumerate(rows) if r.get("status") == "ok"]
    ranked = [r for _, _, r in sorted(ok, key=lambda t: (t[0], t[1]))]
    for rank, r in enumerate(ranked, 1):
        r["placement_rank"] = rank
    return ranked


def write_placement_table(path: Path, ranked: list[dict[str, Any]], parameters: list[str]) -> Path:
    """``placement.csv``: the valid candidates best first: rank, id, the parameters, score, points, geometry."""
    header = ["placement_rank", "id", *parameters, "placement_worst_m", "placement_points_inside", "geometry"]
    return atomic_write_csv(path, header, ranked)
