"""Where to put the seventh leg: the worst minimal detectable fault of a few placements on the reference fixture.

python benchmarks/seventh_leg_placement.py [--grid 3] [--half-width 0.05]

For each placement of a measuring leg added to the ``reference`` preset, the largest minimal
detectable bias of any reading over the x-y section of ``--half-width`` around home
(:func:`hexapod_model.analysis.detectability.detectability_map`), and each reading's largest,
in micrometres (the table of docs/redundancy.md).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from hexapod_model import Hexapod, get_preset
from hexapod_model.analysis.detectability import detectability_map
from hexapod_model.description.sensors import MeasuringLeg


def placements() -> dict[str, tuple[tuple[float, ...], tuple[float, ...]]]:
    """Name -> (base anchor in the base frame, platform anchor in the platform frame), m."""
    leg1 = get_preset("reference").legs[0]
    up = np.array([0.0, 0.0, 0.02])
    return {
        "(0.25, 0, 0) -> (-0.15, 0, 0), reference7": ((0.25, 0.0, 0.0), (-0.15, 0.0, 0.0)),
        "(0.25, 0, 0) -> (0.15, 0, 0)": ((0.25, 0.0, 0.0), (0.15, 0.0, 0.0)),
        "(0, 0, 0) -> (0, 0, 0)": ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
        "(0.25, 0, 0) -> (-0.075, 0.13, 0)": ((0.25, 0.0, 0.0), (-0.075, 0.13, 0.0)),
        "leg 1's anchors, 2 cm higher": (
            tuple(np.array(leg1.base_anchor) + up),
            tuple(np.array(leg1.platform_anchor) + up),
        ),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=3, help="grid points along x and y")
    ap.add_argument("--half-width", type=float, default=0.05, help="m: the section spans home +- this")
    args = ap.parse_args()
    ref = get_preset("reference")
    for name, (b, p) in placements().items():
        leg = MeasuringLeg(base_anchor=b, platform_anchor=p, stroke=(-0.16, 0.20))
        geom = dataclasses.replace(ref, name="placement", measuring_legs=(leg,))
        dmap = detectability_map(Hexapod.from_geometry(geom), half_width=args.half_width, grid=args.grid)
        worst = 1e6 * np.nanmax(dmap.mdb.reshape(-1, len(dmap.names)), axis=0)
        per = " ".join(f"{v:.3g}" for v in worst)
        print(f"{name:45s} worst {worst.max():10.4g} um   per reading (leg1..leg7): {per}")


if __name__ == "__main__":
    main()
