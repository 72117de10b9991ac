"""The calibration's unknowns and its frame convention: names, round trips, gauge constraints, bad input."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.calibration.gauge import move, regauge
from hexapod_model.calibration.parameters import KINDS, SCALES, ParameterSet


@pytest.fixture(scope="module", params=[False, True], ids=["no_scale", "encoder_scale"])
def parameters(request):
    return ParameterSet(hm.get_preset("reference"), encoder_scale=request.param)


def test_every_leg_has_its_named_parameters_with_the_kinds_scale(parameters):
    per_leg = 13 + (parameters.size == 6 * 14)
    assert parameters.size == 6 * per_leg == len(set(parameters.names))
    for p, name, scale in zip(parameters.parameters, parameters.names, parameters.scales):
        assert name.startswith(f"leg{p.leg + 1}.{p.kind}") and p.kind in KINDS
        assert scale == SCALES[p.kind] == p.scale
        assert parameters.index(name) == parameters.names.index(name)
    for i, slots in enumerate(parameters.legs):
        assert len(slots) == per_leg and all(parameters.parameters[k].leg == i for k in slots)


def test_geometry_and_delta_of_are_inverse(parameters):
    """Corrections of a few tolerances in every parameter come back from the geometry they make."""
    delta = np.random.default_rng(7).uniform(-3, 3, parameters.size) * parameters.scales
    geom = parameters.geometry(delta, name="corrected")
    assert geom.name == "corrected"
    np.testing.assert_allclose(parameters.delta_of(geom), delta, rtol=0, atol=1e-14)
    np.testing.assert_allclose(parameters.delta_of(parameters.nominal), 0.0, atol=1e-15)
    np.testing.assert_allclose(parameters.values(delta) - parameters.nominal_values(), delta, atol=1e-15)


def test_an_axis_correction_tilts_its_axis_by_that_angle(parameters):
    """``tilt`` and ``turn`` are tangents of the angle between the corrected and the nominal axis."""
    for name in ("leg2.base_axis.tilt_rad", "leg5.platform_axis.turn_rad"):
        delta = np.zeros(parameters.size)
        delta[parameters.index(name)] = angle = np.radians(0.5)
        side = 0 if ".base_axis" in name else 1
        leg = int(name[3]) - 1
        before = np.asarray(parameters.axes[leg][side])
        after = parameters.leg_arrays(leg, parameters.leg_vector(leg, delta))["a_b" if side == 0 else "a_p"]
        assert np.arctan(angle) == pytest.approx(np.arccos(np.clip(before @ after, -1, 1)), abs=1e-12)


def test_the_gauge_constraints_see_exactly_the_rigid_motions_of_each_plate(parameters):
    C = parameters.gauge_constraints()
    assert C.shape == (12, parameters.size) and np.linalg.matrix_rank(C) == 12
    for side, (kind, points) in enumerate(
        (("base_centre", parameters.nominal.base_points()), ("platform_centre", parameters.nominal.platform_points()))
    ):
        centred = points - points.mean(axis=0)
        motions = []
        for j in range(6):  # an infinitesimal translation or rotation (about the centroid) of every centre
            twist = np.eye(6)[j]
            d = np.zeros(parameters.size)
            for k, p in enumerate(parameters.parameters):
                if p.kind == kind:
                    d[k] = (twist[:3] + np.cross(twist[3:], centred[p.leg]))[p.index]
            motions.append(d)
        seen = C @ np.array(motions).T  # (12, 6)
        assert np.linalg.matrix_rank(seen[6 * side : 6 * side + 6]) == 6
        assert np.all(seen[6 * (1 - side) : 6 * (1 - side) + 6] == 0.0)
    others = [k for k, p in enumerate(parameters.parameters) if "centre" not in p.kind]
    assert np.all(C[:, others] == 0.0)  # axes, offsets and encoder parameters are not frames


def test_moving_by_identities_and_regauging_the_nominal_change_nothing(parameters):
    nominal = parameters.nominal
    same = move(nominal, np.eye(4), np.eye(4))
    np.testing.assert_allclose(same.base_points(), nominal.base_points(), atol=1e-14)
    np.testing.assert_allclose(same.platform_points(), nominal.platform_points(), atol=1e-14)
    np.testing.assert_allclose([leg.encoder_zero for leg in same.legs], [leg.encoder_zero for leg in nominal.legs])
    T_mb, T_pm = np.diag([1.0, 1.0, 1.0, 1.0]), np.eye(4)
    T_mb[:3, 3] = [0.1, -0.2, 0.3]
    geom, A, B = regauge(parameters, nominal, T_mb, T_pm)
    np.testing.assert_allclose(parameters.delta_of(geom), 0.0, atol=1e-14)
    np.testing.assert_allclose(A, T_mb, atol=1e-14)
    np.testing.assert_allclose(B, T_pm, atol=1e-14)


def test_bad_input_is_named():
    with pytest.raises(hm.GeometryError, match=r"joint_type.*spherical.*cardan"):
        ParameterSet(hm.get_preset("spherical"))
    with pytest.raises(hm.GeometryError, match=r"leg7\.encoder_zero_m.*unknown.*leg1\."):
        ParameterSet(hm.get_preset("reference")).index("leg7.encoder_zero_m")
