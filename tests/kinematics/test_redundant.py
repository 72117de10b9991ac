"""Redundant sensing: the least-squares pose, the consistency test's false-alarm rate, fault detection and isolation."""

from __future__ import annotations

import functools

import numpy as np
import pinocchio as pin
import pytest
from scipy.stats import binomtest

import hexapod_model as hm

OFFSET = 3e-4  # m: the constant leg offset of the fault cases
POSE_TOL = 1e-9  # m and rad: noise-free redundant readings give the pose they were made from


@functools.cache
def hexapod(name: str) -> hm.Hexapod:
    return hm.Hexapod.from_preset(name)


def poses(n: int, seed: int) -> list[np.ndarray]:
    """``n`` poses within +-30 mm and +-8 deg of home (base frame, m)."""
    ref = hexapod("reference")
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        v = np.concatenate([rng.uniform(-0.03, 0.03, 3), rng.uniform(-8, 8, 3) * np.pi / 180])
        out.append(ref.home_pose @ pin.exp6(v).homogeneous)
    return out


def readings(hexa: hm.Hexapod, pose: np.ndarray) -> np.ndarray:
    """Every reading of ``hexa`` at ``pose``: the six legs by inverse kinematics, then the extra sensors."""
    six = hexa.inverse(pose).lengths
    return np.concatenate([six, hexa.redundancy.extra_readings(pose)])


def pose_error(a: np.ndarray, b: np.ndarray) -> float:
    """Largest translation (m) or rotation (rad) difference between two poses."""
    rot = np.linalg.norm(pin.log3(a[:3, :3].T @ b[:3, :3]))
    return max(float(np.abs(a[:3, 3] - b[:3, 3]).max()), float(rot))


@pytest.mark.parametrize("name", ["reference7", "reference_tilt"])
def test_clean_readings_give_their_pose_consistent(name):
    hexa = hexapod(name)
    assert hexa.reading_names == hexa.geometry.reading_names
    for T in poses(5, 1):
        sol = hexa.forward(readings(hexa, T))
        assert sol.converged and sol.consistency.consistent and sol.consistency.dof == len(hexa.reading_names) - 6
        assert pose_error(sol.pose, T) < POSE_TOL


def test_reading_count_and_strokes_are_checked():
    hexa = hexapod("reference7")
    z = readings(hexa, hexa.home_pose)
    with pytest.raises(hm.InputError, match="expected 7 values, got 6"):
        hexa.forward(z[:6])
    z[6] = 0.5
    with pytest.raises(hm.LimitError, match="leg7 = 0.5 m is outside"):
        hexa.forward(z)
    with pytest.raises(hm.InputError, match="alpha"):
        hexa.forward(readings(hexa, hexa.home_pose), alpha=2.0)


def test_six_leg_presets_keep_their_solve():
    ref, r7 = hexapod("reference"), hexapod("reference7")
    assert ref.redundancy is None and ref.reading_names == tuple(f"leg{i}" for i in range(1, 7))
    z = readings(r7, poses(1, 2)[0])
    a = ref.forward(z[:6])
    b = ref.forward(z[:6].copy())
    assert type(a) is hm.Solution and np.array_equal(a.pose, b.pose) and np.array_equal(a.q, b.q)


def test_redundant_solve_is_repeatable_bit_for_bit():
    hexa = hexapod("reference_tilt")
    z = readings(hexa, poses(1, 3)[0]) + np.random.default_rng(3).normal(0, 1, 8) * hexa.redundancy.sigmas
    a, b = hexa.forward(z), hexa.forward(z)
    assert np.array_equal(a.pose, b.pose) and a.consistency.statistic == b.consistency.statistic


@pytest.mark.parametrize("leg", range(6))
def test_offset_leg_is_named_with_the_inclinometer(leg):
    """Two parity equations: the offset leg is always a suspect, alone where its fault direction stands apart."""
    hexa = hexapod("reference_tilt")
    name = f"leg{leg + 1}"
    named = 0
    for T in poses(8, 10 + leg):
        z = readings(hexa, T)
        z[leg] += OFFSET
        with pytest.raises(hm.InconsistentReadingsError, match=name):
            hexa.forward(z)
        sol = hexa.forward(z, check=False)
        test = sol.consistency
        assert sol.status == "inconsistent_readings" and name in test.suspects
        assert test.isolated in (name, None)  # never another reading
        if test.isolated == name:
            named += 1
            assert sol.flags == ("estimate", f"without_{name}") and f"faulty reading {name}" in sol.message
            assert pose_error(sol.pose, T) < POSE_TOL  # the estimate from the other readings
        else:
            assert "not isolable" in sol.message and sol.flags == ()
    assert named >= 4


@pytest.mark.parametrize("leg", range(7))
def test_offset_leg_is_detected_by_a_seventh_leg_and_its_suspects_named(leg):
    hexa = hexapod("reference7")
    z = readings(hexa, poses(1, 20 + leg)[0])
    z[leg] += OFFSET
    sol = hexa.forward(z, check=False)
    test = sol.consistency
    assert sol.status == "inconsistent_readings" and not test.consistent and test.isolated is None
    assert f"leg{leg + 1}" in test.suspects and "cannot isolate" in sol.message
    assert f"leg{leg + 1}" in sol.message


@pytest.mark.parametrize("reading", ["tilt_x", "tilt_y"])
def test_inclinometer_bias_is_named(reading):
    hexa = hexapod("reference_tilt")
    z = readings(hexa, poses(1, 30)[0])
    z[hexa.reading_names.index(reading)] += 1e-3  # rad, 50 sigma
    sol = hexa.forward(z, check=False)
    assert sol.status == "inconsistent_readings" and sol.consistency.isolated == reading


@pytest.mark.parametrize("name", ["reference7", "reference_tilt"])
def test_false_alarm_rate_matches_the_stated_rate(name):
    """Clean readings with Gaussian noise of the stated sigmas fail the test at the rate alpha (binomial test)."""
    hexa = hexapod(name)
    alpha, n = 0.02, 1500
    rng = np.random.default_rng(7)
    clean = [readings(hexa, T) for T in poses(30, 40)]
    sig = hexa.redundancy.sigmas
    alarms = 0
    for k in range(n):
        z = clean[k % len(clean)] + rng.normal(0.0, 1.0, len(sig)) * sig
        sol = hexa.forward(z, check=False, alpha=alpha)
        assert sol.status in ("converged", "inconsistent_readings")
        alarms += sol.status == "inconsistent_readings"
    assert binomtest(alarms, n, alpha).pvalue > 1e-3, f"{alarms} alarms of {n} at rate {alpha}"


@pytest.mark.parametrize("name", ["reference7", "reference_tilt"])
def test_creeping_leg_is_flagged_above_its_detectable_size(name):
    """A leg creeping 2 um per sample under noise: each sample drifted by twice its detectable bias fails."""
    hexa = hexapod(name)
    rng = np.random.default_rng(11)
    sig = hexa.redundancy.sigmas
    leg = 2
    wrong_ok = flagged = 0
    for k, T in enumerate(poses(150, 50)):
        bias = 2e-6 * (k + 1)
        z = readings(hexa, T) + rng.normal(0.0, 1.0, len(sig)) * sig
        z[leg] += bias
        sol = hexa.forward(z, check=False)
        mdb = sol.consistency.detectable[leg]
        if bias >= 2 * mdb:
            flagged += 1
            wrong_ok += sol.status == "converged"
            assert f"leg{leg + 1}" in sol.consistency.suspects and sol.consistency.isolated in (f"leg{leg + 1}", None)
    assert wrong_ok == 0 and flagged > 50


def test_urdf_variant_carries_the_sensors(tmp_path):
    for name in ("reference7", "reference_tilt"):
        path = hm.write_urdf(hm.get_preset(name), tmp_path / f"{name}.urdf")
        from_urdf, preset = hm.Hexapod.from_urdf(path), hexapod(name)
        assert from_urdf.reading_names == preset.reading_names
        z = readings(preset, poses(1, 60)[0])
        assert pose_error(from_urdf.forward(z).pose, preset.forward(z).pose) < POSE_TOL


def test_batch_solve_refuses_redundant_readings():
    hexa = hexapod("reference7")
    with pytest.raises(hm.InputError, match=r"takes its 7 readings \(leg1, .*leg7\) in forward"):
        hexa.forward_batch(np.zeros((3, 6)))


def test_gross_faults_are_inconsistent_not_a_solver_failure():
    hexa = hexapod("reference7")
    z = readings(hexa, hexa.home_pose)
    z[6] = 0.19  # m: the seventh leg reads 19 cm long, within its stroke
    sol = hexa.forward(z, check=False)
    assert sol.status == "inconsistent_readings" and "leg7" in sol.consistency.suspects
    tilt = hexapod("reference_tilt")
    z = readings(tilt, tilt.home_pose)
    z[6:] += (1.2, -1.3)  # rad: both tilts wrong
    sol = tilt.forward(z, check=False)
    assert sol.status == "inconsistent_readings" and sol.consistency.suspects == ()
    assert "no single reading's exclusion restores consistency" in sol.message


def test_warm_start_from_a_redundant_solution():
    hexa = hexapod("reference_tilt")
    a, b = poses(2, 70)
    first = hexa.forward(readings(hexa, a))
    second = hexa.forward(readings(hexa, b), guess=first)
    assert second.converged and pose_error(second.pose, b) < POSE_TOL
    assert first.det_sign == hexapod("reference").forward(readings(hexa, a)[:6]).det_sign != 0


def central_differences(hexa: hm.Hexapod, pose: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """``m x 6`` derivative of every reading in the platform-frame twist, by central differences."""
    J = np.empty((len(hexa.reading_names), 6))
    for i in range(6):
        e = np.zeros(6)
        e[i] = step
        plus = readings(hexa, pose @ pin.exp6(e).homogeneous)
        minus = readings(hexa, pose @ pin.exp6(-e).homogeneous)
        J[:, i] = (plus - minus) / (2.0 * step)
    return J


def with_encoder_models(name: str) -> hm.Hexapod:
    """``name`` with an encoder model on every leg (zero and scale) and scale errors on the measuring legs."""
    from dataclasses import replace

    g = hexapod(name).geometry
    legs = tuple(replace(leg, encoder_zero=0.01 * i, encoder_scale=0.02 * (i - 2.5)) for i, leg in enumerate(g.legs))
    return hm.Hexapod.from_geometry(replace(g, legs=legs))


@pytest.mark.parametrize("name", ["reference7", "reference_tilt", "encoders"])
def test_the_readings_jacobian_matches_central_differences(name):
    # the Gauss-Newton step's and the consistency test's Jacobian, analytic: every reading's row
    # against central differences of inverse kinematics and the extra sensors' model
    hexa = with_encoder_models("reference7") if name == "encoders" else hexapod(name)
    assert name != "encoders" or hexa.engine.encoder is not None
    for T in [hexa.home_pose, *poses(4, seed=7)]:
        ik = hexa.inverse(T)
        J = hexa.redundancy.jacobian(T, ik)
        fd = central_differences(hexa, T)
        # m/m and m/rad (legs), rad/m and rad/rad (tilts); central differences of 1e-6 are good to
        # about 1e-7 of a row's size here (the inverse solves stop at 1e-10 m)
        np.testing.assert_allclose(J, fd, rtol=0, atol=2e-6)
