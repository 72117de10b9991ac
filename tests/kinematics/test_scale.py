"""A hexapod scaled by 0.05 (a 1 cm base radius) or by 10 (2 m) gets the same answers, to scale."""

from __future__ import annotations

import functools

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.geometry import geometry_from_dict
from hexapod_model.kinematics.rotations import pose_distance

from ..conftest import hexapod


def scaled(geometry: hm.HexapodGeometry, factor: float) -> hm.HexapodGeometry:
    """``geometry`` with every length multiplied by ``factor`` (angles unchanged)."""
    d = geometry.to_dict()
    for key in ("home_height", "base_offset", "platform_offset"):
        d[key] *= factor
    for leg in d["legs"]:
        for key in ("base_anchor", "platform_anchor", "stroke"):
            leg[key] = [v * factor for v in leg[key]]
        for key in ("base_offset", "platform_offset", "encoder_zero"):
            if key in leg:
                leg[key] *= factor
    d["name"] = f"{geometry.name}_scaled"
    return geometry_from_dict(d)


@functools.cache
def scaled_hexapod(name: str, factor: float) -> hm.Hexapod:
    return hm.Hexapod.from_geometry(scaled(hm.get_preset(name), factor))


@pytest.mark.parametrize("factor", [0.05, 10.0])
@pytest.mark.parametrize("name", ["reference", "3-6", "spherical"])
def test_scaled_geometries_give_the_same_statuses_and_poses_to_scale(name, factor):
    unit, big = hexapod(name), scaled_hexapod(name, factor)
    rng = np.random.default_rng(3)
    for T in box_poses(unit.home_pose, 40, seed=11, translation=0.1, angle_deg=40):
        S = T.copy()
        S[:3, 3] *= factor
        a, b = unit.inverse(T, check=False), big.inverse(S, check=False)
        assert a.status == b.status
        if not a.converged:
            continue
        np.testing.assert_allclose(b.lengths, a.lengths * factor, rtol=0, atol=1e-11 * factor)
        for guess_a, guess_b in ((None, None), (a, b)):  # cold, and warm 10 um (x factor) away
            step = rng.normal(scale=1e-5, size=6) if guess_a is not None else np.zeros(6)
            la = np.clip(a.lengths + step, *unit.stroke.T)
            fa = unit.forward(la, guess_a, check=False)
            fb = big.forward(la * factor, guess_b, check=False)
            assert fa.status == fb.status and len(fa.candidates) == len(fb.candidates)
            if fa.closed:
                Pb = fb.pose.copy()
                Pb[:3, 3] /= factor
                assert pose_distance(Pb, fa.pose, 0.2) < 1e-10
    readings = rng.uniform(unit.stroke[:, 0], unit.stroke[:, 1], size=(10, 6))  # mostly no assembly
    fa, fb = unit.forward_batch(readings), big.forward_batch(readings * factor)
    assert list(fa.status) == list(fb.status)
