"""Express a hexapod (geometry and frames) in the calibration's convention for the base and platform frames.

Moving every base-side joint by one rigid motion ``G_b`` (and every platform-side joint by
``G_p``, in the platform frame) changes nothing a measuring device can see, provided the
frames follow (``T_mb -> T_mb G_b^-1``, ``T_pm -> G_p T_pm``) and each encoder zero absorbs the
change of its leg's home length. The calibration fixes this freedom by a convention
(``ParameterSet.gauge_constraints``); :func:`regauge` moves any other description of the same
hexapod to that convention, so that its parameters can be compared one by one (the true
geometry of a simulation, or another calibration).

Extra sensors move with their side: a measuring leg's base anchor with the base, its platform
anchor and the inclinometer's mounting frame with the platform (its encoder zero keeps each
reading's physical length). An inclinometer refers to the base frame's z axis as the vertical:
with its unknowns in the parameter set, the base side may only turn about z (the frame
convention has no rows for the other two rotations, which the readings determine).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin

from ..description.geometry import HexapodGeometry
from ..description.legs import axes_of, fixed_axes, leg_axes
from ..description.sensor_layout import rpy_matrix
from ..description.sensors import Inclinometer
from ..lie import matrix_to_rpy
from .parameters import ParameterSet


def move(geom: HexapodGeometry, G_b: np.ndarray, G_p: np.ndarray) -> HexapodGeometry:
    """``geom`` with its base-side joints moved by ``G_b`` and its platform-side joints by ``G_p``.

    ``G_b`` is a 4x4 in the base frame, ``G_p`` one in the platform frame; encoder zeros keep
    each reading's physical leg length. What moves rigidly are the plate-fixed features: each
    fixed Cardan axis and the foot of its common normal on it. The centres (midpoints of the
    common normals at home) follow from the new home construction, solved by fixed-point
    iteration.
    """
    legs = []
    h = geom.home_translation
    for i, leg in enumerate(geom.legs):
        a_b, a_p = fixed_axes(geom, i)
        assert a_p is not None
        eb, ep = geom.offsets(i)
        old = axes_of(geom, i)
        assert old.platform is not None
        foot_b = G_b[:3, :3] @ old.start + G_b[:3, 3]
        foot_p = G_p[:3, :3] @ (np.asarray(leg.platform_anchor) + ep / 2 * old.platform[:, 2]) + G_p[:3, 3]
        a_b, a_p = G_b[:3, :3] @ a_b, G_p[:3, :3] @ a_p
        b, p = foot_b + eb / 2 * old.base[:, 2], foot_p - ep / 2 * old.platform[:, 2]
        for _ in range(100):
            new = leg_axes(b, h + p, a_b, a_p, eb, ep)
            assert new.platform is not None
            b2, p2 = foot_b + eb / 2 * new.base[:, 2], foot_p - ep / 2 * new.platform[:, 2]
            done = max(np.max(np.abs(b2 - b)), np.max(np.abs(p2 - p))) < 1e-16
            b, p = b2, p2
            if done:
                break
        zero = leg.encoder_zero + (1.0 + leg.encoder_scale) * (float(new.rest) - float(old.rest))
        legs.append(
            replace(
                leg,
                base_anchor=tuple(b),
                platform_anchor=tuple(p),
                base_axis=tuple(a_b),
                platform_axis=tuple(a_p),
                encoder_zero=zero,
            )
        )
    measuring = []
    for m in geom.measuring_legs:
        b, p = np.asarray(m.base_anchor), np.asarray(m.platform_anchor)
        b2, p2 = G_b[:3, :3] @ b + G_b[:3, 3], G_p[:3, :3] @ p + G_p[:3, 3]
        change = float(np.linalg.norm(h + p2 - b2) - np.linalg.norm(h + p - b))
        zero = m.encoder_zero + (1.0 + m.encoder_scale) * change
        measuring.append(replace(m, base_anchor=tuple(b2), platform_anchor=tuple(p2), encoder_zero=zero))
    incl = geom.inclinometer
    if incl is not None:
        roll, pitch, yaw = (float(a) for a in matrix_to_rpy(G_p[:3, :3] @ rpy_matrix(incl.rpy)))
        incl = Inclinometer((roll, pitch, yaw), incl.sigma)
    return replace(geom, legs=tuple(legs), measuring_legs=tuple(measuring), inclinometer=incl)


def regauge(
    ps: ParameterSet, geom: HexapodGeometry, T_mb: np.ndarray, T_pm: np.ndarray
) -> tuple[HexapodGeometry, np.ndarray, np.ndarray]:
    """The same hexapod and frames with ``ps.gauge_constraints() @ ps.delta_of(geometry) = 0``.

    Returns ``(geometry, T_mb, T_pm)``: the moved geometry and the frames that keep every
    measured pose the same (and every extra reading; a levelled base turns about z only).
    """
    C = ps.gauge_constraints()
    free = [k for k in range(12) if not (ps.levelled and k in (3, 4))]  # the base's tilt stays
    x = np.zeros(len(free))

    def transforms(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        full = np.zeros(12)
        full[free] = x
        return pin.exp6(full[:6]).homogeneous, pin.exp6(full[6:]).homogeneous

    def gauge(x: np.ndarray) -> np.ndarray:
        return C @ ps.delta_of(move(geom, *transforms(x)))

    for _ in range(20):
        g = gauge(x)
        if np.max(np.abs(g)) < 1e-14:
            break
        J = np.empty((len(free), len(free)))
        for k in range(len(free)):
            e = np.zeros(len(free))
            e[k] = 1e-7
            J[:, k] = (gauge(x + e) - gauge(x - e)) / 2e-7
        x = x - np.linalg.solve(J, g)
    G_b, G_p = transforms(x)
    return move(geom, G_b, G_p), T_mb @ np.linalg.inv(G_b), G_p @ T_pm
