"""The unknowns of a calibration: per-leg joint parameters as corrections to a nominal geometry.

A :class:`ParameterSet` lists, for each of the six legs of a ``cardan`` hexapod (SI units,
base frame for base-side values, platform frame for platform-side ones):

* ``legK.base_centre.{x,y,z}_m`` / ``legK.platform_centre.{x,y,z}_m``: the Cardan centres;
* ``legK.base_axis.{tilt,turn}_rad`` / ``legK.platform_axis.{tilt,turn}_rad``: the fixed
  Cardan axis is ``unit(a0 + tilt * u + turn * v)`` for its nominal direction ``a0``, ``u``
  the unit component of the nominal home leg direction ``w0`` perpendicular to ``a0`` and
  ``v = unit(w0 x a0)``: ``tilt`` leans the axis towards the leg, ``turn`` turns it about the
  leg (tangents of the angles: equal to the angles to 1e-4 relative below 1 deg);
* ``legK.base_offset_m`` / ``legK.platform_offset_m``: the axis offsets;
* ``legK.encoder_zero_m``: the reading at home; optionally ``legK.encoder_scale``.

With ``sensors``, a geometry's measuring legs and inclinometer add their unknowns after the
six legs' (:mod:`~hexapod_model.calibration.sensors`).

The vector of a calibration is the *correction* ``delta`` (nominal = zeros). ``scale`` gives
each parameter's expected magnitude (the study's tolerances), used to make the identification
Jacobian dimensionless.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..description.geometry import HexapodGeometry
from ..description.legs import fixed_axes, unit
from ..exceptions import GeometryError
from .sensors import derivative_column, mount_of, sensor_unknowns, sensor_value, with_sensors

#: expected magnitude of each kind of parameter (SI): the tolerances of the simulated study
SCALES = {  # in the order of a leg's slots
    "base_centre": 0.5e-3,
    "base_axis": math.radians(0.3),
    "base_offset": 0.5e-3,
    "platform_centre": 0.5e-3,
    "platform_axis": math.radians(0.3),
    "platform_offset": 0.5e-3,
    "encoder_zero": 1e-3,
    "encoder_scale": 1e-3,
}
KINDS = tuple(SCALES)
_COMPONENTS = {
    "base_centre": ("x_m", "y_m", "z_m"),
    "platform_centre": ("x_m", "y_m", "z_m"),
    "base_axis": ("tilt_rad", "turn_rad"),
    "platform_axis": ("tilt_rad", "turn_rad"),
}
LEG_SIZE = 14  # per-leg slots in the order of KINDS (encoder_scale last)


@dataclass(frozen=True)
class Parameter:
    """One unknown: leg ``leg`` (0..5; 6, ... a measuring leg; -1 the inclinometer), ``kind``, component ``index``.

    ``kind``: one of :data:`KINDS`, or of :data:`~hexapod_model.calibration.sensors.SENSOR_KINDS`.
    """

    name: str
    leg: int
    kind: str
    index: int
    scale: float


def _raw(geom: HexapodGeometry, p: Parameter) -> float:
    """The value (SI) of a non-axis parameter ``p`` in ``geom``."""
    if p.leg >= 6:
        return sensor_value(geom, p.leg, p.kind, p.index)
    leg = geom.legs[p.leg]
    if p.kind in ("base_centre", "platform_centre"):
        return float((leg.base_anchor if p.kind == "base_centre" else leg.platform_anchor)[p.index])
    if p.kind in ("base_offset", "platform_offset"):
        return geom.offsets(p.leg)[p.kind == "platform_offset"]
    return float(getattr(leg, p.kind))


def _tangents(w0: np.ndarray, a0: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Unit directions perpendicular to the axis ``a0``: towards the leg ``w0``, and about it."""
    assert a0 is not None
    lean = w0 - (w0 @ a0) * a0
    turn = np.cross(w0, a0)
    return lean / np.linalg.norm(lean), turn / np.linalg.norm(turn)


def _leg_parameters(leg: int, scale: bool) -> list[Parameter]:
    out = []
    for kind in KINDS:
        if kind == "encoder_scale" and not scale:
            continue
        comps = _COMPONENTS.get(kind)
        if comps is None:
            suffix = "" if kind == "encoder_scale" else "_m"
            out.append(Parameter(f"leg{leg + 1}.{kind}{suffix}", leg, kind, 0, SCALES[kind]))
        else:
            out += [Parameter(f"leg{leg + 1}.{kind}.{c}", leg, kind, k, SCALES[kind]) for k, c in enumerate(comps)]
    return out


class ParameterSet:
    """The per-leg unknowns of a nominal ``cardan`` geometry (see the module doc).

    Args:
        nominal: the geometry to correct.
        encoder_scale: also identify each reading's scale error.
        sensors: also the extra sensors' unknowns (measuring legs, an inclinometer), after the
            six legs'; without, the sensors stay as ``nominal`` has them.

    Raises:
        GeometryError: the geometry is not a ``cardan`` hexapod.
    """

    def __init__(self, nominal: HexapodGeometry, encoder_scale: bool = False, sensors: bool = False):
        if nominal.joint_type != "cardan":
            raise GeometryError(
                "joint_type", nominal.joint_type, "calibration identifies cardan hexapods (offset Cardan joints)"
            )
        self.nominal = nominal
        six = [p for i in range(6) for p in _leg_parameters(i, encoder_scale)]
        extra = [Parameter(*u) for u in sensor_unknowns(nominal, encoder_scale)] if sensors else []
        self.parameters = tuple(six + extra)
        #: positions of the extra sensors' unknowns in the vector (empty without ``sensors``)
        self.sensor_index = np.arange(len(six), len(six) + len(extra))
        #: their columns in :meth:`SensorModel.derivatives <hexapod_model.calibration.sensors.SensorModel.derivatives>`
        self.sensor_columns = np.array(
            [derivative_column(p.leg, p.kind, p.index, len(nominal.measuring_legs)) for p in extra], dtype=int
        )
        self.levelled = sensors and nominal.inclinometer is not None
        self.names = tuple(p.name for p in self.parameters)
        self.scales = np.array([p.scale for p in self.parameters])
        self.size = len(self.parameters)
        self.legs = tuple(np.array([k for k, p in enumerate(self.parameters) if p.leg == i]) for i in range(6))
        self.axes = tuple(fixed_axes(nominal, i) for i in range(6))
        #: per leg, per fixed axis (base, platform): the unit directions of ``tilt`` and ``turn``
        self.tangents = tuple(tuple(_tangents(nominal.home_leg_axis(i)[0], a) for a in self.axes[i]) for i in range(6))

    def index(self, name: str) -> int:
        """Position of parameter ``name`` in the vector."""
        try:
            return self.names.index(name)
        except ValueError:
            raise GeometryError("parameter", name, f"unknown; e.g. {self.names[0]!r}, {self.names[-1]!r}") from None

    def nominal_values(self) -> np.ndarray:
        """The nominal value of every parameter (SI; axis angles 0)."""
        return self.values(np.zeros(self.size))

    def values(self, delta: np.ndarray) -> np.ndarray:
        """Parameter values (SI) for the corrections ``delta``: nominal + delta (axis and mount angles: delta)."""
        out = np.array(delta, dtype=float)
        for k, p in enumerate(self.parameters):
            if p.kind not in ("base_axis", "platform_axis", "mount"):
                out[k] += _raw(self.nominal, p)
        return out

    def mount(self, delta: np.ndarray) -> np.ndarray:
        """(3,) the inclinometer's mounting rotation correction in ``delta`` (rad; zeros without it)."""
        out = np.zeros(3)
        for k in self.sensor_index:
            p = self.parameters[k]
            if p.kind == "mount":
                out[p.index] = delta[k]
        return out

    def leg_vector(self, i: int, delta: np.ndarray) -> np.ndarray:
        """The (14,) slots of leg ``i`` (order of :data:`KINDS`, encoder_scale last) filled from ``delta``."""
        v = np.zeros(LEG_SIZE, dtype=np.result_type(delta, float))
        v[: len(self.legs[i])] = delta[self.legs[i]]
        return v

    def leg_arrays(self, i: int, v: np.ndarray) -> dict:
        """Leg ``i``'s joint description for its correction slots ``v`` (..., 14).

        Real or complex, leading batch axes kept: centres ``b``, ``p`` (m), unit fixed axes
        ``a_b``, ``a_p``, offsets ``e_b``, ``e_p`` (m), ``zero`` (m), ``scale``.
        """
        leg = self.nominal.legs[i]
        eb, ep = self.nominal.offsets(i)
        a_b0, a_p0 = self.axes[i]
        (tb, nb), (tp, np_) = self.tangents[i]
        v = np.asarray(v)
        s = v[..., None]
        return {
            "b": np.asarray(leg.base_anchor) + v[..., 0:3],
            "a_b": unit(a_b0 + s[..., 3, :] * tb + s[..., 4, :] * nb),
            "e_b": eb + v[..., 5],
            "p": np.asarray(leg.platform_anchor) + v[..., 6:9],
            "a_p": unit(a_p0 + s[..., 9, :] * tp + s[..., 10, :] * np_),
            "e_p": ep + v[..., 11],
            "zero": leg.encoder_zero + v[..., 12],
            "scale": leg.encoder_scale + v[..., 13],
        }

    def geometry(self, delta: np.ndarray, name: str | None = None) -> HexapodGeometry:
        """The nominal geometry corrected by ``delta`` (every per-leg value written out)."""
        delta = np.asarray(delta, dtype=float)
        legs = []
        for i, leg in enumerate(self.nominal.legs):
            a = self.leg_arrays(i, self.leg_vector(i, delta))
            legs.append(
                replace(
                    leg,
                    base_anchor=tuple(a["b"]),
                    platform_anchor=tuple(a["p"]),
                    base_axis=tuple(a["a_b"]),
                    platform_axis=tuple(a["a_p"]),
                    base_offset=float(a["e_b"]),
                    platform_offset=float(a["e_p"]),
                    encoder_zero=float(a["zero"]),
                    encoder_scale=float(a["scale"]),
                )
            )
        geom = replace(self.nominal, name=name or self.nominal.name, legs=tuple(legs))
        if not self.sensor_index.size:
            return geom
        extra = [self.parameters[k] for k in self.sensor_index]
        values = self.values(delta)[self.sensor_index]
        return with_sensors(geom, self.nominal, [(p.leg, p.kind, p.index) for p in extra], values)

    def delta_of(self, geom: HexapodGeometry) -> np.ndarray:
        """The corrections that turn the nominal geometry into ``geom`` (its inverse of :meth:`geometry`)."""
        out = np.zeros(self.size)
        for k, p in enumerate(self.parameters):
            if p.kind == "mount":
                out[k] = mount_of(self.nominal, geom)[p.index]
            elif p.kind in ("base_axis", "platform_axis"):
                side = 0 if p.kind == "base_axis" else 1
                a = np.asarray(fixed_axes(geom, p.leg)[side])
                a0 = self.axes[p.leg][side]
                out[k] = float(a @ self.tangents[p.leg][side][p.index]) / float(a @ a0)
            else:
                out[k] = _raw(geom, p)
        return out - self.nominal_values()

    def gauge_constraints(self) -> np.ndarray:
        """(12, size) linear constraints ``C @ delta = 0`` that fix the base and platform frames.

        A rigid motion of all base-side joints is indistinguishable from another measuring
        frame, and one of all platform-side joints from another marker frame. The calibrated
        frames are fixed by convention: the centre corrections have no mean translation and no
        mean rotation about the centres' centroid (rows 0-5 base, 6-11 platform).

        With an inclinometer among the unknowns the base frame's z axis is the vertical its
        readings refer to: a rotation of the base side about x or y changes them, the data
        determine it, and rows 3-4 are dropped ((10, size)).
        """
        C = np.zeros((12, self.size))
        for side, (kind, points) in enumerate(
            (("base_centre", self.nominal.base_points()), ("platform_centre", self.nominal.platform_points()))
        ):
            centred = points - points.mean(axis=0)
            for k, p in enumerate(self.parameters):
                if p.kind != kind:
                    continue
                e = np.zeros(3)
                e[p.index] = 1.0
                C[6 * side : 6 * side + 3, k] = e
                C[6 * side + 3 : 6 * side + 6, k] = np.cross(centred[p.leg], e)
        return np.delete(C, [3, 4], axis=0) if self.levelled else C
