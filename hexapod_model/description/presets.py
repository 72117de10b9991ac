"""Bundled hexapod geometries. ``PRESETS`` maps a name to a zero-argument factory.

All dimensions are in metres and radians. The ``reference`` hexapod is our stand-in for the
fixture of Bem et al. (2026) (its paper gives no dimensions): anchors on a 0.25 m (base) and 0.15 m
(platform) radius, 0.40 m between the anchor planes at home (0.45 m legs), 12 mm Cardan axis
offsets (the order of the patented preloaded hub), 70 deg Cardan limits, +-90 deg roll and a
-0.16 / +0.20 m leg stroke, so that the whole +-50 mm / +-25 deg test box of Bem et al. (2026), corners
included, lies inside the stroke and joint limits (the corners need up to 67 deg on the
platform Cardan joints and -0.147 / +0.185 m of stroke).

Joint cones (:mod:`~hexapod_model.description.body`): the Cardan presets take 75 deg at both
ends (their 70 deg per-axis limits combine to 69 deg at most in the test box); the ball joints
of the 3-6 sensor and the guideway model take 45 deg, the tilt that high-angle ball joints sold
for parallel mechanisms reach (standard rod-end and ball-socket joints allow 15-30 deg); the
``spherical`` preset keeps the textbook's ideal ball joint (no cone: its test box needs 68 deg).
Collision bodies take the defaults: 20 mm leg radius, 25 mm joint housings, 20 mm plates;
but the guideway model's neighbouring struts of different pairs cross (the paper's idealised
line struts): its platform joints lie 1 mm outside and inside its platform circle, so that the
crossing axes pass 1.7 mm apart at home (on one circle they would meet there exactly), and its
struts take a 0.1 mm radius: its home pose is free of collision and a strut passing through
another is still caught.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..exceptions import GeometryError
from .geometry import HexapodGeometry, LegGeometry
from .sensors import Inclinometer, MeasuringLeg

DEG = math.pi / 180.0
BASE7 = (0.25, 0.0, 0.0)  # m, base frame: the seventh leg's base anchor (reference7)
PLATFORM7 = (-0.15, 0.0, 0.0)  # m, platform frame: its platform anchor


def _circle(radius: float, angle_deg: float, z: float = 0.0) -> tuple[float, float, float]:
    a = angle_deg * DEG
    return (radius * math.cos(a), radius * math.sin(a), z)


def symmetric_legs(
    base_radius: float,
    platform_radius: float,
    base_spread_deg: float,
    platform_spread_deg: float,
    stroke: tuple[float, float],
) -> tuple[LegGeometry, ...]:
    """Six legs of the classic 6-6 layout with three-fold symmetry.

    Base anchors sit in pairs around 0, 120, 240 deg (``base_spread_deg`` apart), platform
    anchors in pairs around 60, 180, 300 deg; leg ``2k`` and ``2k+1`` leave base pair ``k``
    towards the two neighbouring platform pairs. Radii in metres.
    """
    legs = []
    for k in range(3):
        c = 120.0 * k
        for sign in (-1, 1):
            legs.append(
                LegGeometry(
                    base_anchor=_circle(base_radius, c + sign * base_spread_deg / 2),
                    platform_anchor=_circle(platform_radius, c + sign * (60.0 - platform_spread_deg / 2)),
                    stroke=stroke,
                )
            )
    return tuple(legs)


#: m: the guideway model's strut radius (the paper's struts are lines; see GUIDEWAY_JOINT_SHIFT)
GUIDEWAY_STRUT_RADIUS = 1e-4
#: m: the guideway model's platform joints lie this much outside (legs 2, 4, 6) and inside (legs
#: 1, 3, 5) the platform radius. Each strut crosses one of the neighbouring pair's (legs 1-6,
#: 2-3, 4-5); with the six joints on one circle the two are mirror images about a plane of
#: symmetry, so at home they meet exactly where they cross it, and no strut, however thin,
#: clears the other. With the joints 2 mm apart radially their axes pass 1.7 mm apart at home
GUIDEWAY_JOINT_SHIFT = 1e-3


def reference() -> HexapodGeometry:
    """Offset-axis Cardan joints at both ends plus a cylindrical joint (Bem et al. (2026))."""
    return HexapodGeometry(
        name="reference",
        joint_type="cardan",
        legs=symmetric_legs(0.25, 0.15, 24.0, 24.0, (-0.16, 0.20)),
        home_height=0.40,
        base_offset=0.012,
        platform_offset=0.012,
        cardan_limit=70 * DEG,
        roll_limit=math.pi / 2,
        base_cone=75 * DEG,
        platform_cone=75 * DEG,
        description="Bem et al. (2026) design: offset-axis Cardan joints (12 mm) at both ends, cylindrical joint",
    )


REFERENCE7_LEG = MeasuringLeg(base_anchor=BASE7, platform_anchor=PLATFORM7, stroke=(-0.16, 0.20))


def reference7() -> HexapodGeometry:
    """The reference fixture with a seventh, passive measuring leg (readings ``leg1`` .. ``leg7``).

    The seventh leg's base anchor sits between base pairs, its platform anchor across the
    platform (see :data:`REFERENCE7_LEG`): a diagonal strut whose reading depends on every
    pose coordinate, so that a fault on any of the seven legs moves the one parity residual.
    """
    return replace(
        reference(),
        name="reference7",
        measuring_legs=(REFERENCE7_LEG,),
        description="reference fixture + a seventh, diagonal measuring leg (readings leg1..leg7)",
    )


def reference_tilt() -> HexapodGeometry:
    """The reference fixture with a two-axis platform inclinometer (readings leg1 .. leg6, tilt_x, tilt_y).

    The inclinometer's mounting frame is the platform frame: two redundant angles, enough to
    name a single faulty leg (each leg's fault tilts the platform its own way; docs/redundancy.md).
    """
    return replace(
        reference(),
        name="reference_tilt",
        inclinometer=Inclinometer(),
        description="reference fixture + a 2-axis platform inclinometer (readings leg1..leg6, tilt_x, tilt_y)",
    )


def intersecting() -> HexapodGeometry:
    """The reference geometry with ideal universal joints (zero axis offsets)."""
    return replace(
        reference(),
        name="intersecting",
        base_offset=0.0,
        platform_offset=0.0,
        description="reference geometry with ideal (intersecting-axis) universal joints",
    )


def spherical() -> HexapodGeometry:
    """Ideal universal joint at the base, ball joint at the platform: the textbook model."""
    return replace(
        reference(),
        name="spherical",
        joint_type="spherical",
        base_offset=0.0,
        platform_offset=0.0,
        platform_cone=None,
        description="reference anchors, universal joint at the base, ball joint at the platform",
    )


def three_six() -> HexapodGeometry:
    """The 3-6 sensor.

    Shi, She and Duan's 3-6 sensor: six base points on a regular hexagon, legs meeting in pairs
    at three platform points (ball joints).
    """
    rb, ra = 0.20, 0.12
    legs = []
    for k in range(3):
        top = _circle(ra, 120.0 * k + 30.0)
        for j in (0, 1):
            legs.append(
                LegGeometry(base_anchor=_circle(rb, 120.0 * k + 60.0 * j), platform_anchor=top, stroke=(-0.18, 0.18))
            )
    return HexapodGeometry(
        name="3-6",
        joint_type="spherical",
        legs=tuple(legs),
        home_height=0.22,
        cardan_limit=60 * DEG,
        platform_cone=45 * DEG,
        description="Shi, She and Duan (2016) 3-6 sensor: ball joints, legs meet in pairs at three platform points",
    )


def guideway() -> HexapodGeometry:
    """Jakobović and Jelenković's second model: fixed-length struts whose base ends slide on guideways.

    Three pairs of parallel guideways, ``0.06 m`` apart, inclined like the line from radius
    0.45 m on the floor to radius 0.15 m at 0.25 m height; the slider (the measured joint) is
    on that line's midpoint at home and travels +-0.22 m along the rail; struts go to ball
    joints on a 0.15 m platform, the two of a pair 1 mm outside and inside that radius
    (:data:`GUIDEWAY_JOINT_SHIFT`: crossing struts that clear each other at home).
    """
    r_lo, r_hi, h, d, rp = 0.45, 0.15, 0.25, 0.06, 0.15
    legs = []
    for k in range(3):
        c = 120.0 * k
        radial = np.array(_circle(1.0, c))
        tangent = np.array(_circle(1.0, c + 90.0))
        rail = np.array([-(r_lo - r_hi) * radial[0], -(r_lo - r_hi) * radial[1], h])
        length = float(np.linalg.norm(rail))
        for sign in (-1, 1):
            mid = radial * (r_lo + r_hi) / 2 + sign * d / 2 * tangent + np.array([0, 0, h / 2])
            legs.append(
                LegGeometry(
                    base_anchor=tuple(mid),
                    platform_anchor=_circle(rp + sign * GUIDEWAY_JOINT_SHIFT, c + sign * 75.0),
                    stroke=(-0.22, 0.22),
                    guideway=tuple(rail / length),
                )
            )
    return HexapodGeometry(
        name="guideway",
        joint_type="guideway",
        legs=tuple(legs),
        home_height=0.50,
        cardan_limit=60 * DEG,
        platform_cone=45 * DEG,
        leg_radius=GUIDEWAY_STRUT_RADIUS,
        description="Jakobović and Jelenković's model 2: fixed struts on sliding guideways (slider = measured joint)",
    )


PRESETS: dict[str, Callable[[], HexapodGeometry]] = {
    "reference": reference,
    "intersecting": intersecting,
    "spherical": spherical,
    "3-6": three_six,
    "guideway": guideway,
    "reference7": reference7,
    "reference_tilt": reference_tilt,
}
DEFAULT_PRESET = "reference"


def get_preset(name: str) -> HexapodGeometry:
    """The preset geometry called ``name`` (see ``PRESETS``)."""
    try:
        return PRESETS[name]()
    except KeyError:
        raise GeometryError("preset", name, f"unknown preset; choose one of {sorted(PRESETS)}") from None
