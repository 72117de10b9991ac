"""Extra sensors in a calibration: their unknowns, reading model and derivatives, frame convention."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.calibration.derivatives import CalibrationModel
from hexapod_model.calibration.frames import Noise
from hexapod_model.calibration.gauge import move
from hexapod_model.calibration.identifiability import free_basis
from hexapod_model.calibration.parameters import ParameterSet
from hexapod_model.calibration.problem import MeasuredPoses, Problem, sensor_whitening
from hexapod_model.calibration.sensors import SensorModel
from hexapod_model.description.geometry_toml import save_geometry

PRESETS = ("reference7", "reference_tilt")


@pytest.fixture(scope="module", params=PRESETS)
def corrected(request):
    """A parameter set with the sensors' unknowns (and scales) and a geometry off nominal in all of them."""
    ps = ParameterSet(hm.get_preset(request.param), encoder_scale=True, sensors=True)
    delta = np.random.default_rng(2).uniform(-1, 1, ps.size) * ps.scales
    return ps, delta


def _model(ps: ParameterSet, delta: np.ndarray) -> SensorModel:
    return SensorModel(ps.geometry(delta), hm.Hexapod.from_geometry(ps.nominal).home_pose, ps.mount(delta))


def _poses(ps: ParameterSet) -> np.ndarray:
    return box_poses(hm.Hexapod.from_geometry(ps.nominal).home_pose, 4, seed=7)


def test_the_unknowns_follow_the_six_legs_and_round_trip(corrected):
    ps, delta = corrected
    six = ParameterSet(ps.nominal, encoder_scale=True)
    assert ps.names[: six.size] == six.names and ps.size > six.size
    extra = [ps.names[k] for k in ps.sensor_index]
    if ps.nominal.inclinometer is not None:
        assert extra == ["inclinometer.mount.x_rad", "inclinometer.mount.y_rad", "inclinometer.mount.z_rad"]
        assert ps.gauge_constraints().shape == (10, ps.size)  # the base's tilt is seen by the inclinometer
    else:
        assert extra[0] == "leg7.base_anchor.x_m" and "leg7.encoder_zero_m" in extra and "leg7.encoder_scale" in extra
        assert ps.gauge_constraints().shape == (12, ps.size)
    np.testing.assert_allclose(ps.delta_of(ps.geometry(delta)), delta, rtol=0, atol=1e-15)
    assert six.geometry(delta[: six.size]).measuring_legs == ps.nominal.measuring_legs  # without: kept nominal


def test_the_sensor_model_reads_as_the_least_squares_solve_does(corrected):
    """Its readings are those Hexapod.forward compares with, for the corrected geometry."""
    ps, delta = corrected
    hexa = hm.Hexapod.from_geometry(ps.geometry(delta))
    assert hexa.redundancy is not None
    P = _poses(ps)
    expected = np.array([hexa.redundancy.extra_readings(T) for T in P])
    np.testing.assert_allclose(_model(ps, delta).readings(P), expected, rtol=0, atol=1e-13)


def test_sensor_derivatives_match_finite_differences(corrected):
    ps, delta = corrected
    P = _poses(ps)
    model = _model(ps, delta)
    pose, own = model.derivatives(P)
    h = 1e-7
    for i in range(6):
        e = np.zeros(6)
        e[i] = h
        plus = model.readings(P @ pin.exp6(e).homogeneous)
        minus = model.readings(P @ pin.exp6(-e).homogeneous)
        np.testing.assert_allclose(pose[:, :, i], (plus - minus) / (2 * h), rtol=0, atol=1e-7)
    for k, col in zip(ps.sensor_index, ps.sensor_columns):
        e = np.zeros(ps.size)
        e[k] = h
        fd = (_model(ps, delta + e).readings(P) - _model(ps, delta - e).readings(P)) / (2 * h)
        np.testing.assert_allclose(own[:, :, col], fd, rtol=0, atol=1e-7, err_msg=ps.names[k])


def test_the_frame_convention_moves_the_sensors_without_changing_a_reading(corrected):
    """A base motion about z and any platform motion, with the poses following: the same extra readings."""
    ps, delta = corrected
    geom = ps.geometry(delta)
    G_b = pin.exp6(np.array([1e-3, -2e-3, 5e-4, 0.0, 0.0, 4e-3])).homogeneous  # about z: the base stays levelled
    G_p = pin.exp6(np.array([-1e-3, 1e-3, 2e-3, 3e-3, -2e-3, 1e-3])).homogeneous
    moved = move(geom, G_b, G_p)
    home = hm.Hexapod.from_geometry(ps.nominal).home_pose
    P = _poses(ps)
    before = SensorModel(geom, home).readings(P)
    after = SensorModel(moved, home).readings(G_b @ P @ np.linalg.inv(G_p))
    np.testing.assert_allclose(after, before, rtol=0, atol=1e-12)


def test_a_calibrated_geometry_with_sensors_is_written_and_read_back_exactly(corrected, tmp_path):
    """The geometry file carries the identified sensors (the TOML writer failed on sensor tables)."""
    ps, delta = corrected
    geom = ps.geometry(delta, name="calibrated")
    back = hm.load_geometry(save_geometry(geom, tmp_path / "g.toml"))
    assert back.measuring_legs == geom.measuring_legs and back.inclinometer == geom.inclinometer
    np.testing.assert_allclose(ps.delta_of(back), ps.delta_of(geom), rtol=0, atol=1e-15)


@pytest.mark.parametrize("name", PRESETS)
def test_the_problem_jacobian_with_extra_rows_matches_finite_differences(name):
    """The extra readings' rows: through the pose, the sensors' own columns, zero frame columns, the whitening."""
    ps = ParameterSet(hm.get_preset(name), sensors=True)
    nominal = CalibrationModel(ps, np.zeros(ps.size))
    true = hm.Hexapod.from_geometry(ps.nominal)
    poses = box_poses(true.home_pose, 6, seed=2)
    assert true.redundancy is not None
    readings = np.array([[*true.inverse(T).lengths, *true.redundancy.extra_readings(T)] for T in poses])
    data = MeasuredPoses(readings, poses)
    P, qs, Gs, ok = nominal.forward(readings)
    assert ok.all()
    whitening = sensor_whitening(nominal, P, qs, Gs)
    basis = free_basis(ps.gauge_constraints() * ps.scales, (), ps.size)
    problem = Problem(ps, data, Noise(), basis, (np.eye(4), np.eye(4)), None, whitening)
    x = np.concatenate([np.random.default_rng(3).normal(0, 0.5, basis.shape[1]), np.zeros(12)])
    J = problem.jac(x)
    assert J.shape == (6 * 6 + 6 * whitening.shape[1], basis.shape[1] + 12)
    extra = slice(36, None)
    np.testing.assert_array_equal(J[extra, basis.shape[1] :], 0.0)  # the frames do not move a reading
    for k in [0, 7, basis.shape[1] - 1]:
        e = np.zeros_like(x)
        e[k] = 1e-4
        fd = (problem.fun(x + e) - problem.fun(x - e)) / 2e-4
        scale = np.max(np.abs(fd[extra])) + 1.0
        np.testing.assert_allclose(J[extra, k] / scale, fd[extra] / scale, rtol=0, atol=2e-3)
