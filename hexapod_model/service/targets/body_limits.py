"""A target against the machine's body: collisions, joint cones, the operating envelope; clearance as JSON.

A target the inverse kinematics solves within the stroke and joint limits may still be one the
machine cannot take (:mod:`hexapod_model.kinematics.body_check`):

* ``collision``: two collision bodies closer than the geometry's ``min_clearance``
  (:meth:`hexapod_model.kinematics.hexapod.Hexapod.clearance`); the refusal names the pair, the
  clearance (mm, negative: the bodies overlap by that much) and ``min_clearance`` (mm);
* ``cone_limit``: a ball or Cardan joint deflected beyond its cone
  (:func:`hexapod_model.kinematics.cones.check_cones`); the refusal names the joint, its angle and
  the cone's half-angle (deg);
* ``envelope``: the pose outside the geometry's operating envelope (a box about home,
  ``HexapodGeometry.envelope``); the refusal names the axis farthest outside, its offset from
  home and the half-width (mm or deg).

Each refusal is a :class:`Refusal`: one line of text and the JSON details the service's ``422``
body carries beside ``error`` and ``field`` (``docs/changeover.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...exceptions import HexapodError
from ...kinematics.body_check import BodyCheck
from ...kinematics.clearance import Clearance
from ...kinematics.cones import ENDS, check_cones
from ...kinematics.hexapod import Hexapod
from ...kinematics.newton.solver import Solution

#: the envelope's axes, their unit in messages and the factor from SI (m, rad) to it
AXES = (("x", "mm", 1e3), ("y", "mm", 1e3), ("z", "mm", 1e3)) + tuple(
    (name, "deg", math.degrees(1.0)) for name in ("roll", "pitch", "yaw")
)


@dataclass(frozen=True)
class Refusal:
    """Why the machine's body refuses a target.

    Attributes:
        reason: one line naming the limit and the values (mm, deg).
        details: JSON details: ``limit`` (``collision``, ``cone_limit``, ``envelope``) and its figures.
    """

    reason: str
    details: dict[str, Any]


def clearance_json(c: Clearance) -> dict[str, Any]:
    """``{"distance_mm", "pair", "min_clearance_mm", "collision"}`` of a clearance (mm; negative: overlap)."""
    return {
        "distance_mm": c.distance * 1e3,
        "pair": list(c.pair),
        "min_clearance_mm": c.min_clearance * 1e3,
        "collision": c.collision,
    }


def clearance_of(hexa: Hexapod, q: np.ndarray | None) -> dict[str, Any] | None:
    """:func:`clearance_json` of configuration ``q``; ``None`` without one or for a model without collision bodies."""
    if q is None:
        return None
    try:
        return clearance_json(hexa.clearance(q))
    except HexapodError:  # a URDF written without <collision> elements: nothing to measure
        return None


def collision(hexa: Hexapod, sol: Solution) -> Refusal:
    """The refusal of a solve in ``collision``: the pair, the clearance and ``min_clearance`` (mm)."""
    c = hexa.clearance(sol.q)
    details = {
        "limit": "collision",
        "pair": list(c.pair),
        "clearance_mm": c.distance * 1e3,
        "min_clearance_mm": c.min_clearance * 1e3,
    }
    return Refusal(
        f"in collision: {c.pair[0]} - {c.pair[1]} at {c.distance * 1e3:.3f} mm "
        f"(min_clearance {c.min_clearance * 1e3:.3f} mm)",
        details,
    )


def cone_limit(hexa: Hexapod, sol: Solution) -> Refusal:
    """The refusal of a solve at ``cone_limit``: the joint farthest beyond its cone, its angle and the limit (deg)."""
    cones = check_cones(hexa.closed_loop, hexa.geometry, sol.q)
    leg, end, _ = cones.worst()
    angle = math.degrees(float(cones.angles[leg, ENDS.index(end)]))
    limit = math.degrees(float(cones.limits[leg, ENDS.index(end)]))
    joint = f"leg{leg + 1} {end}"
    return Refusal(
        f"beyond a joint cone: {joint} joint deflected {angle:.3f} deg, cone half-angle {limit:.3f} deg",
        {"limit": "cone_limit", "joint": joint, "angle_deg": angle, "cone_deg": limit},
    )


def body_refusal(hexa: Hexapod, sol: Solution) -> Refusal | None:
    """The refusal of an inverse solve the body check refused (status ``collision`` or ``cone_limit``), else None.

    A ``converged`` solve of a hexapod whose solves skip the body check (``check_body = False``)
    is checked here, cones first as the solver does: a target is never set unchecked.
    """
    status = sol.status
    if status == "converged" and not hexa.check_body:
        clear = clearance_of(hexa, sol.q)
        if not check_cones(hexa.closed_loop, hexa.geometry, sol.q).within:
            status = "cone_limit"
        elif clear is not None and clear["collision"]:
            status = "collision"
    if status == "collision":
        return collision(hexa, sol)
    if status == "cone_limit":
        return cone_limit(hexa, sol)
    return None


def outside_envelope(hexa: Hexapod, pose: np.ndarray) -> Refusal | None:
    """The refusal of ``pose`` (4x4, base frame, m) outside the geometry's operating envelope; None inside or without.

    The axis named is the one farthest outside, relative to its half-width.
    """
    envelope = None if hexa.geometry is None else hexa.geometry.envelope
    if envelope is None:
        return None
    body = hexa.engine.body or BodyCheck(hexa.closed_loop, hexa.geometry, hexa.compiled)
    if body.within_envelope(pose):
        return None
    offset = body.offset(pose)
    k = int(np.argmax(np.abs(offset) / np.asarray(envelope)))
    name, unit, factor = AXES[k]
    value, half = float(offset[k]) * factor, float(envelope[k]) * factor
    return Refusal(
        f"outside the operating envelope: {name} {value:+.3f} {unit} from home, half-width {half:.3f} {unit}",
        {"limit": "envelope", "axis": name, "offset": value, "half_width": half, "unit": unit},
    )
