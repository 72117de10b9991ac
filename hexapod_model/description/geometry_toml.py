"""Write a geometry as a TOML file (the format :func:`~hexapod_model.description.geometry.load_geometry` reads).

Per-leg values that all legs share go to the short, hexapod-level form (:func:`compact`), so a
calibrated file lists per leg only what differs between legs. Numbers are written with
``repr`` (the shortest text that reads back to the same float): file -> geometry is exact.
Extra sensors follow the legs as ``[[measuring_legs]]`` tables and an ``[inclinometer]`` table.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from ..files import atomic_write_text
from .geometry import HexapodGeometry


def compact(geom: HexapodGeometry) -> HexapodGeometry:
    """The same hexapod with uniform per-leg offsets moved to the hexapod level.

    An offset that every leg has in common becomes ``base_offset`` / ``platform_offset`` and
    leaves the legs; a leg value equal to the hexapod-level one is dropped.
    """
    base = [geom.offsets(i)[0] for i in range(6)]
    plat = [geom.offsets(i)[1] for i in range(6)]
    eb = base[0] if all(v == base[0] for v in base) else geom.base_offset
    ep = plat[0] if all(v == plat[0] for v in plat) else geom.platform_offset
    legs = tuple(
        replace(leg, base_offset=None if b == eb else b, platform_offset=None if p == ep else p)
        for leg, b, p in zip(geom.legs, base, plat)
    )
    return replace(geom, legs=legs, base_offset=eb, platform_offset=ep)


def _value(v) -> str:
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return repr(float(v))


def geometry_to_toml(geom: HexapodGeometry, comment: str = "") -> str:
    """TOML text of ``compact(geom)``; ``comment`` lines go first, each prefixed with ``#``."""
    data = compact(geom).to_dict()
    lines = [f"# {line}".rstrip() for line in comment.splitlines()]
    legs = data.pop("legs")
    measuring = data.pop("measuring_legs", [])
    inclinometer = data.pop("inclinometer", None)
    lines += [f"{k} = {_value(v)}" for k, v in data.items()]
    for name, table in [("[[legs]]", leg) for leg in legs] + [("[[measuring_legs]]", leg) for leg in measuring]:
        lines += ["", name] + [f"{k} = {_value(v)}" for k, v in table.items()]
    if inclinometer is not None:
        lines += ["", "[inclinometer]"] + [f"{k} = {_value(v)}" for k, v in inclinometer.items()]
    return "\n".join(lines) + "\n"


def save_geometry(geom: HexapodGeometry, path: str | Path, comment: str = "") -> Path:
    """Write :func:`geometry_to_toml` to ``path`` atomically; returns the path."""
    return atomic_write_text(path, geometry_to_toml(geom, comment))
