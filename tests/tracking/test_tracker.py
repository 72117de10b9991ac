"""Jakobović and Jelenković (2002) §IV-V: predictors, the tracker's branch flags, `hexapod track`."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.cli.main import main
from hexapod_model.lie import rpy_to_matrix
from hexapod_model.studies.track import run_table, simulate
from hexapod_model.tracking.tracker import PREDICTORS, Tracker, pose_distance, predict


@pytest.fixture(scope="module")
def reference():
    return hm.Hexapod.from_preset("reference")


@pytest.mark.parametrize("predictor", ["eq22", "eq23", "eq24"])
def test_predictors_are_exact_on_constant_twist_motion(reference, predictor):
    """P_k = q0 (+) k dv (a screw motion of the platform, linear leg joints): every linear
    extrapolation predicts the next sample exactly, and the quaternion stays unit."""
    model = reference.model
    rng = np.random.default_rng(3)
    dv = rng.normal(scale=0.01, size=model.nv)
    q0 = pin.integrate(model, reference.q_home, rng.normal(scale=0.05, size=model.nv))
    P = [pin.integrate(model, q0, k * dv) for k in range(4)]  # oldest first
    X = predict(model, [P[2], P[1], P[0]], predictor)
    assert np.abs(pin.difference(model, P[3], X)).max() < 1e-12
    i = reference.closed_loop.platform_q
    assert np.linalg.norm(X[i + 3 : i + 7]) == pytest.approx(1.0, abs=1e-14)


def test_predictors_differ_on_accelerated_motion_and_none_holds(reference):
    model = reference.model
    dv = np.zeros(model.nv)
    dv[reference.closed_loop.platform_v] = 1e-3
    P = [pin.integrate(model, reference.q_home, (k * k) * dv) for k in range(3)]  # x = k^2 mm
    hist = [P[2], P[1], P[0]]
    x = {p: predict(model, hist, p)[reference.closed_loop.platform_q] for p in PREDICTORS}
    assert x["none"] == pytest.approx(4e-3)
    assert x["eq22"] == pytest.approx(7e-3)  # 2*4 - 1
    assert x["eq23"] == pytest.approx(6e-3)  # 1.5*4 - 0.5*0
    assert x["eq24"] == pytest.approx(5.5e-3)  # 1.25*4 + 0.5*1 - 0.75*0
    with pytest.raises(hm.InputError):
        predict(model, hist, "eq99")


def test_short_history_falls_back(reference):
    model = reference.model
    q = reference.q_home
    np.testing.assert_array_equal(predict(model, [q], "eq24"), q)


@pytest.mark.parametrize("predictor", PREDICTORS)
def test_a_plate_at_rest_far_from_home_is_not_predicted_from_home(reference, predictor):
    """The start (home) is no sample of the stream: the second sample is predicted from the first alone.

    With the plate 5 cm off home and tilted by 21 and 23 degrees, a prediction that extrapolated
    from home to the first sample led Newton beyond the Cardan joints' limits, and the tracker
    kept that configuration: every later sample of the plate at rest was out_of_limits.
    """
    T = reference.home_pose.copy()
    T[:3, :3] = T[:3, :3] @ rpy_to_matrix(*np.radians([-21.2, 23.1, 2.0]))
    T[:3, 3] += [-0.0226, -0.0493, 0.0146]  # m, base frame
    lengths = reference.inverse(T).lengths
    tracker = Tracker(reference, predictor)
    results = [tracker.step(lengths) for _ in range(8)]
    assert [(r.status, r.flags) for r in results[-3:]] == [("ok", ())] * 3, [(r.status, r.flags) for r in results]
    assert all(r.status == "ok" and set(r.flags) <= {"settling"} for r in results)
    assert max(pose_distance(r.solution.pose, T, 1.0) for r in results) < 1e-9  # m (rad as m)


@pytest.mark.parametrize("preset", ["reference", "intersecting", "spherical", "3-6", "guideway"])
def test_plates_at_rest_about_home_are_ok_after_settling(preset):
    """50 plates at rest about home (box poses), each tracked from home with 1 um noise read as 1 um counts.

    After the first samples every sample is ok and unflagged, however far the plate is from home
    (a prediction extrapolated from home to the first sample leaves the limits or the assembly
    on some of them).
    """
    hexa = hm.Hexapod.from_preset(preset)
    solved = hexa.inverse_batch(box_poses(hexa.home_pose, 50, seed=1))
    rng = np.random.default_rng(1)
    doubtful = []
    for i in np.flatnonzero(solved.converged):
        tracker = Tracker(hexa, noise=1e-6, resolution=1e-6)
        for k in range(12):
            r = tracker.step(np.round((solved.lengths[i] + rng.normal(0.0, 1e-6, 6)) * 1e6) / 1e6)  # m, in counts
            if k >= 5 and (r.status != "ok" or r.flags):
                doubtful.append((int(i), k, r.status, r.flags))
    assert np.count_nonzero(solved.converged) >= 40 and doubtful == [], doubtful[:5]


def test_tracking_trajectory_a_stays_on_branch_and_unflagged(reference):
    run = simulate(reference, "A", speed=8, predictor="eq24")
    s = run.summary()
    assert s["branch_jumps"] == 0 and s["failed"] == 0
    # only the first samples, before the motion model has three, are unchecked ('settling')
    assert s["flags"] == {"settling": 3} and list(run.status[:4]) == ["flagged"] * 3 + ["ok"]
    assert s["max_position_error_m"] < 1e-9 and s["max_angle_error_deg"] < 1e-7
    ends, w = run.window_max()
    assert w.shape == (len(ends), 6) and ends[-1] == pytest.approx(run.t[-1])
    assert np.all(w.max(axis=0) == run.errors.max(axis=0))


def _yaw_passage(hexa, lo=80.0, hi=100.0, n=2001):
    poses, lengths, sol = [], [], None
    for yaw in np.radians(np.linspace(lo, hi, n)):
        T = hexa.home_pose.copy()
        T[:3, :3] = rpy_to_matrix(0.0, 0.0, yaw)
        sol = hexa.inverse(T, guess=sol)
        poses.append(T)
        lengths.append(sol.lengths)
    return poses, lengths


@pytest.fixture(scope="module")
def passage():
    """The spherical preset turning about z through its 90 deg singularity."""
    hexa = hm.Hexapod.from_preset("spherical")
    return hexa, *_yaw_passage(hexa)


@pytest.mark.parametrize("predictor", PREDICTORS)
def test_near_singular_passage_is_flagged_and_no_wrong_sample_passes_as_ok(passage, predictor):
    """The paper's raw tracker (``recover=False``: the predictor alone chooses the assembly)."""
    hexa, poses, lengths = passage
    tracker = Tracker(hexa, predictor, initial=hexa.inverse(poses[0]), recover=False)
    res = [tracker.step(l) for l in lengths]
    err = np.array([pose_distance(T, r.pose, 0.25) for T, r in zip(poses, res)])
    good = np.array([r.ok for r in res])
    near = [("near_singular" in r.flags) for r in res]
    assert near[1000], "the singular pose itself must be flagged"
    assert not any(near[:500]) and not any(near[-500:]), "far from the singularity nothing is flagged"
    assert not np.any((err > 1e-5) & good), "a wrong-branch sample was returned as fine"
    if predictor == "none":
        # the paper's 'division': without prediction the solver follows the wrong branch ...
        assert np.sum(err > 1e-3) > 500
        # ... and no sample of the wrong branch is good (near the singularity and after it
        # the pose is flagged near_singular / imprecise: its noise-propagated sigma is large)
        assert not any(r.ok for r, e in zip(res, err) if e > 1e-5)

    else:
        # linear prediction carries the solver through the bifurcation (Jakobović and Jelenković (2002) §V)
        assert err.max() < 1e-5


def test_passage_with_recovery_keeps_the_moving_assembly_even_without_prediction(passage):
    """Near a singularity the tracker also solves from its motion model and keeps the
    assembly the motion continues to: no predictor leaves the true branch."""
    hexa, poses, lengths = passage
    tracker = Tracker(hexa, "none", initial=hexa.inverse(poses[0]))
    res = [tracker.step(l) for l in lengths]
    err = np.array([pose_distance(T, r.pose, 0.25) for T, r in zip(poses, res)])
    assert err.max() < 1e-5 and not any(r.failed for r in res)
    # no stream alarm; from the first near-singular sample on the assembly is not certified
    first = next(k for k, r in enumerate(res) if "near_singular" in r.flags)
    assert 500 < first < 1000 and not any(set(r.flags) - {"imprecise"} for r in res[3:first])
    assert all(set(r.flags) - {"near_singular", "imprecise"} == {"branch_uncertain"} for r in res[first + 1 :])
    assert all(0 < r.sigma_translation < np.inf for r in res if r.condition_number < np.inf)


def test_reset_reanchors_a_tracker_that_left_the_branch(passage):
    hexa, poses, lengths = passage
    tracker = Tracker(hexa, "none", initial=hexa.inverse(poses[0]), recover=False)
    res = [tracker.step(l) for l in lengths]
    assert not res[-1].ok and pose_distance(poses[-1], res[-1].pose, 0.25) > 1e-3
    tracker.reset(hexa.inverse(poses[-1]))
    again = [tracker.step(l) for l in lengths[-1:] * 5]
    assert all(pose_distance(poses[-1], r.pose, 0.25) < 1e-9 for r in again)
    assert "settling" in again[0].flags and "settling" not in again[-1].flags
    assert not any("branch_uncertain" in r.flags for r in again)


def test_reading_outside_stroke_is_a_failed_sample_not_an_exception(reference):
    tracker = Tracker(reference, "eq22")
    r = tracker.step([0.5, 0, 0, 0, 0, 0])
    assert r.status == "invalid_input" and r.failed and not r.ok and "stroke" in r.solution.message
    r = tracker.step(np.zeros(6))
    assert not r.failed and r.flags == ("settling",)


def test_track_command_writes_figure_and_summary(tmp_path, capsys):
    js = tmp_path / "t.json"
    assert (
        main(
            [
                "track",
                "reference",
                "--trajectory",
                "B",
                "--speed",
                "8",
                "--predictor",
                "eq23",
                "--out",
                str(tmp_path),
                "--json",
                str(js),
            ]
        )
        == 0
    )
    s = json.loads(js.read_text())
    assert (tmp_path / "track_B_x8_eq23.png").stat().st_size > 1000
    assert s["samples"] == 501 and s["branch_jumps"] == 0
    # trajectory B's 55 deg roll leaves the reference Cardan limits: reported, not hidden
    assert s["truth_ik_status"].get("out_of_limits", 0) == s["flags"].get("out_of_limits", 0) > 0
    assert "left the true branch: no" in capsys.readouterr().out


def test_table_rows(reference):
    rows = run_table(reference, trajectories=("A",), predictors=("none", "eq22"), speeds=(8,))
    assert [(r["trajectory"], r["predictor"], r["speed"]) for r in rows] == [("A", "none", 8), ("A", "eq22", 8)]
    assert all(r["median_solve_us"] > 0 and r["branch_jumps"] == 0 for r in rows)


def test_three_six_trajectory_b_division_without_prediction():
    """Jakobović and Jelenković's 'division' on a real trajectory: B passes near a singularity of the 3-6
    preset; without prediction the solver leaves the true branch (flagged, never 'ok'), with
    eq. 22 it holds on."""
    hexa = hm.Hexapod.from_preset("3-6")
    none = simulate(hexa, "B", 8, "none").summary()
    eq22 = simulate(hexa, "B", 8, "eq22").summary()
    assert none["branch_jumps"] >= 1 and none["off_branch_samples"] > 0
    assert none["unflagged_off_branch"] == 0 and none["flags"].get("branch_uncertain", 0) >= 1
    assert eq22["branch_jumps"] == 0 and eq22["off_branch_samples"] == 0
    assert eq22["flags"].get("near_singular", 0) > 0


@pytest.mark.parametrize("name", ["reference", "3-6", "guideway"])
def test_compiled_sensitivity_matches_the_jacobian_module(name):
    """The tracker's compiled elimination gives the same 6x6 Jacobian, condition number and
    propagated uncertainty as the SVD route of hexapod_model.analysis.jacobian."""
    from hexapod_model.analysis.jacobian import evaluate_jacobian, leg_jacobian, leg_jacobian_local
    from hexapod_model.analysis.sensitivity import SensitivityEvaluator
    from hexapod_model.analysis.trajectories import box_poses

    hexa = hm.Hexapod.from_preset(name)
    ev = SensitivityEvaluator(hexa, 0.25)
    for T in box_poses(hexa.home_pose, 5, seed=4):
        q = hexa.inverse(T).q
        s = ev.evaluate(q)
        J = leg_jacobian_local(hexa, q)[0]
        np.testing.assert_allclose(ev.J, J, rtol=0, atol=1e-12 * np.abs(J).max())
        assert s.condition_number == pytest.approx(evaluate_jacobian(leg_jacobian(hexa, q), 0.25).condition_number)
        Ji = np.linalg.inv(leg_jacobian(hexa, q))  # base frame: traces are frame-invariant
        assert s.translation == pytest.approx(np.sqrt(np.sum(Ji[:3] ** 2)))
        assert s.rotation == pytest.approx(np.sqrt(np.sum(Ji[3:] ** 2)))
        assert s.det_sign == np.sign(np.linalg.det(J))


def test_motion_model_weights_extrapolate_quadratics_exactly():
    from hexapod_model.tracking.reading_tests import MotionModel

    mm = MotionModel()
    for ages in [(1, 2, 3), (1, 2, 3, 4, 5, 6), (2, 3, 5, 6), (4, 5, 6, 7, 8, 9)]:
        w, spread = mm.weights(ages)
        a = -np.asarray(ages, dtype=float)
        assert w @ (3.0 - 2.0 * a + 0.5 * a**2) == pytest.approx(3.0)
        assert spread == pytest.approx(np.sqrt(1 + w @ w)) and w.sum() == pytest.approx(1.0)
    assert mm.weights((1, 2, 3))[1] == pytest.approx(np.sqrt(20.0))  # l^ = 3 l0 - 3 l1 + l2


def test_trackers_stepped_in_turn_on_one_thread_may_share_an_evaluator(reference):
    """Two streams stepped alternately with one shared SensitivityEvaluator give, bit for bit, what
    each gives with its own (same code path): a step leaves nothing in the evaluator that the next reads."""
    from hexapod_model.analysis.sensitivity import SensitivityEvaluator
    from hexapod_model.tracking.tracker import characteristic_length

    rng = np.random.default_rng(5)
    ramps = [np.linspace(0.0, 0.004, 60)[:, None] * rng.uniform(-1, 1, 6) for _ in range(2)]
    ramps = [r + rng.normal(0.0, 1e-6, r.shape) for r in ramps]
    alone = [Tracker(reference, noise=1e-6) for _ in ramps]
    shared_eval = SensitivityEvaluator(reference, characteristic_length(reference))
    shared = [Tracker(reference, noise=1e-6, sensitivity=shared_eval) for _ in ramps]
    for k in range(60):
        for i, r in enumerate(ramps):
            a, b = alone[i].step(r[k]), shared[i].step(r[k])
            assert a.flags == b.flags and a.status == b.status
            np.testing.assert_array_equal(a.solution.q, b.solution.q)
            assert (a.sigma_translation, a.condition_number) == (b.sigma_translation, b.condition_number)
    with pytest.raises(hm.InputError):
        Tracker(reference, length=1.0, sensitivity=shared_eval)


def test_a_caller_may_refill_one_readings_array_sample_after_sample(reference):
    """One array refilled for every sample (a 1 kHz loop's buffer), or read-only rows: the answers of fresh arrays.

    The stuck test compares each sample with the ones before: a tracker that kept the caller's
    array saw every leg frozen, and flagged most of trajectory A ``stuck``.
    """
    from hexapod_model.service.sim.config import trajectory_sequence

    lengths, guess = [], None
    for T in trajectory_sequence("A", reference.home_pose, 0.01, 250.0, 8.0)[:300]:
        guess = reference.inverse(T, guess=guess)
        lengths.append(guess.lengths)
    readings = np.array(lengths) + np.random.default_rng(0).normal(0.0, 10e-6, (len(lengths), 6))
    rows = readings.copy()
    rows.setflags(write=False)  # pandas' copy-on-write to_numpy(), np.load(..., mmap_mode="r")
    fresh, refilled, read_only = Tracker(reference), Tracker(reference), Tracker(reference)
    buffer = np.empty(6)
    for k in range(len(readings)):
        buffer[:] = readings[k]
        a, b, c = fresh.step(readings[k].copy()), refilled.step(buffer), read_only.step(rows[k])
        assert a.flags == b.flags == c.flags and a.status == b.status == c.status
        np.testing.assert_array_equal(a.solution.q, b.solution.q)
        np.testing.assert_array_equal(a.solution.q, c.solution.q)
    assert a.ok


def test_a_trackers_proofs_do_not_depend_on_the_trackers_stepped_before_it(reference):
    """Fixtures at rest at poses of their own, stepped in turn on one thread (the service's cycle).

    Each tracker's answers, its proofs included, are bit for bit those it gives stepped alone
    (same code path), and at rest its steps are proven in its own region: a proof state shared by
    the thread made each step find the other fixture's region and prove itself afresh.
    """
    poses = [reference.home_pose.copy() for _ in range(2)]
    poses[0][:3, 3] += [0.01, 0.0, 0.02]
    poses[1][:3, 3] += [-0.01, 0.015, 0.01]
    rng = np.random.default_rng(6)
    series = [reference.inverse(T).lengths + rng.normal(0.0, 1e-6, (40, 6)) for T in poses]
    alone = []
    for readings in series:
        tracker = Tracker(reference, noise=1e-6)
        alone.append([tracker.step(r) for r in readings])
    trackers = [Tracker(reference, noise=1e-6) for _ in series]
    for k in range(40):
        for i, readings in enumerate(series):
            got, want = trackers[i].step(readings[k]), alone[i][k]
            assert got.status == want.status and got.flags == want.flags
            np.testing.assert_array_equal(got.solution.q, want.solution.q)
            assert got.solution.proof == want.solution.proof, (k, i, got.solution.proof, want.solution.proof)
    for samples in alone:
        proofs = [s.solution.proof for s in samples[10:]]
        assert all(p is not None and p.proven and p.in_region for p in proofs), proofs
