"""Guidance to a target: how far the plate is from it and what to change on each leg.

* **Deviation**: the current pose relative to the target, ``E = T_target^-1 T_current``: its
  translation (mm) along the target frame's axes and its rotation vector (deg, target frame),
  with the overall lengths ``translation_mm`` and ``rotation_deg``.
* **Legs**: per leg the reading (m -> mm), the target reading (the target's inverse kinematics)
  and the change to make, ``target - reading`` (positive: extend). For a small pose error the
  changes are the leg Jacobian times the error (``docs/changeover.md``).
* **in_tolerance**: only for an ``ok`` pose with a ``sigma``, judged conservatively: the deviation
  plus :data:`MARGIN_SIGMAS` times the pose's 1-sigma uncertainty is within the tolerance, for
  translation and rotation alike. A flagged or failed record is never in tolerance.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin

from ..record.pose_record import PoseRecord
from .target import Target, Tolerance

MARGIN_SIGMAS = 2.0  # the deviation plus this many sigma must fit the tolerance


def deviation(current: np.ndarray, target: np.ndarray) -> dict[str, float]:
    """``current`` relative to ``target`` (4x4 each, same frame), in the target's frame: mm and deg."""
    Rt = target[:3, :3].T  # E = T_target^-1 T_current of rigid transforms
    d = Rt @ (current[:3, 3] - target[:3, 3]) * 1e3
    w = np.degrees(pin.log3(Rt @ current[:3, :3]))
    return {
        "translation_mm": float(np.linalg.norm(d)),
        "rotation_deg": float(np.linalg.norm(w)),
        "x_mm": float(d[0]),
        "y_mm": float(d[1]),
        "z_mm": float(d[2]),
        "rx_deg": float(w[0]),
        "ry_deg": float(w[1]),
        "rz_deg": float(w[2]),
    }


def within(dev: dict[str, float], sigma: dict[str, float] | None, tolerance: Tolerance) -> bool:
    """True when the deviation plus ``MARGIN_SIGMAS`` sigma fits the tolerance (False without a sigma)."""
    if sigma is None:
        return False
    t = dev["translation_mm"] + MARGIN_SIGMAS * sigma["translation_mm"]
    r = dev["rotation_deg"] + MARGIN_SIGMAS * sigma["rotation_deg"]
    return t <= tolerance.translation * 1e3 and r <= math.degrees(tolerance.rotation)


def legs(readings: list[float | None], target: Target) -> list[dict[str, Any]]:
    """Per leg ``{"leg", "reading_mm", "target_mm", "change_mm"}`` (``None`` where no reading is fresh)."""
    out = []
    for k, (r, g) in enumerate(zip(readings, target.readings.tolist())):
        out.append(
            {
                "leg": k + 1,
                "reading_mm": None if r is None else r * 1e3,
                "target_mm": g * 1e3,
                "change_mm": None if r is None else (g - r) * 1e3,
            }
        )
    return out


def guidance(
    rec: PoseRecord,
    target: Target | None,
    extra: dict[str, Any] | None = None,
    clearance: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The guidance of one fixture from its latest record and its target (``None``: no target set).

    Keys: ``fixture``, ``t``, ``status``, ``state``, ``stored``, ``flags``, ``pose``, ``sigma``,
    ``pose_in_robot`` (the record's), ``target`` (as stored, or ``None``), ``deviation`` (``None`` without a pose or a
    target), ``legs`` (``[]`` without a target), ``in_tolerance``, ``clearance`` (the record's pose) and
    ``target_clearance`` (the target's): ``{"distance_mm", "pair", "min_clearance_mm", "collision"}``
    (:func:`.body_limits.clearance_json`) or ``None``; ``extra`` is merged in.

    Args:
        rec: the fixture's latest record.
        target: its target, or ``None``.
        extra: keys to add.
        clearance: the clearance of the record's pose (``None``: no pose, or no collision bodies).
    """
    out: dict[str, Any] = {
        "fixture": rec.fixture,
        "t": rec.t,
        "status": rec.status,
        "state": rec.state,
        "stored": rec.stored,
        "flags": rec.flags,
        "pose": rec.pose,
        "sigma": rec.sigma,
        "pose_in_robot": rec.pose_in_robot,
    }
    out.update({"target": None, "deviation": None, "legs": [], "in_tolerance": False})
    out.update({"clearance": clearance, "target_clearance": None})
    if target is not None:
        out["target"] = target.to_json()
        out["target_clearance"] = target.clearance
        out["legs"] = legs(rec.readings if len(rec.readings) == 6 else [None] * 6, target)
        if rec.transform is not None:
            dev = deviation(rec.transform, target.pose)
            out["deviation"] = dev
            out["in_tolerance"] = rec.status == "ok" and within(dev, rec.sigma, target.tolerance)
    if extra:
        out.update(extra)
    return out
