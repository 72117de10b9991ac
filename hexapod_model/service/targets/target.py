"""Target poses and recipes of a changeover: what each fixture's plate should be set to, validated.

A **target** is a platform pose in the fixture's base frame (x, y, z in m; roll, pitch, yaw in
degrees, ``R = Rz(yaw) Ry(pitch) Rx(roll)``, or a unit quaternion ``qx, qy, qz, qw``) with a
tolerance (``translation_mm``, ``rotation_deg``). A **recipe** names a target for each of several
fixtures: the set-up of one workpiece. The JSON form (HTTP and the store)::

    {"pose": {"x": 0.01, "y": -0.02, "z": 0.41, "roll": 5.0, "pitch": -3.0, "yaw": 10.0},
     "tolerance": {"translation_mm": 0.1, "rotation_deg": 0.05}}
    {"targets": {"left": {...}, "right": {...}}}            # a recipe

Every field is checked (:class:`TargetError` names the field, the value and what is expected, on
one line), and a target is solved by inverse kinematics when it is set: a pose outside the
workspace is refused with the leg (or Cardan joint) and the limit it breaks; a pose the machine's
body refuses (two bodies in collision, a joint beyond its cone, outside the operating envelope:
:mod:`.body_limits`) with the pair, the joint or the axis, and :attr:`TargetError.details`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...exceptions import HexapodError, brief_repr
from ...kinematics.hexapod import Hexapod
from ...lie import matrix_to_quaternion, matrix_to_rpy, quaternion_to_matrix, rpy_to_matrix
from .body_limits import body_refusal, clearance_of, outside_envelope

RPY_KEYS = ("x", "y", "z", "roll", "pitch", "yaw")
QUATERNION_KEYS = ("x", "y", "z", "qx", "qy", "qz", "qw")
MAX_TRANSLATION_MM = 1000.0
MAX_ROTATION_DEG = 180.0


class TargetError(HexapodError, ValueError):
    """A target or recipe field cannot be used.

    Attributes:
        field: dotted name of the field (``"targets.left.pose.z"``).
        value: the value found there (``None`` when missing).
        reason: what is expected.
        details: JSON details of a refusal by the machine's body (``limit`` and its figures,
            :mod:`.body_limits`); empty for the other errors.
    """

    def __init__(self, field: str, value: Any, reason: str, details: dict[str, Any] | None = None):
        self.field, self.value, self.reason = field, value, reason
        self.details: dict[str, Any] = dict(details or {})
        super().__init__(f"field {field!r} = {brief_repr(value, 80)}: {' '.join(str(reason).split())}")


@dataclass(frozen=True)
class Tolerance:
    """How close the plate must be to a target: ``translation`` (m) and ``rotation`` (rad)."""

    translation: float
    rotation: float

    def to_json(self) -> dict[str, float]:
        """``{"translation_mm", "rotation_deg"}``."""
        return {"translation_mm": self.translation * 1e3, "rotation_deg": math.degrees(self.rotation)}


@dataclass(frozen=True)
class Target:
    """The pose one fixture's plate should be set to.

    Attributes:
        fixture: the fixture's name.
        pose: 4x4 platform pose in the fixture's base frame (m).
        tolerance: the allowed deviation.
        readings: (6,) leg readings of the pose by inverse kinematics (m, leg order).
        set_by: who set it.
        set_at: when (s, Unix time).
        recipe: the recipe it came from (``None``: set on its own).
        id: row id once stored.
        clearance: the pose's clearance (:func:`.body_limits.clearance_json`: mm and the pair),
            ``None`` for a model without collision bodies.
    """

    fixture: str
    pose: np.ndarray = field(repr=False)
    tolerance: Tolerance
    readings: np.ndarray = field(repr=False)
    set_by: str
    set_at: float
    recipe: str | None = None
    id: int | None = None
    clearance: dict[str, Any] | None = field(default=None, compare=False)

    def to_json(self, brief: bool = False) -> dict[str, Any]:
        """JSON: ``pose`` (m, deg and quaternion), ``tolerance``, ``recipe``, ``set_by``, ``set_at``, ``id``.

        ``brief``: a PUT body (``pose`` as position and quaternion, ``tolerance``): how the store keeps it.
        """
        if brief:
            pose = {k: v for k, v in self._pose_json.items() if k in QUATERNION_KEYS}
            return {"pose": pose, "tolerance": self.tolerance.to_json()}
        return {
            "pose": dict(self._pose_json),
            "tolerance": self.tolerance.to_json(),
            "recipe": self.recipe,
            "set_by": self.set_by,
            "set_at": self.set_at,
            "id": self.id,
        }

    @functools.cached_property
    def _pose_json(self) -> dict[str, float]:
        """:func:`pose_json` of the pose, made once (the dashboard's stream asks for it four times a second)."""
        return pose_json(self.pose)


@dataclass(frozen=True)
class Recipe:
    """One workpiece's set-up: a target per fixture.

    Attributes:
        name: the recipe's name.
        targets: the targets by fixture name (their ``recipe`` is ``name``).
        set_by: who stored it.
        set_at: when (s, Unix time).
    """

    name: str
    targets: dict[str, Target]
    set_by: str
    set_at: float

    def to_json(self) -> dict[str, Any]:
        """``{"name", "targets": {fixture: target}, "set_by", "set_at"}``."""
        return {
            "name": self.name,
            "targets": {
                k: {"pose": pose_json(t.pose), "tolerance": t.tolerance.to_json()} for k, t in self.targets.items()
            },
            "set_by": self.set_by,
            "set_at": self.set_at,
        }


def pose_json(T: np.ndarray) -> dict[str, float]:
    """``x, y, z`` (m), ``qx, qy, qz, qw`` (``qw >= 0``) and ``roll, pitch, yaw`` (deg) of a 4x4 pose."""
    values = [*T[:3, 3], *matrix_to_quaternion(T[:3, :3]), *np.degrees(matrix_to_rpy(T[:3, :3]))]
    return dict(zip((*QUATERNION_KEYS, "roll", "pitch", "yaw"), map(float, values)))


def _object(data: Any, where: str) -> dict:
    if not isinstance(data, dict):
        raise TargetError(where or "<body>", data, "expected a JSON object")
    return data


def _finish(data: dict, known: tuple[str, ...], where: str) -> None:
    unknown = sorted(set(data) - set(known))
    if unknown:
        raise TargetError(_join(where, unknown[0]), data[unknown[0]], f"unknown field (known here: {', '.join(known)})")


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


def _number(data: dict, key: str, where: str, unit: str, lo: float = -math.inf, hi: float = math.inf) -> float:
    v = data.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not lo <= v <= hi:
        if v is None and key not in data:
            raise TargetError(_join(where, key), None, f"missing (required, {unit})")
        raise TargetError(_join(where, key), v, f"expected a number in [{lo:g}, {hi:g}] {unit}")
    return float(v)


def parse_pose(data: Any, where: str = "pose") -> np.ndarray:
    """A 4x4 pose from ``{"x","y","z"}`` (m) and ``{"roll","pitch","yaw"}`` (deg) or ``{"qx","qy","qz","qw"}``.

    Raises:
        TargetError: a missing, unknown or non-finite field, both or neither rotation form, or a
            quaternion whose norm is not 1 (within 1e-6).
    """
    data = _object(data, where)
    rpy, quat = any(k in data for k in RPY_KEYS[3:]), any(k in data for k in QUATERNION_KEYS[3:])
    if rpy == quat:
        raise TargetError(where, data, "give roll, pitch, yaw (deg) or qx, qy, qz, qw: exactly one of the two")
    keys = RPY_KEYS if rpy else QUATERNION_KEYS
    _finish(data, keys, where)
    T = np.eye(4)
    T[:3, 3] = [_number(data, k, where, "m", -10.0, 10.0) for k in "xyz"]
    if rpy:
        T[:3, :3] = rpy_to_matrix(*np.radians([_number(data, k, where, "deg", -360.0, 360.0) for k in RPY_KEYS[3:]]))
    else:
        q = np.array([_number(data, k, where, "", -1.0, 1.0) for k in QUATERNION_KEYS[3:]])
        if abs(np.linalg.norm(q) - 1.0) > 1e-6:
            raise TargetError(f"{where}.qw", q.tolist(), f"the quaternion's norm is {np.linalg.norm(q):.9g}, not 1")
        T[:3, :3] = quaternion_to_matrix(q)
    return T


def parse_tolerance(data: Any, where: str = "tolerance") -> Tolerance:
    """``{"translation_mm": > 0, "rotation_deg": > 0}`` as a :class:`Tolerance` (m, rad)."""
    data = _object(data, where)
    _finish(data, ("translation_mm", "rotation_deg"), where)
    mm = _number(data, "translation_mm", where, "mm", 0.0, MAX_TRANSLATION_MM)
    deg = _number(data, "rotation_deg", where, "deg", 0.0, MAX_ROTATION_DEG)
    for key, v in (("translation_mm", mm), ("rotation_deg", deg)):
        if v <= 0.0:
            raise TargetError(_join(where, key), v, "must be above 0")
    return Tolerance(mm * 1e-3, math.radians(deg))


def reachable(hexa: Hexapod, pose: np.ndarray, where: str, fixture: str) -> tuple[np.ndarray, dict[str, Any] | None]:
    """The leg readings (m) of ``pose`` by inverse kinematics and its clearance (:func:`.body_limits.clearance_of`).

    Raises:
        TargetError: ``pose`` outside the workspace (the leg or joint and the limit), or refused by
            the machine's body: in collision, beyond a joint cone or outside the operating
            envelope (:mod:`.body_limits`; the figures in :attr:`TargetError.details`).
    """
    try:
        sol = hexa.inverse(pose)
    except HexapodError as exc:
        result = getattr(exc, "result", None)
        refusal = None if result is None else body_refusal(hexa, result)
        if refusal is not None:
            reason = f"fixture {fixture!r} {refusal.reason}"
            raise TargetError(where, pose_json(pose), reason, refusal.details) from None
        message = str(exc).split(": ", 1)[-1] if str(exc).startswith("out_of_limits") else str(exc)
        raise TargetError(where, pose_json(pose), f"outside the workspace of fixture {fixture!r}: {message}") from None
    refusal = body_refusal(hexa, sol) or outside_envelope(hexa, pose)
    if refusal is not None:
        raise TargetError(where, pose_json(pose), f"fixture {fixture!r} {refusal.reason}", refusal.details)
    return np.array(sol.lengths, dtype=float), clearance_of(hexa, sol.q)


def target_from_json(
    data: Any,
    fixture: str,
    hexa: Hexapod,
    set_by: str,
    set_at: float,
    recipe: str | None = None,
    where: str = "",
) -> Target:
    """Validate a target's JSON (``{"pose": ..., "tolerance": ...}``) and solve its inverse kinematics."""
    data = _object(data, where)
    _finish(data, ("pose", "tolerance"), where)
    if "pose" not in data:
        raise TargetError(_join(where, "pose"), None, "missing (required)")
    if "tolerance" not in data:
        raise TargetError(_join(where, "tolerance"), None, "missing (required: translation_mm, rotation_deg)")
    pose = parse_pose(data["pose"], _join(where, "pose"))
    tolerance = parse_tolerance(data["tolerance"], _join(where, "tolerance"))
    readings, clearance = reachable(hexa, pose, _join(where, "pose"), fixture)
    return Target(fixture, pose, tolerance, readings, set_by, set_at, recipe, clearance=clearance)


def recipe_from_json(data: Any, name: str, hexapods: dict[str, Hexapod], set_by: str, set_at: float) -> Recipe:
    """Validate a recipe's JSON (``{"targets": {fixture: target}}``) against the service's fixtures."""
    data = _object(data, "")
    _finish(data, ("targets",), "")
    targets = data.get("targets")
    if not isinstance(targets, dict) or not targets:
        raise TargetError("targets", targets, "expected an object naming one or more fixtures")
    out = {}
    for fixture, body in targets.items():
        if fixture not in hexapods:
            raise TargetError(f"targets.{fixture}", None, f"no such fixture (fixtures: {', '.join(hexapods)})")
        out[fixture] = target_from_json(body, fixture, hexapods[fixture], set_by, set_at, name, f"targets.{fixture}")
    return Recipe(name, out, set_by, set_at)
