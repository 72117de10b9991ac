"""Calibration derivatives against finite differences: placements, solved poses, frames, the whole problem."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.calibration.derivatives import CalibrationModel, site_derivatives, site_placements
from hexapod_model.calibration.frames import Noise, predict, residual, twist_jacobian
from hexapod_model.calibration.identifiability import free_basis
from hexapod_model.calibration.parameters import ParameterSet
from hexapod_model.calibration.problem import MeasuredPoses, Problem


@pytest.fixture(scope="module")
def parameters():
    return ParameterSet(hm.get_preset("reference"), encoder_scale=True)


@pytest.fixture(scope="module")
def delta(parameters):
    """A geometry off nominal in every parameter (tilted axes, per-leg offsets, encoder model)."""
    return np.random.default_rng(0).uniform(-1, 1, parameters.size) * parameters.scales


def _body_twist(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    return pin.log6(pin.SE3(P).inverse() * pin.SE3(Q)).vector


def test_placement_twists_match_finite_differences(parameters, delta):
    for i in (0, 3):
        v = parameters.leg_vector(i, delta)
        X = site_derivatives(parameters, i, v)
        R0, t0 = site_placements(parameters, i, v)
        for k in range(14):
            h = 1e-7  # m or rad (tangent of an axis angle)
            e = np.zeros(14)
            e[k] = h
            (Rp, tp), (Rm, tm) = site_placements(parameters, i, v + e), site_placements(parameters, i, v - e)
            dt, dR = (tp - tm) / (2 * h), (Rp - Rm) / (2 * h)
            fd_v = np.einsum("sji,sj->si", R0, dt)
            W = np.einsum("sji,sjk->sik", R0, dR)
            fd_w = np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], axis=1)
            np.testing.assert_allclose(X[:, :3, k], fd_v, atol=1e-7)
            np.testing.assert_allclose(X[:, 3:, k], fd_w, atol=1e-7)


@pytest.mark.parametrize("readings_at", [0, 1])
def test_pose_jacobian_matches_finite_differences(parameters, delta, readings_at):
    model = CalibrationModel(parameters, delta)
    hexa = model.hexapod
    T = box_poses(hexa.home_pose, 2, seed=4)[readings_at]
    readings = hexa.inverse(T).lengths[None]
    P, qs, Gs, ok = model.forward(readings)
    assert ok.all()
    J = model.pose_jacobian(qs[0], Gs[0])

    def pose(d):
        return CalibrationModel(parameters, d).forward(readings)[0][0]

    directions = [np.eye(parameters.size)[k] for k in parameters.legs[readings_at]]  # every column of one leg
    rng = np.random.default_rng(readings_at)
    directions += [rng.normal(size=parameters.size) for _ in range(3)]  # all columns at once
    for u in directions:
        step = 2e-3 * u * parameters.scales  # 1 um on a centre, 0.6 mdeg on an axis
        fd = (_body_twist(P[0], pose(delta + step)) - _body_twist(P[0], pose(delta - step))) / 2.0
        np.testing.assert_allclose(J @ step, fd, rtol=1e-5, atol=1e-11)


def test_measurement_twist_jacobian_matches_finite_differences():
    rng = np.random.default_rng(1)
    A = np.array([pin.exp6(rng.normal(0, 0.4, 6)).homogeneous for _ in range(4)])
    B = np.array([pin.exp6(rng.normal(0, 0.4, 6)).homogeneous for _ in range(4)])
    measured = A @ np.array([pin.exp6(rng.normal(0, 0.02, 6)).homogeneous for _ in range(4)]) @ B
    noise = Noise()
    J = twist_jacobian(A, B, measured, noise)
    for k in range(6):
        e = np.zeros(6)
        e[k] = 1e-7
        plus, minus = pin.exp6(e).homogeneous, pin.exp6(-e).homogeneous
        fd = (residual(A @ plus @ B, measured, noise) - residual(A @ minus @ B, measured, noise)) / 2e-7
        np.testing.assert_allclose(J[:, :, k], fd, rtol=1e-6, atol=1e-3)


def test_identification_jacobian_matches_finite_differences(parameters):
    """The least-squares problem's Jacobian: geometry basis, frame twists through Jexp6, weights."""
    ps = ParameterSet(hm.get_preset("reference"))
    hexa = hm.Hexapod.from_preset("reference")
    poses = box_poses(hexa.home_pose, 6, seed=2)
    readings = np.array([hexa.inverse(T).lengths for T in poses])
    T_mb, T_pm = pin.exp6(np.array([0.1, -0.2, 0.3, 0.2, 0.1, -0.1])).homogeneous, np.eye(4)
    data = MeasuredPoses(readings, predict(T_mb, poses, T_pm))
    basis = free_basis(ps.gauge_constraints() * ps.scales, (), ps.size)
    problem = Problem(ps, data, Noise(), basis, (T_mb, T_pm), None)
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.normal(0, 0.5, basis.shape[1]), rng.normal(0, 2.0, 12)])  # frames away from 0
    J = problem.jac(x)
    for k in [0, 7, basis.shape[1] - 1] + list(range(basis.shape[1], basis.shape[1] + 12)):
        e = np.zeros_like(x)
        e[k] = 1e-4
        fd = (problem.fun(x + e) - problem.fun(x - e)) / 2e-4
        np.testing.assert_allclose(J[:, k], fd, rtol=1e-4, atol=1e-3)
