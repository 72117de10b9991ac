"""The stream tracker under injected faults: each measured fault of the old tracker
has a test here, on a quick subset of trajectory B (benchmarks/tracker_faults.py runs all)."""

from __future__ import annotations

import functools
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import trajectory_poses
from hexapod_model.kinematics.body_check import BODY_STATUSES
from hexapod_model.studies.track import true_readings
from hexapod_model.tracking.tracker import Tracker, characteristic_length, pose_distance

from ..conftest import hexapod

STREAM_FLAGS = {"jump", "stuck", "branch_uncertain"}


@functools.cache
def trajectory_b(name: str, speed: float):
    """True poses and readings of trajectory B at ``speed`` on preset ``name``."""
    hexa = hexapod(name)
    length = characteristic_length(hexa)
    _, poses = trajectory_poses("B", hexa.home_pose, length / 50.0, 1000.0, speed)
    return poses, true_readings(hexa, poses)[0]


def track(name, speed, readings, predictor="eq22", **options):
    hexa = hexapod(name)
    poses, _ = trajectory_b(name, speed)
    tracker = Tracker(hexa, predictor, initial=hexa.inverse(poses[0], check=False), **options)
    res = [tracker.step(x) for x in readings]
    length = characteristic_length(hexa)
    return res, np.array([pose_distance(T, r.pose, length) for T, r in zip(poses, res)])


def alarm(r, k):
    """A stream alarm: a failed solve, a stream flag, or settling after the first samples."""
    return r.status not in ("ok", "flagged") or bool(STREAM_FLAGS & set(r.flags)) or ("settling" in r.flags and k > 2)


def stuck(readings, leg, start, count):
    out = readings.copy()
    out[start : start + count, leg] = out[start - 1, leg]
    return out


def test_recovery_after_a_stuck_leg_is_released_reference_8x():
    """Old tracker: after a leg stuck for 100 samples, all 300 later clean samples failed
    (failed samples never reset the predictor)."""
    _, clean = trajectory_b("reference", 8)
    res, err = track("reference", 8, stuck(clean, 1, 100, 100))
    assert any("stuck" in r.flags for r in res[100:105]), "flagged stuck within 5 samples"
    assert not any(r.ok for r in res[102:200]), "no sample of the stuck period is good"
    assert not any(alarm(r, k) for k, r in enumerate(res[204:], 204)), "clean again within 5 samples"
    assert err[204:].max() < 1e-6


def test_stuck_encoder_on_three_six_is_flagged_not_ok():
    """Old tracker: 3-6 at 8x, eq. 22: 99 samples ok with errors up to 83 mm."""
    _, clean = trajectory_b("3-6", 8)
    res, err = track("3-6", 8, stuck(clean, 1, 200, 100))
    good = np.array([r.ok for r in res])
    assert not np.any(good & (err > 1e-4)), "a sample off by more than 0.1 mm was returned as good"
    assert any("stuck" in r.flags for r in res[200:205])
    assert err[305:].max() < 1e-6  # tracking again after the release
    # B crosses a singularity of the 3-6 preset twice (samples 84 and 135): branch_uncertain
    # through each passage, cleared within 5 samples of leaving it (no longer latched)
    uncertain = np.array(["branch_uncertain" in r.flags for r in res])
    near = np.flatnonzero(["near_singular" in r.flags for r in res])
    assert uncertain[84] and uncertain[136]
    for last in (near[near < 110].max(), near.max()):
        assert not uncertain[last + 5 : last + 40].any()
    assert not uncertain[145:].any()


def test_a_one_sample_spike_is_flagged_and_clears_at_once():
    """Old tracker: a 5 mm spike latched branch_uncertain on every later sample."""
    _, clean = trajectory_b("spherical", 8)
    readings = clean.copy()
    readings[250, 2] += 5e-3
    res, err = track("spherical", 8, readings)
    assert not any(alarm(r, k) for k, r in enumerate(res[251:], 251))
    assert err[251:].max() < 1e-6
    assert "jump" in res[250].flags and res[250].legs == (2,) and not res[250].ok


@pytest.mark.parametrize("noise", [10e-6, 50e-6])
def test_reading_noise_raises_no_latched_false_alarms(noise):
    """Old tracker: with 10 um noise 91-95 % of the samples ended flagged, >= 98 % at 50 um."""
    _, clean = trajectory_b("reference", 8)
    noisy = clean + np.random.default_rng(7).normal(0.0, noise, clean.shape)
    res, err = track("reference", 8, noisy, **({} if noise == 10e-6 else {"noise": noise}))  # 10 um: default
    alarms = sum(alarm(r, k) for k, r in enumerate(res))
    assert alarms <= 0.001 * len(res)
    sigma = np.array([np.hypot(r.sigma_translation, 0.25 * r.sigma_rotation) for r in res])
    good = np.array([r.ok for r in res])
    # at 8x the trajectory passes legs through each other: those samples are rightly flagged
    hexa = hexapod("reference")
    poses, _ = trajectory_b("reference", 8)
    reachable = np.array([hexa.inverse(T, check=False).status not in BODY_STATUSES for T in poses])
    assert good[reachable].mean() > 0.7 and np.all(err[good] <= 5.0 * sigma[good])
    # the stated uncertainty is the propagated noise: errors scale with it
    assert 0.5 < np.sqrt(np.mean((err[good] / sigma[good]) ** 2)) < 1.5


def test_one_sample_default_noise_stays_quiet_at_1x_on_guideway():
    _, clean = trajectory_b("guideway", 1)
    noisy = clean[:1500] + np.random.default_rng(3).normal(0.0, 10e-6, clean[:1500].shape)
    res, _ = track("guideway", 1, noisy)
    assert sum(alarm(r, k) for k, r in enumerate(res)) == 0


def test_a_failure_resets_the_history_and_the_tracker_reanchors():
    """Readings outside the stroke for 10 samples, then good ones: the first good sample is
    solved by continuation from the last trusted configuration and flagged 'settling'."""
    _, clean = trajectory_b("reference", 8)
    readings = clean.copy()
    readings[100:110] = 0.5
    res, err = track("reference", 8, readings)
    assert all(r.status == "invalid_input" for r in res[100:110])
    assert "settling" in res[110].flags and err[110] < 1e-6
    assert not any(alarm(r, k) for k, r in enumerate(res[113:], 113))


def test_tracker_settings_are_validated():
    hexa = hm.Hexapod.from_preset("spherical")
    for bad in ({"noise": -1.0}, {"noise": float("nan")}, {"window": 2}, {"stuck_samples": 1.5}, {"nois": 1e-5}):
        with pytest.raises(hm.HexapodError):
            Tracker(hexa, **bad)


def test_three_six_noisy_passage_clears_branch_uncertain_with_the_true_assembly():
    """Old tracker: B crosses the 3-6 singular surface at samples 84 and 135 (8x); with 10 um
    noise every sample from the first passage on stayed branch_uncertain until reset(), and the
    solver followed the mirror assembly (2 cm off) between the two crossings."""
    _, clean = trajectory_b("3-6", 8)
    noisy = clean + np.random.default_rng(0).normal(0.0, 10e-6, clean.shape)
    res, err = track("3-6", 8, noisy)
    uncertain = np.array(["branch_uncertain" in r.flags for r in res])
    assert uncertain[84:87].any() and uncertain[135:138].any()  # each passage is flagged ...
    assert not uncertain[94:130].any() and not uncertain[146:].any()  # ... and clears within 10
    sigma = np.array([np.hypot(r.sigma_translation, 0.2 * r.sigma_rotation) for r in res])
    settled = np.r_[94:130, 146 : len(res)]
    assert np.all(err[settled] <= np.maximum(100e-6, 5.0 * sigma[settled]))  # the true assembly
    assert err[94:130].max() < 2e-3  # the mirror is 5-20 mm away there


def test_stuck_leg_at_50um_noise_and_1x_is_flagged_within_5_samples_on_guideway():
    """Old tracker: 6 samples (a slow leg moves 3 sqrt(2) noise only after 5-6 samples)."""
    _, clean = trajectory_b("guideway", 1)
    noisy = clean[:900] + np.random.default_rng(0).normal(0.0, 50e-6, clean[:900].shape)
    res, _ = track("guideway", 1, stuck(noisy, 1, 800, 60), noise=50e-6)
    assert not any(alarm(r, k) for k, r in enumerate(res[:800]))
    assert any("stuck" in r.flags for r in res[800:805])


def test_a_tracked_stream_loads_no_scipy_module_once_the_tracker_is_made():
    """scipy loaded mid-stream stalled that sample: the passage test's quantiles were imported at the
    first decision (scipy.stats, ~0.5 s), the stuck test's run length at a leg's first frozen run.
    A fresh interpreter tracks the noisy 3-6 passages of trajectory B with counted readings."""
    code = textwrap.dedent(
        """
        import sys
        import numpy as np
        from tests.tracking.test_faults import hexapod, trajectory_b
        from hexapod_model.tracking.tracker import Tracker
        poses, clean = trajectory_b("3-6", 8)
        noisy = np.round((clean + np.random.default_rng(0).normal(0.0, 10e-6, clean.shape)) / 1e-6) * 1e-6
        hexa = hexapod("3-6")
        tracker = Tracker(hexa, "eq22", initial=hexa.inverse(poses[0], check=False), resolution=1e-6)
        before = set(sys.modules)
        flags = [tracker.step(x).flags for x in noisy]
        assert any("branch_uncertain" in f for f in flags)  # passages, and the tests that decide them
        print(sorted(m for m in set(sys.modules) - before if m.split(".")[0] == "scipy"))
        """
    )
    root = Path(__file__).resolve().parents[2]
    out = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]", out.stdout
