"""Identification: recovery of known errors, identifiability, frames, gauge, validation, planning, bad input."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.calibration.derivatives import CalibrationModel
from hexapod_model.calibration.frames import Noise, fit_frames, initial_frames, pose_errors, predict
from hexapod_model.calibration.gauge import move, regauge
from hexapod_model.calibration.identify import MeasuredPoses, identify
from hexapod_model.calibration.parameters import ParameterSet
from hexapod_model.calibration.planning import plan_poses
from hexapod_model.calibration.validation import cross_validate, folds_of
from hexapod_model.description.geometry_toml import save_geometry
from hexapod_model.description.model import ClosedLoopModel
from hexapod_model.description.urdf_geometry import geometry_of_urdf
from hexapod_model.studies.calibrate import Errors, simulate

FINE = Noise(2e-6, 2e-5)  # a nearly exact measuring device: 2 um, 1 mdeg


@pytest.fixture(scope="module")
def small():
    """40 poses of a true hexapod off nominal, measured almost exactly through unknown frames."""
    return simulate(hm.get_preset("reference"), 40, seed=5, encoder_noise=1e-7, noise=FINE)


@pytest.fixture(scope="module")
def identified(small):
    return identify(small.nominal, small.data, FINE)


def test_known_errors_are_recovered(small, identified):
    ps = identified.parameters
    geom, T_mb, T_pm = regauge(ps, small.true_geometry, small.measuring_frame, small.marker_frame)
    truth = ps.delta_of(geom)
    ok = identified.identifiable
    assert ok.sum() >= 40  # with 2 um data most parameters are determined
    z = (identified.delta[ok] - truth[ok]) / identified.sigma[ok]
    assert np.all(np.abs(z) < 3.0), np.array(ps.names)[ok][np.abs(z) >= 3]
    # the encoder zeros (+-1 mm errors) are found to 0.2 mm where identified; the rest of their
    # error comes from the held parameters (known to their tolerance only), which sigma includes
    zeros = [k for k, n in enumerate(ps.names) if n.endswith("encoder_zero_m") and ok[k]]
    assert zeros and np.max(np.abs(identified.delta[zeros] - truth[zeros])) < 2e-4
    for found, true, sigma in (
        (identified.measuring_frame, T_mb, identified.frame_sigma[:6]),
        (identified.marker_frame, T_pm, identified.frame_sigma[6:]),
    ):
        error = pin.log6(pin.SE3(found).inverse() * pin.SE3(true)).vector
        assert np.all(np.abs(error) < 3 * sigma + 1e-9), (error, sigma)
    M, ok_rows = identified.predict(small.data.readings)
    assert ok_rows.all()
    before = pose_errors(predict(*initial_frames(small.true_poses, small.data.measured)[:1], small.true_poses,
                                 np.eye(4)), small.data.measured)  # fmt: skip
    after = pose_errors(M, small.data.measured)
    assert np.mean(after[0]) < 0.01 < np.mean(before[0])  # mm: down to the 2 um noise


def test_held_parameters_are_never_reported_as_identified(identified):
    held = ~identified.identifiable
    assert held.any() and np.all(np.isnan(identified.sigma[held])) and np.all(identified.delta[held] == 0)
    named = {c.held for c in identified.combinations}
    assert named == {identified.parameters.names[k] for k in np.flatnonzero(held)}


def test_intersecting_axes_make_the_axis_directions_unidentifiable():
    """With zero offsets a Cardan joint's axis directions do not change its kinematics: named and held."""
    sim = simulate(hm.get_preset("intersecting"), 40, seed=2, errors=Errors(offset_m=0.0), noise=FINE)
    result = identify(sim.nominal, sim.data, FINE)
    axes = [k for k, n in enumerate(result.parameters.names) if "_axis." in n]
    assert not result.identifiable[axes].any()
    unseen = [c for c in result.combinations if not np.isfinite(c.sigma)]
    assert {c.held for c in unseen} >= {result.parameters.names[k] for k in axes}
    assert all("not seen by the data" in c.describe() and "held at nominal" in c.describe() for c in unseen)


def test_calibrated_geometry_round_trips_through_file_and_urdf(small, identified, tmp_path):
    geom = identified.geometry
    path = save_geometry(geom, tmp_path / "calibrated.toml")
    urdf = hm.write_urdf(hm.load_geometry(path), tmp_path / "calibrated.urdf")
    from_file = hm.Hexapod.from_urdf(urdf)
    model = CalibrationModel(identified.parameters, identified.delta)
    for r in small.data.readings[:8]:
        np.testing.assert_allclose(from_file.forward(r).pose, model.hexapod.forward(r).pose, atol=1e-9)
    back = geometry_of_urdf(ClosedLoopModel.from_file(urdf))  # and the geometry read back off the URDF
    np.testing.assert_allclose(back.base_points(), geom.base_points(), atol=1e-9)
    np.testing.assert_allclose([leg.encoder_zero for leg in back.legs], [leg.encoder_zero for leg in geom.legs])


def test_moving_either_plate_side_changes_nothing_measurable(small):
    G_b = pin.exp6(np.array([2e-3, -1e-3, 1e-3, 3e-3, -2e-3, 1e-3])).homogeneous
    G_p = pin.exp6(np.array([-1e-3, 2e-3, 1e-3, -1e-3, 2e-3, 2e-3])).homogeneous
    a, b = hm.Hexapod.from_geometry(small.true_geometry), hm.Hexapod.from_geometry(move(small.true_geometry, G_b, G_p))
    for r in small.data.readings[:5]:
        np.testing.assert_allclose(G_b @ a.forward(r).pose @ np.linalg.inv(G_p), b.forward(r).pose, atol=1e-11)
    ps = ParameterSet(small.nominal)
    geom, _, _ = regauge(ps, small.true_geometry, small.measuring_frame, small.marker_frame)
    assert np.max(np.abs(ps.gauge_constraints() @ ps.delta_of(geom))) < 1e-12


def test_frames_are_found_from_exact_poses():
    P = box_poses(np.eye(4), 20, seed=3)
    rng = np.random.default_rng(4)
    T_mb, T_pm = pin.exp6(rng.normal(0, 0.6, 6)).homogeneous, pin.exp6(rng.normal(0, 0.3, 6)).homogeneous
    A, B = fit_frames(P, predict(T_mb, P, T_pm), Noise())
    np.testing.assert_allclose(A, T_mb, atol=1e-12)
    np.testing.assert_allclose(B, T_pm, atol=1e-12)


def test_cross_validation_predicts_every_pose_once(small):
    fold = folds_of(40, 4, seed=1)
    assert sorted(np.bincount(fold).tolist()) == [10, 10, 10, 10]
    val = cross_validate(small.nominal, small.data, FINE, folds=2, seed=1, hold=("*_axis.*",))  # 54 unknowns
    assert val.after[0].shape == (40,) and np.all(np.isfinite(val.after[0]))
    assert np.mean(val.after[0]) < 0.2 * np.mean(val.before[0])


def test_planned_poses_condition_the_identification_better_than_random():
    plan = plan_poses(hm.get_preset("reference"), 27, candidates=150, seed=1)
    hexa = hm.Hexapod.from_preset("reference")
    for T, r in zip(plan.poses, plan.readings):
        np.testing.assert_allclose(hexa.forward(r).pose, T, atol=1e-9)  # reachable, readings consistent
    assert np.sum(np.log(plan.singular_values)) > np.sum(np.log(plan.singular_values_random))


def test_too_few_poses_and_unknown_hold_patterns(small):
    with pytest.raises(hm.InputError, match=r"need at least 26 measured poses"):
        identify(small.nominal, small.data.subset(np.arange(20)), FINE)
    with pytest.raises(hm.InputError, match="matches no parameter"):
        identify(small.nominal, small.data, FINE, hold=("leg9.*",))


def test_a_row_outside_the_workspace_is_named(small):
    readings = small.data.readings.copy()
    readings[7, 2] = 0.5  # far beyond the stroke
    data = dataclasses.replace(small.data, readings=readings, lines=tuple(range(2, 42)))
    with pytest.raises(hm.InputError, match=r"line 9.*no pose of the nominal hexapod"):
        identify(small.nominal, data, FINE)


def test_an_outlier_row_is_named_with_its_residual(small):
    measured = small.data.measured.copy()
    measured[12, :3, 3] += [0.004, 0.0, 0.0]  # 4 mm off
    with pytest.raises(hm.InputError, match=r"row 13.*outlier.*\d mm"):
        identify(small.nominal, dataclasses.replace(small.data, measured=measured), FINE)


def test_data_no_geometry_near_nominal_explains(small):
    measured = small.data.measured.copy()
    measured[:, :3, 3] *= 1.3  # positions from another scale: not a rigid motion of the model's poses
    with pytest.raises(hm.InputError, match="no geometry near nominal explains"):
        identify(small.nominal, MeasuredPoses(small.data.readings, measured, "scaled.csv"), FINE)


def test_a_hexapod_with_a_measuring_leg_is_identified_from_its_six_legs():
    """reference7 rows with six readings: the six legs' fit of today, leg7 carried nominal."""
    sim = simulate(hm.get_preset("reference7"), 30, seed=5, encoder_noise=1e-7, noise=FINE)
    assert sim.data.readings.shape[1] == 7
    six = sim.data.six()
    found = identify(sim.nominal, six, FINE)
    plain = identify(hm.get_preset("reference"), six, FINE)
    assert not found.sensors and found.sensor_rms is None
    assert found.geometry.measuring_legs == sim.nominal.measuring_legs
    np.testing.assert_allclose(found.delta, plain.delta, rtol=0, atol=1e-12)
