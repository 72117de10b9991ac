"""Write Jakobović and Jelenković's two hexapods (Table I) as geometry files docs/geometries/seed002_model{1,2}.toml.

Reading of the paper (see docs/evaluate.md): one paper length unit = 1 cm = 0.01 m; angles alpha,
beta = 0 put the two anchors of a pair at the same point (3-3 layouts); model 2's r1, r2 are
the radii of the guideway ends (the paper's r11, r12) and r_b2 the platform joint radius; legs of base pair k go
to the platform points at 120k +- 60 deg; phi_max = 45 deg is the Cardan angle limit; the home
pose is mid-stroke (model 1) / sliders at mid-rail (model 2); the tool length l_alat = 0 puts the
tool point at the platform origin. The paper counts a point only without "collision between
struts" but gives no strut size: 30 mm struts (``STRUT_RADIUS``) in 34 mm joint housings.

Usage: python scripts/make_seed002_geometries.py [OUTDIR]
"""

from __future__ import annotations

import inspect
import math
import sys
from pathlib import Path

import numpy as np

from hexapod_model.description.geometry import HexapodGeometry, LegGeometry
from hexapod_model.kinematics.hexapod import Hexapod

UNIT = 0.01  # metres per paper unit
#: m: the struts' collision radius and the joint housings' (the paper states no strut size): 30 mm
#: struts in 34 mm housings keep model 2's paired struts, 35 mm apart on their guideways, clear at home
STRUT_RADIUS, HOUSING_RADIUS = 0.015, 0.017


def _circle(r: float, deg: float, z: float = 0.0) -> tuple[float, float, float]:
    a = math.radians(deg)
    return (r * math.cos(a) * UNIT, r * math.sin(a) * UNIT, z * UNIT)


def model1() -> HexapodGeometry:
    """Table I, model 1: l in [45, 85], r1 = 50, r2 = 25, alpha = beta = 0, phi_max = 45 deg."""
    lmin, lmax, r1, r2 = 45.0, 85.0, 50.0, 25.0
    l0 = (lmin + lmax) / 2
    horiz = math.dist(_circle(r1, 0.0), _circle(r2, 60.0)) / UNIT
    h = math.sqrt(l0**2 - horiz**2)
    legs = [
        LegGeometry(
            base_anchor=_circle(r1, 120.0 * k),
            platform_anchor=_circle(r2, 120.0 * k + s * 60.0),
            stroke=((lmin - l0) * UNIT, (lmax - l0) * UNIT),
        )
        for k in range(3)
        for s in (-1, 1)
    ]
    return HexapodGeometry(
        name="seed002_model1",
        joint_type="spherical",
        legs=tuple(legs),
        home_height=h * UNIT,
        cardan_limit=math.radians(45.0),
        leg_radius=STRUT_RADIUS,
        housing_radius=HOUSING_RADIUS,
        description="Jakobović and Jelenković's Table I model 1: 3-3 platform, struts 45-85 cm, r1 50 cm, r2 25 cm",
    )


def model2() -> HexapodGeometry:
    """Table I, model 2: fixed struts l = 70 on guideways.

    The guideways run from r1 = 75 (floor) up to r2 = 10 at height h = 20 (r1, r2 = the
    paper's r11, r12), pairs d = 3.5 apart; platform joints on r_b2 = 30, beta = 0,
    phi_max = 45 deg.
    """
    l, r_out, r_in, h, d, r2 = 70.0, 75.0, 10.0, 20.0, 3.5, 30.0
    rail_len = math.hypot(r_out - r_in, h)
    legs, heights = [], []
    for k in range(3):
        c = math.radians(120.0 * k)
        radial = np.array([math.cos(c), math.sin(c), 0.0])
        tangent = np.array([-math.sin(c), math.cos(c), 0.0])
        rail = np.array([-(r_out - r_in) * radial[0], -(r_out - r_in) * radial[1], h]) / rail_len
        for s in (-1, 1):
            mid = radial * (r_out + r_in) / 2 + s * d / 2 * tangent + np.array([0.0, 0.0, h / 2])
            top = np.array(_circle(r2, 120.0 * k + s * 60.0)) / UNIT
            horiz = float(np.linalg.norm(top[:2] - mid[:2]))
            heights.append(mid[2] + math.sqrt(l**2 - horiz**2))
            legs.append(
                dict(
                    base_anchor=tuple(mid * UNIT),
                    platform_anchor=tuple(top * UNIT),
                    stroke=(-rail_len / 2 * UNIT * 0.999, rail_len / 2 * UNIT * 0.999),
                    guideway=tuple(rail),
                )
            )
    assert max(heights) - min(heights) < 1e-9, heights
    return HexapodGeometry(
        name="seed002_model2",
        joint_type="guideway",
        legs=tuple(LegGeometry(**leg) for leg in legs),
        home_height=heights[0] * UNIT,
        cardan_limit=math.radians(45.0),
        leg_radius=STRUT_RADIUS,
        housing_radius=HOUSING_RADIUS,
        description="Jakobović and Jelenković's Table I model 2: 70 cm struts on guideways r 75->10 cm, platform 30 cm",
    )


def to_toml(g: HexapodGeometry, header: str) -> str:
    def num(x: float) -> str:
        return repr(round(float(x), 12))

    def vec(v) -> str:
        return "[" + ", ".join(num(x) for x in v) + "]"

    lines = [f"# {line}" if line else "#" for line in header.strip().splitlines()]
    lines += [
        "",
        f'name = "{g.name}"',
        f'joint_type = "{g.joint_type}"',
        f'description = "{g.description}"',
        f"home_height = {num(g.home_height)}",
        f"cardan_limit_deg = {num(math.degrees(g.cardan_limit))}",
        f"leg_radius = {num(g.leg_radius)}  # m, the paper states no strut size (docs/evaluate.md)",
        f"housing_radius = {num(g.housing_radius)}",
    ]
    for leg in g.legs:
        lines += [
            "",
            "[[legs]]",
            f"base_anchor = {vec(leg.base_anchor)}",
            f"platform_anchor = {vec(leg.platform_anchor)}",
            f"stroke = {vec(leg.stroke)}",
        ]
        if leg.guideway is not None:
            lines.append(f"guideway = {vec(leg.guideway)}")
    return "\n".join(lines) + "\n"


def main(outdir: str = "docs/geometries") -> None:
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    for factory in (model1, model2):
        g = factory()
        Hexapod.from_geometry(g)  # must load and assemble
        header = (
            f"Generated by scripts/make_seed002_geometries.py. Units: metres (1 paper unit = 1 cm).\n"
            f"{inspect.getdoc(factory)}\nSee docs/evaluate.md for the reading of the paper."
        )
        path = out / f"{g.name}.toml"
        path.write_text(to_toml(g, header))
        print(f"wrote {path}")


if __name__ == "__main__":
    main(*sys.argv[1:])
