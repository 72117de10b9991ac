"""Checked values of a geometry description: vectors of 3 numbers and bounded numbers.

Each check raises one :class:`~hexapod_model.exceptions.GeometryError` line naming the field,
the value and the rule it breaks; the geometry and sensor dataclasses call them in
``__post_init__``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..exceptions import GeometryError

Vec3 = tuple[float, float, float]


def vec3(name: str, value: Any, *, unit: bool = False) -> Vec3:
    """``value`` as 3 finite floats; normalised to a unit vector when ``unit``.

    Raises:
        GeometryError: not 3 numbers, not finite, or a zero direction.
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise GeometryError(name, value, "expected 3 numbers") from None
    if arr.shape != (3,):
        raise GeometryError(name, value, "expected 3 numbers")
    if not np.all(np.isfinite(arr)):
        raise GeometryError(name, value, "must be finite")
    if unit:
        norm = float(np.linalg.norm(arr))
        if norm < 1e-9:
            raise GeometryError(name, value, "direction must not be zero")
        arr = arr / norm
    return (float(arr[0]), float(arr[1]), float(arr[2]))


def number(name: str, value: Any, lo: float, hi: float, *, open_lo: bool = False) -> float:
    """``value`` as a float in ``[lo, hi]`` (``(lo, hi]`` when ``open_lo``).

    Raises:
        GeometryError: not a number (a bool is not), not finite, or outside the interval.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise GeometryError(name, value, "expected a number")
    v = float(value)
    if not math.isfinite(v) or v < lo or v > hi or (open_lo and v == lo):
        bracket = "(" if open_lo else "["
        raise GeometryError(name, value, f"must lie in {bracket}{lo:g}, {hi:g}]")
    return v


def stroke(name: str, value: Any) -> tuple[float, float]:
    """``value`` as a reading interval ``(min, max)`` in metres with ``min < 0 < max`` (0 = home).

    Raises:
        GeometryError: not two finite numbers around 0.
    """
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise GeometryError(name, value, "expected [min, max] in metres") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < 0.0 < hi):
        raise GeometryError(name, value, "need finite min < 0 < max (0 = home reading)")
    return lo, hi
