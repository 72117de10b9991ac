"""Lengths implausible for a hexapod's size: most likely a value in the wrong unit.

The package works in metres. A length given in millimetres is 1000 times too large and
still a finite number: a solve then fails with a convergence message, or a sweep rates a
120 m platform. Every length that describes one hexapod - a platform position, an anchor
radius, a stroke, the home height - is within a small multiple of its base radius (the
largest horizontal distance of a base joint from the base origin, ``Hexapod.base_radius``).
One beyond :data:`PLAUSIBLE_RATIO` times it is refused here, in one line that names the
value, the base radius and the unit it suspects.

``hexapod statics``, ``hexapod ik``, :func:`~hexapod_model.analysis.statics.leg_forces`,
:class:`~hexapod_model.description.geometry.HexapodGeometry` and the sweep's candidate
geometries (:mod:`hexapod_model.studies.sweep_spec`) check their lengths here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..exceptions import InputError

#: a length more than this many base radii is refused (the presets' lengths are within 3)
PLAUSIBLE_RATIO = 100.0


def implausible(label: str, value: float, base_radius: float, ratio: float = PLAUSIBLE_RATIO) -> str:
    """Why ``value`` (m) is implausible for a hexapod of ``base_radius`` (m), or ``""`` when it is not.

    Args:
        label: what the value is, as the user named it (``"z"``, ``"base_radius"``).
        value: the length (m); its magnitude is compared.
        base_radius: the hexapod's base radius (m); 0 or not finite: nothing is judged.
        ratio: the largest plausible ``|value| / base_radius``.

    Returns:
        One line such as ``"z = 415 m is 1660x the base radius 0.25 m (at most 100x): is it in mm?"``.
    """
    if not (math.isfinite(base_radius) and base_radius > 0.0 and math.isfinite(value)):
        return ""
    times = abs(value) / base_radius
    if times <= ratio:
        return ""
    unit = "mm" if times > 300.0 else "cm"
    return (
        f"{label} = {value:.6g} m is {times:.0f}x the base radius {base_radius:.6g} m "
        f"(at most {ratio:g}x): is it in {unit}?"
    )


def check_length(name: str, label: str, value: float, base_radius: float) -> float:
    """``value`` (m), or :class:`~hexapod_model.exceptions.InputError` naming ``name`` when :func:`implausible`."""
    why = implausible(label, value, base_radius)
    if why:
        raise InputError(name, value, why)
    return value


def position_problem(xyz: Sequence[float] | np.ndarray, base_radius: float) -> str:
    """The first of ``x, y, z`` (m, base frame) that is :func:`implausible`, as one line; ``""`` when none is."""
    for label, v in zip("xyz", np.asarray(xyz, dtype=float)[:3]):
        why = implausible(label, float(v), base_radius)
        if why:
            return why
    return ""


def check_pose_position(name: str, pose: np.ndarray, base_radius: float) -> np.ndarray:
    """``pose`` (4x4, base frame, m) unless its position is :func:`implausible`: then :class:`InputError`."""
    T = np.asarray(pose, dtype=float)
    if T.shape == (4, 4):
        why = position_problem(T[:3, 3], base_radius)
        if why:
            raise InputError(name, T[:3, 3].tolist(), why)
    return pose
