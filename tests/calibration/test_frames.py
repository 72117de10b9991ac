"""The measurement model: pose errors and residuals in their units, the frame Jacobian, frames from noisy poses."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.calibration.frames import (
    ERROR_KEYS,
    Noise,
    error_stats,
    fit_frames,
    frame_jacobian,
    pose_errors,
    predict,
    residual,
)


def _rotated(T: np.ndarray, axis: np.ndarray, angle: float, shift: np.ndarray) -> np.ndarray:
    out = T.copy()
    out[:3, :3] = pin.exp3(angle * axis) @ T[:3, :3]
    out[:3, 3] += shift
    return out


def test_pose_errors_and_residuals_are_in_their_units():
    P = box_poses(np.eye(4), 5, seed=2)
    angle, shift = np.radians(0.5), np.array([0.0, 0.6e-3, -0.8e-3])  # 0.5 deg, 1 mm
    axis = np.array([0.0, 0.0, 1.0])
    M = np.array([_rotated(T, axis, angle, shift) for T in P])
    dp, dr = pose_errors(M, P)
    np.testing.assert_allclose(dp, 1.0, rtol=1e-12)  # mm
    np.testing.assert_allclose(dr, 0.5, rtol=1e-9)  # deg
    noise = Noise(position_m=2e-4, rotation_rad=1e-3)
    r = residual(M, P, noise)
    np.testing.assert_allclose(r[:, :3], np.tile(shift / 2e-4, (5, 1)), rtol=1e-12)
    np.testing.assert_allclose(r[:, 3:], np.tile(np.sin(angle) * axis / 1e-3, (5, 1)), atol=1e-9)  # in the device frame


def test_error_stats_are_mean_sample_deviation_and_maximum():
    rng = np.random.default_rng(3)
    errors = (rng.uniform(0, 2, 9), rng.uniform(0, 0.1, 9))
    stats = error_stats(errors)
    assert tuple(stats) == ERROR_KEYS
    for values, unit in zip(errors, ("translation", "rotation")):
        keys = [k for k in ERROR_KEYS if k.startswith(unit)]
        got = [stats[k] for k in keys]
        np.testing.assert_allclose(got, [values.mean(), values.std(ddof=1), values.max()], rtol=1e-12)
    assert error_stats((np.array([1.5]), np.array([0.2])))["translation_std_mm"] == 0.0


def _perturbed_residual(T_mb, P, T_pm, measured, noise, d: np.ndarray) -> np.ndarray:
    """Residuals with the frames moved by the twists ``d[:6]`` (measuring) and ``d[6:]`` (marker), on the right."""
    A, B = T_mb @ pin.exp6(d[:6]).homogeneous, T_pm @ pin.exp6(d[6:]).homogeneous
    return residual(predict(A, P, B), measured, noise)


def test_frame_jacobian_matches_finite_differences():
    rng = np.random.default_rng(5)
    P = box_poses(np.eye(4), 4, seed=6)
    T_mb, T_pm = pin.exp6(rng.normal(0, 0.5, 6)).homogeneous, pin.exp6(rng.normal(0, 0.2, 6)).homogeneous
    measured = predict(T_mb, P, T_pm) @ np.array([pin.exp6(rng.normal(0, 0.01, 6)).homogeneous for _ in range(4)])
    noise = Noise()
    J = frame_jacobian(T_mb, P, T_pm, measured, noise)
    assert J.shape == (4, 6, 12)
    for k in range(12):
        e = np.zeros(12)
        e[k] = 1e-7  # m or rad

        plus, minus = (_perturbed_residual(T_mb, P, T_pm, measured, noise, d) for d in (e, -e))
        np.testing.assert_allclose(J[:, :, k], (plus - minus) / 2e-7, rtol=1e-6, atol=1e-3)


def test_frames_from_noisy_poses_are_within_their_noise():
    """Seeded noise of 50 um / 0.01 deg on 30 poses: the frames come back to well under a millimetre."""
    rng = np.random.default_rng(8)
    home = np.eye(4)
    home[:3, 3] = hm.get_preset("reference").home_translation
    P = box_poses(home, 30, seed=9)
    T_mb, T_pm = pin.exp6(rng.normal(0, 0.5, 6)).homogeneous, pin.exp6(rng.normal(0, 0.2, 6)).homogeneous
    noise = Noise(position_m=5e-5, rotation_rad=np.radians(0.01))
    scale = np.r_[[noise.position_m] * 3, [noise.rotation_rad] * 3]
    jitter = np.array([pin.exp6(rng.normal(0, 1, 6) * scale).homogeneous for _ in range(30)])
    measured = predict(T_mb, P, T_pm) @ jitter
    A, B = fit_frames(P, measured, noise)
    for found, true in ((A, T_mb), (B, T_pm)):
        error = pin.log6(pin.SE3(found).inverse() * pin.SE3(true)).vector
        assert np.all(np.abs(error[:3]) < 1e-3) and np.all(np.abs(error[3:]) < np.radians(0.05)), error
    r = residual(predict(A, P, B), measured, noise)
    assert 0.5 < np.sqrt(np.mean(r**2)) < 1.5  # whitened: what is left is the stated noise


@pytest.mark.parametrize("position, rotation", [(0.0, 1e-3), (-1e-4, 1e-3), (1e-4, float("nan")), (float("inf"), 1.0)])
def test_a_noise_that_is_no_standard_deviation_is_named(position, rotation):
    with pytest.raises(hm.InputError, match=r"noise.*must be a positive standard deviation"):
        Noise(position, rotation)
