"""The tracker of a hexapod with redundant sensors: every reading taken, the consistency test on each sample."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from hexapod_model.kinematics.redundant import RedundantSolution
from hexapod_model.tracking.tracker import Tracker

from ..conftest import hexapod


def stream(name: str, n: int = 40) -> tuple[list[np.ndarray], np.ndarray]:
    """``n`` poses of a slow screw motion from home and their noise-free readings (reading order)."""
    hexa, six = hexapod(name), hexapod("reference")
    poses = [hexa.home_pose @ pin.exp6(np.array([1e-4, 5e-5, 2e-5, 1e-3, 0.0, 5e-4]) * k).homogeneous for k in range(n)]
    z = np.array([np.concatenate([six.inverse(T).lengths, hexa.redundancy.extra_readings(T)]) for T in poses])
    return poses, z


def error(a: np.ndarray, b: np.ndarray) -> float:
    return max(float(np.abs(a[:3, 3] - b[:3, 3]).max()), float(np.linalg.norm(pin.log3(a[:3, :3].T @ b[:3, :3]))))


def test_every_reading_is_solved_and_a_consistent_stream_tracks_the_truth():
    poses, z = stream("reference_tilt")
    tracker = Tracker(hexapod("reference_tilt"), noise=1e-6)
    for T, readings in zip(poses, z, strict=True):
        r = tracker.step(readings)
        assert r.status == "ok" and "inconsistent_readings" not in r.flags
        assert isinstance(r.solution, RedundantSolution) and r.solution.consistency.consistent
        assert error(r.pose, T) < 1e-9


def test_an_offset_leg_is_flagged_inconsistent_and_named_with_the_others_estimate():
    poses, z = stream("reference_tilt")
    z[20:, 2] += 3e-4  # m: leg 3 reads 0.3 mm long from the 21st sample
    tracker = Tracker(hexapod("reference_tilt"), noise=1e-6)
    results = [tracker.step(readings) for readings in z]
    assert all("inconsistent_readings" not in r.flags for r in results[:20])
    for T, r in zip(poses[20:], results[20:], strict=True):
        assert not r.ok and "inconsistent_readings" in r.flags
        assert r.solution.consistency.isolated == "leg3" and "estimate" in r.solution.flags
        assert error(r.pose, T) < 1e-8  # the pose of the seven good readings


def test_a_seventh_leg_detects_the_offset_without_naming_it():
    _, z = stream("reference7", 25)
    z[10:, 2] += 3e-4
    tracker = Tracker(hexapod("reference7"), noise=1e-6)
    results = [tracker.step(readings) for readings in z]
    assert all("inconsistent_readings" in r.flags and r.solution.consistency.isolated is None for r in results[10:])


def test_a_wrong_count_of_readings_is_an_unreadable_sample_naming_the_order():
    poses, z = stream("reference7", 10)
    tracker = Tracker(hexapod("reference7"), noise=1e-6)
    for readings in z[:5]:
        tracker.step(readings)
    bad = tracker.step(z[5, :6])
    assert bad.status == "invalid_input" and "expected 7 finite readings (leg1, leg2" in bad.solution.message
    nan = z[6].copy()
    nan[6] = np.nan
    assert tracker.step(nan).status == "invalid_input"
    good = tracker.step(z[7])
    assert good.status == "ok" and error(good.pose, poses[7]) < 1e-9


def test_a_recorded_log_without_the_extra_readings_is_one_line_naming_them():
    import pytest

    import hexapod_model as hm
    from hexapod_model.studies.track import track_log

    with pytest.raises(hm.InputError, match=r"expected 7 readings a row \(leg1, .*leg7\)"):
        track_log(hexapod("reference7"), np.arange(3.0), np.zeros((3, 6)))


def test_the_tracking_experiment_feeds_the_extra_readings():
    from hexapod_model.studies.track import simulate

    run = simulate(hexapod("reference7"), "A", rate_hz=100.0)
    assert "failed" not in set(run.status) and list(run.status).count("ok") > 0.9 * len(run.status)
    assert float(np.max(run.errors[:, 3:])) < 1e-9  # m: noise-free readings, the true pose
