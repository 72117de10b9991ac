"""The tracker adapter: noise-propagated sigma (checked by Monte Carlo), margin, flags that clear."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.analysis.jacobian import leg_jacobian_local
from hexapod_model.service import PoseSolver

from ..conftest import hexapod

NOISE = 10e-6


@pytest.mark.parametrize("name", ["reference", "guideway"])
def test_propagation_is_the_inverse_of_the_eliminated_jacobian(name):
    hexa = hexapod(name)
    sol = hexa.forward([0.01, -0.005, 0.002, 0.0, 0.004, -0.003])
    X = PoseSolver(hexa, NOISE).propagation(sol.q)
    J, _ = leg_jacobian_local(hexa, sol.q)
    assert np.allclose(X @ J, np.eye(6), atol=1e-9)


def test_sigma_matches_monte_carlo_of_the_reading_noise():
    hexa = hexapod("reference")
    solver = PoseSolver(hexa, NOISE)
    truth = hexa.forward([0.02, -0.01, 0.015, -0.02, 0.005, 0.01])
    u = solver.uncertainty(truth.q)
    rng = np.random.default_rng(7)
    dp, dr = [], []
    for _ in range(400):
        s = hexa.forward(truth.lengths + rng.normal(0, NOISE, 6), guess=truth)
        dp.append(np.sum((s.pose[:3, 3] - truth.pose[:3, 3]) ** 2))
        dr.append(np.sum(pin.log3(truth.pose[:3, :3].T @ s.pose[:3, :3]) ** 2))
    # sigma is the RMS error length: sqrt(mean |e|^2) over 400 samples within ~10 %
    assert np.sqrt(np.mean(dp)) == pytest.approx(u.translation, rel=0.12)
    assert np.sqrt(np.mean(dr)) == pytest.approx(u.rotation, rel=0.12)
    assert 5e-6 < u.translation < 1e-4  # of the order of the reading noise


def test_margin_is_one_at_home_and_falls_towards_a_singularity():
    hexa = hexapod("reference")
    solver = PoseSolver(hexa, NOISE)
    assert solver.uncertainty(hexa.q_home).margin == pytest.approx(1.0, abs=1e-12)
    far = hexa.forward([0.15, 0.15, 0.15, 0.15, 0.15, 0.15])
    assert solver.uncertainty(far.q).margin < solver.uncertainty(hexa.forward([0.05] * 6).q).margin


def readings_along(hexa, n, step=2e-4):
    """Readings of a smooth motion (a constant twist) from home."""
    out, guess = [], None
    for k in range(n):
        T = hexa.home_pose.copy()
        T[:3, 3] += [step * k, 0.5 * step * k, 0.0]
        T[:3, :3] = T[:3, :3] @ pin.exp3(np.array([0.0, 0.0, 2e-4 * k]))
        guess = hexa.inverse(T, guess=guess)
        out.append(guess.lengths.copy())
    return np.array(out)


def test_noise_alone_raises_no_flag():
    hexa = hexapod("reference")
    solver = PoseSolver(hexa, NOISE)
    rng = np.random.default_rng(1)
    L = readings_along(hexa, 300) + rng.normal(0, NOISE, (300, 6))
    out = [solver.step(r) for r in L]
    settle = solver.tracker.settings.settle_samples  # the tracker's history fills first
    assert all(o.flags == ("settling",) for o in out[:settle])
    assert [o.status for o in out[settle:]].count("ok") == 300 - settle


def test_a_spike_is_flagged_and_the_doubt_clears_after_confirmation():
    hexa = hexapod("reference")
    solver = PoseSolver(hexa, NOISE, confirm_samples=4)
    L = readings_along(hexa, 40)
    L[20, 4] += 0.002
    out = [solver.step(r) for r in L]
    settle = solver.tracker.settings.settle_samples
    assert all(o.status == "ok" for o in out[settle:20])
    assert "jump" in out[20].flags and out[20].status == "flagged"
    flagged = [k for k, o in enumerate(out) if o.status != "ok" and k >= settle]
    assert flagged == list(range(20, flagged[-1] + 1)) and flagged[-1] <= 20 + 2 + 4
    assert all(o.status == "ok" and not o.flags for o in out[flagged[-1] + 1 :])


def test_a_failed_solve_reports_no_pose_and_tracking_restarts():
    hexa = hexapod("reference")
    solver = PoseSolver(hexa, NOISE)
    L = readings_along(hexa, 10)
    assert solver.step(L[0]).flags == ("settling",)
    bad = solver.step(np.array([0.19, -0.15, 0.19, -0.15, 0.19, -0.15]))  # no assembly near
    assert bad.status == "failed" and bad.pose is None and bad.uncertainty is None
    assert bad.flags[-1] in ("max_iterations", "not_found", "out_of_limits", "singular")  # the failure, named
    after = [solver.step(r) for r in L[1:]]
    settle = solver.tracker.settings.settle_samples
    assert all(o.status == "ok" for o in after[settle:]) and all(o.pose is not None for o in after)


def test_pose_record_angles_are_numpy_degrees_of_pinocchio_rpy_bit_for_bit():
    """The record's roll, pitch, yaw (deg): the same product as ``np.degrees`` (x * 180/pi), on floats."""
    from hexapod_model.service.record.pose import pose_record

    rng = np.random.default_rng(7)
    for _ in range(2000):
        T = np.eye(4)
        T[:3, :3] = pin.exp3(rng.normal(size=3) * rng.uniform(0.0, 3.0))
        rec = pose_record(T)
        assert [rec["roll"], rec["pitch"], rec["yaw"]] == np.degrees(pin.rpy.matrixToRpy(T[:3, :3])).tolist()
