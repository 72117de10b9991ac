"""The extra sensors of a calibration: their unknowns, their readings and the readings' derivatives.

A geometry with measuring legs or an inclinometer (:mod:`hexapod_model.description.sensors`)
is calibrated with its extra readings as equations when the measured rows carry them. Its
extra unknowns (SI; base frame for base-side values, platform frame for platform-side ones):

* per measuring leg ``legK`` (K = 7, 8, ...): ``legK.base_anchor.{x,y,z}_m``,
  ``legK.platform_anchor.{x,y,z}_m``, ``legK.encoder_zero_m`` and, with the six legs',
  ``legK.encoder_scale``, as in :class:`~hexapod_model.description.sensors.MeasuringLeg`;
* the inclinometer's mounting rotation ``inclinometer.mount.{x,y,z}_rad``: the mounting frame
  is ``R_S0 exp(delta)`` for its nominal ``R_S0`` (the rotation vector ``delta`` in the
  sensor frame S). The reading model has no separate zero offsets: an offset on ``tilt_x``
  is the mounting rotation about ``y_S`` (exactly so while the platform tilts about one
  axis), on ``tilt_y`` the one about ``x_S``; the rotation carries them.

The readings are those of :meth:`hexapod_model.kinematics.redundant.RedundantSensing.extra_readings`:
a measuring leg reads ``zero + (1 + scale) (|t + R p - b| - |t_h + R_h p - b|)`` for the
platform pose ``(R, t)`` and home ``(R_h, t_h)``; the inclinometer ``asin`` of the base z
axis' components along the sensor's x and y axes. Their derivatives are in closed form: with
respect to the platform pose (its body twist ``[v; w]``, m and rad) and to the sensors'
unknowns.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pinocchio as pin

from ..description.geometry import HexapodGeometry
from ..description.sensor_layout import rpy_matrix
from ..description.sensors import Inclinometer, MeasuringLeg
from ..lie import matrix_to_rpy

#: expected magnitude of each kind of extra-sensor unknown (SI)
SENSOR_SCALES = {
    "measuring_base": 0.5e-3,
    "measuring_platform": 0.5e-3,
    "measuring_zero": 1e-3,
    "measuring_scale": 1e-3,
    "mount": math.radians(0.3),
}
SENSOR_KINDS = tuple(SENSOR_SCALES)
INCLINOMETER = -1  # the ``leg`` of the inclinometer's unknowns
_XYZ = ("x", "y", "z")


def sensor_unknowns(geom: HexapodGeometry, encoder_scale: bool) -> list[tuple[str, int, str, int, float]]:
    """``(name, leg, kind, index, scale)`` of every extra-sensor unknown of ``geom`` (module doc).

    ``leg`` is 6, 7, ... for the measuring legs, :data:`INCLINOMETER` for the inclinometer.
    """
    out = []
    for k in range(len(geom.measuring_legs)):
        leg, name = 6 + k, f"leg{7 + k}"
        for kind, field in (("measuring_base", "base_anchor"), ("measuring_platform", "platform_anchor")):
            out += [(f"{name}.{field}.{c}_m", leg, kind, i, SENSOR_SCALES[kind]) for i, c in enumerate(_XYZ)]
        out.append((f"{name}.encoder_zero_m", leg, "measuring_zero", 0, SENSOR_SCALES["measuring_zero"]))
        if encoder_scale:
            out.append((f"{name}.encoder_scale", leg, "measuring_scale", 0, SENSOR_SCALES["measuring_scale"]))
    if geom.inclinometer is not None:
        out += [
            (f"inclinometer.mount.{c}_rad", INCLINOMETER, "mount", i, SENSOR_SCALES["mount"])
            for i, c in enumerate(_XYZ)
        ]
    return out


def derivative_column(leg: int, kind: str, index: int, measuring_legs: int) -> int:
    """Column of an unknown in :meth:`SensorModel.derivatives` (8 per measuring leg, then the mount's 3)."""
    if leg == INCLINOMETER:
        return 8 * measuring_legs + index
    return 8 * (leg - 6) + {"measuring_base": 0, "measuring_platform": 3, "measuring_zero": 6}.get(kind, 7) + index


def sensor_value(geom: HexapodGeometry, leg: int, kind: str, index: int) -> float:
    """The value (SI) of a measuring-leg unknown in ``geom`` (not for the mounting rotation)."""
    m = geom.measuring_legs[leg - 6]
    if kind == "measuring_base":
        return float(m.base_anchor[index])
    if kind == "measuring_platform":
        return float(m.platform_anchor[index])
    return float(m.encoder_zero if kind == "measuring_zero" else m.encoder_scale)


def mount_of(nominal: HexapodGeometry, geom: HexapodGeometry) -> np.ndarray:
    """(3,) the mounting rotation correction (rad, sensor frame) from ``nominal``'s inclinometer to ``geom``'s."""
    assert nominal.inclinometer is not None and geom.inclinometer is not None
    R0, R = rpy_matrix(nominal.inclinometer.rpy), rpy_matrix(geom.inclinometer.rpy)
    return np.asarray(pin.log3(R0.T @ R))


def with_sensors(
    geom: HexapodGeometry, nominal: HexapodGeometry, unknowns: list[tuple[int, str, int]], values: np.ndarray
) -> HexapodGeometry:
    """``geom`` with its extra sensors set from ``values`` of the unknowns ``(leg, kind, index)``.

    Measuring-leg unknowns are values (SI), the mounting rotation a correction of ``nominal``'s.
    """
    k = len(nominal.measuring_legs)
    b = np.array([m.base_anchor for m in nominal.measuring_legs], dtype=float).reshape(k, 3)
    p = np.array([m.platform_anchor for m in nominal.measuring_legs], dtype=float).reshape(k, 3)
    zero = [m.encoder_zero for m in nominal.measuring_legs]
    scale = [m.encoder_scale for m in nominal.measuring_legs]
    mount = np.zeros(3)
    for (leg, kind, index), v in zip(unknowns, values):
        if kind == "mount":
            mount[index] = v
        elif kind == "measuring_base":
            b[leg - 6, index] = v
        elif kind == "measuring_platform":
            p[leg - 6, index] = v
        elif kind == "measuring_zero":
            zero[leg - 6] = float(v)
        else:
            scale[leg - 6] = float(v)
    measuring = tuple(
        replace(m, base_anchor=_vec(b[j]), platform_anchor=_vec(p[j]), encoder_zero=zero[j], encoder_scale=scale[j])
        for j, m in enumerate(nominal.measuring_legs)
    )
    incl = nominal.inclinometer
    if incl is not None:
        incl = Inclinometer(_vec(matrix_to_rpy(rpy_matrix(incl.rpy) @ pin.exp3(mount))), incl.sigma)
    return replace(geom, measuring_legs=measuring, inclinometer=incl)


def _vec(v: np.ndarray) -> tuple[float, float, float]:
    return float(v[0]), float(v[1]), float(v[2])


def reading_sigmas(geom: HexapodGeometry) -> np.ndarray:
    """(m,) stated standard deviation of each extra reading (m for legs, rad for tilts), reading order."""
    legs = [geom.encoder_sigma] * len(geom.measuring_legs)
    tilts = [geom.inclinometer.sigma] * 2 if geom.inclinometer is not None else []
    return np.array(legs + tilts, dtype=float)


class SensorModel:
    """The extra readings of a geometry's sensors and their derivatives (module doc).

    Args:
        geom: the (corrected) geometry with its sensors.
        home: 4x4 home pose of the platform (base frame, m).
        mount: the mounting rotation correction the geometry's inclinometer carries (rad,
            sensor frame; its derivative is taken there).
    """

    def __init__(self, geom: HexapodGeometry, home: np.ndarray, mount: np.ndarray | None = None):
        ms: tuple[MeasuringLeg, ...] = geom.measuring_legs
        self.b = np.array([m.base_anchor for m in ms], dtype=float).reshape(-1, 3)
        self.p = np.array([m.platform_anchor for m in ms], dtype=float).reshape(-1, 3)
        self.zero = np.array([m.encoder_zero for m in ms], dtype=float)
        self.gain = 1.0 + np.array([m.encoder_scale for m in ms], dtype=float)
        d_home = home[:3, 3] + self.p @ home[:3, :3].T - self.b
        self.home_lengths = np.linalg.norm(d_home, axis=1)
        self.home_units = d_home / self.home_lengths[:, None]
        self.R_home = home[:3, :3]
        self.R_S = None if geom.inclinometer is None else rpy_matrix(geom.inclinometer.rpy)
        self.J_mount = pin.Jexp3(np.zeros(3) if mount is None else np.asarray(mount, dtype=float))
        self.m = len(ms) + (2 if self.R_S is not None else 0)

    def readings(self, P: np.ndarray) -> np.ndarray:
        """(N, m) extra readings at platform poses ``P`` (N, 4, 4), reading order."""
        R, t = P[:, :3, :3], P[:, :3, 3]
        d = t[:, None, :] + np.einsum("nij,kj->nki", R, self.p) - self.b
        out = self.zero + self.gain * (np.linalg.norm(d, axis=2) - self.home_lengths)
        if self.R_S is not None:
            s = (R @ self.R_S)[:, 2, :2]
            out = np.concatenate([out, np.arcsin(np.clip(s, -1.0, 1.0))], axis=1)
        return out

    def derivatives(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Derivatives of :meth:`readings` at ``P``.

        Returns ``(pose, sensors)``: (N, m, 6) per platform body twist ``[v; w]`` and
        (N, m, u) per extra-sensor unknown, in the order of :func:`sensor_unknowns` (with the
        encoder scale columns whether or not they are unknowns; the caller picks).
        """
        n, k = len(P), len(self.b)
        R, t = P[:, :3, :3], P[:, :3, 3]
        d = t[:, None, :] + np.einsum("nij,kj->nki", R, self.p) - self.b
        L = np.linalg.norm(d, axis=2)
        u_p = np.einsum("nji,nkj->nki", R, d / L[..., None])  # unit leg direction in the platform frame
        pose = np.zeros((n, self.m, 6))
        pose[:, :k, :3] = self.gain[:, None] * u_p
        pose[:, :k, 3:] = self.gain[:, None] * np.cross(self.p, u_p)
        sensors = np.zeros((n, self.m, 8 * k + (3 if self.R_S is not None else 0)))
        for j in range(k):
            c = 8 * j  # base xyz, platform xyz, zero, scale
            sensors[:, j, c : c + 3] = self.gain[j] * (self.home_units[j] - d[:, j] / L[:, j, None])
            sensors[:, j, c + 3 : c + 6] = self.gain[j] * (u_p[:, j] - self.R_home.T @ self.home_units[j])
            sensors[:, j, c + 6] = 1.0
            sensors[:, j, c + 7] = L[:, j] - self.home_lengths[j]
        if self.R_S is not None:
            g = R[:, 2, :]  # the base z axis in the platform frame, (N, 3)
            g_s = g @ self.R_S  # ... in the sensor frame
            s = g_s[:, :2]
            cos = np.sqrt(np.clip(1.0 - s**2, 1e-300, None))
            for j in range(2):
                a = self.R_S[:, j]
                pose[:, k + j, 3:] = np.cross(a, g) / cos[:, j, None]
                e = np.eye(3)[j]
                sensors[:, k + j, 8 * k :] = (np.cross(e, g_s) / cos[:, j, None]) @ self.J_mount
        return pose, sensors
