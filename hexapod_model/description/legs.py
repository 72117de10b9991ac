"""Where one leg's joint axes lie at home: the construction the URDF writer and the calibration share.

A Cardan joint with offset axes is two revolute axes a distance ``e`` apart along their common
normal. The geometry file gives, per joint, the *centre* (midpoint of the common normal at
home), the direction of the axis fixed to its plate and the offset ``e``. Its common normal is
perpendicular to that fixed axis and lies in the plane of the fixed axis and the leg, so

* ``n = unit(w - (w . a) a)`` for the leg direction ``w`` and the fixed axis ``a`` (``n = w``
  when ``a`` is perpendicular to the leg, the nominal case);
* the leg line runs from the base joint's second axis, ``b + e_b/2 n_b``, to the platform
  joint's first axis, ``p - e_p/2 n_p``, and ``w`` is its direction: a small fixed point
  (``w`` depends on ``n_b``, ``n_p``), solved by iteration.

Everything here is plain arithmetic (no ``abs``, ``norm`` or ``arctan2`` on the inputs), so it
also runs on complex numbers: the calibration differentiates it by complex steps, which are
exact to rounding (no truncation error, unlike finite differences). Vectors may carry leading
batch axes (one construction per complex step).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geometry import HexapodGeometry

PERPENDICULAR = 1e-12  # |a . w| below which a real axis counts as perpendicular to the leg
MAX_ITERATIONS = 200


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a . b`` over the last axis (no conjugation of complex values)."""
    return np.sum(a * b, axis=-1)


def unit(v: np.ndarray) -> np.ndarray:
    """``v / |v|`` over the last axis (also for complex ``v``: no conjugation)."""
    return v / np.sqrt(dot(v, v))[..., None]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis (real or complex)."""
    a, b = np.broadcast_arrays(a, b)
    return np.stack(
        [a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
         a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]],
        axis=-1,
    )  # fmt: skip


def _columns(*vectors: np.ndarray) -> np.ndarray:
    """Rotation matrices whose columns are ``vectors`` (leading axes kept)."""
    return np.stack(np.broadcast_arrays(*vectors), axis=-1)


def _t(M: np.ndarray) -> np.ndarray:
    return np.swapaxes(M, -1, -2)


def default_axis(d: np.ndarray) -> np.ndarray:
    """The default fixed Cardan axis for centre direction ``d``: horizontal, perpendicular to ``d``."""
    a = np.cross([0.0, 0.0, 1.0], d)
    if np.linalg.norm(a) < 1e-9:
        a = np.array([1.0, 0.0, 0.0])
    a = a - np.dot(a, d) * d
    return a / np.linalg.norm(a)


def common_normal(w: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Unit common normal of a Cardan joint with fixed axis ``a`` on a leg along ``w``."""
    if np.isrealobj(w) and np.isrealobj(a) and w.ndim == a.ndim == 1 and abs(float(w @ a)) <= PERPENDICULAR:
        return w
    return unit(w - dot(w, a)[..., None] * a)


@dataclass(frozen=True)
class LegAxes:
    """One leg at home, in the base frame (the platform frame is only translated at home).

    Attributes:
        w: leg direction (unit).
        base: rotation of the base yoke frame: x the fixed base axis, y the second axis, z
            the common normal ``n_b``.
        start: origin of the first base axis (the foot of its common normal), m.
        roll: rotation of the leg frame (x, y = the second base axis, z = ``w``) relative to
            the base cross frame (identity when the base axis is perpendicular to the leg).
        rest: length from the second base axis to the platform joint's first axis (cardan)
            or to the platform anchor (ball joint) along the leg, m.
        platform: rotation of the platform cross frame: x the fixed platform axis, y the
            rod-side axis, z the common normal ``n_p`` (cardan legs; else ``None``).
        platform_rel: ``platform`` relative to the leg frame (cardan legs; else ``None``).
    """

    w: np.ndarray
    base: np.ndarray
    start: np.ndarray
    roll: np.ndarray
    rest: np.ndarray
    platform: np.ndarray | None
    platform_rel: np.ndarray | None


def leg_axes(
    base_anchor: np.ndarray,
    platform_anchor_home: np.ndarray,
    base_axis: np.ndarray,
    platform_axis: np.ndarray | None,
    base_offset: complex | float,
    platform_offset: complex | float,
) -> LegAxes:
    """Solve the home construction of one leg (see the module doc).

    Args:
        base_anchor: base joint centre ``b`` (base frame, m).
        platform_anchor_home: platform joint centre at home, in the base frame (m).
        base_axis: unit fixed base Cardan axis (base frame).
        platform_axis: unit fixed platform Cardan axis, or ``None`` for a ball joint at the platform.
        base_offset: base axis offset ``e_b`` (m).
        platform_offset: platform axis offset ``e_p`` (m).

    Every argument may carry the same leading batch axes (offsets: those axes only).
    """
    b, p = base_anchor, platform_anchor_home
    eb, ep = np.asarray(base_offset)[..., None], np.asarray(platform_offset)[..., None]
    w = unit(p - b)
    for _ in range(MAX_ITERATIONS):
        d = p - b - eb / 2 * common_normal(w, base_axis)
        if platform_axis is not None:
            d = d - ep / 2 * common_normal(w, platform_axis)
        new = unit(d)
        change = new - w
        w = new
        if np.max(np.abs(change.real)) <= 4e-16 and np.max(np.abs(change.imag)) <= 4e-16 * (
            np.max(np.abs(w.imag)) + 1e-300
        ):
            break
    n_b = common_normal(w, base_axis)
    second = cross(n_b, base_axis)
    base = _columns(base_axis, second, n_b)
    leg = _columns(cross(second, w), second, w)
    s2 = b + eb / 2 * n_b
    if platform_axis is None:
        return LegAxes(w, base, b - eb / 2 * n_b, _t(base) @ leg, dot(p - s2, w), None, None)
    n_p = common_normal(w, platform_axis)
    platform = _columns(platform_axis, cross(n_p, platform_axis), n_p)
    rest = dot(p - ep / 2 * n_p - s2, w)
    return LegAxes(w, base, b - eb / 2 * n_b, _t(base) @ leg, rest, platform, _t(leg) @ platform)


def fixed_axes(geom: HexapodGeometry, i: int) -> tuple[np.ndarray, np.ndarray | None]:
    """Unit fixed Cardan axes of leg ``i``, defaults filled in.

    Base axis in the base frame, platform axis in the platform frame (``None`` for ball
    joints). Defaults: horizontal and perpendicular to the home centre line; the platform axis
    parallel to the base one.
    """
    leg = geom.legs[i]
    a_b = default_axis(geom.home_leg_axis(i)[0]) if leg.base_axis is None else np.asarray(leg.base_axis, float)
    if geom.joint_type != "cardan":
        return a_b, None
    return a_b, a_b.copy() if leg.platform_axis is None else np.asarray(leg.platform_axis, float)


def axes_of(geom: HexapodGeometry, i: int) -> LegAxes:
    """The home construction (:func:`~hexapod_model.description.legs.leg_axes`) of leg ``i``."""
    a_b, a_p = fixed_axes(geom, i)
    eb, ep = geom.offsets(i)
    leg = geom.legs[i]
    p = geom.home_translation + np.asarray(leg.platform_anchor)
    return leg_axes(np.asarray(leg.base_anchor, float), p, a_b, a_p, eb, ep)
