"""Batch solves give every row what the per-row API gives it, failures included."""

from __future__ import annotations

import json
import threading
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses, trajectory_poses
from hexapod_model.lie import rpy_to_matrix

from ..conftest import PATH_TOL, PRESET_NAMES, assert_same_message, batch_rule_forward, hexapod, limits_only
from .test_newton import idle_roll_hexapod


def per_row(solve, rows, guess=None, warm=False) -> list[tuple]:
    """(status, message, flags, det_sign, iterations, pose, lengths, q, proof) per row, with check=False."""
    out = []
    for x in rows:
        try:
            sol = solve(x, guess, check=False)
        except hm.HexapodError as exc:
            out.append(("invalid_input", str(exc), (), 0, 0, None, None, None, None))
            continue
        row = (sol.status, sol.message, sol.flags, sol.det_sign, sol.iterations, sol.pose, sol.lengths, sol.q)
        out.append((*row, getattr(sol, "proof", None)))
        if warm and sol.converged:
            guess = sol
    return out


def assert_rows_match(result: hm.BatchResult, expected: list[tuple]) -> None:
    assert len(result.status) == len(expected)
    for k, (status, message, flags, det_sign, iterations, pose, lengths, q, proof) in enumerate(expected):
        assert (result.status[k], result.flags[k], result.det_sign[k]) == (status, flags, det_sign), k
        if status == "converged":  # a proof where the row's forward has one
            got = result.proofs[k] if result.proofs else None
            assert (got is None, got is not None and got.proven) == (proof is None, proof is not None), k
        assert_same_message(result.messages[k], message, numbers=status != "max_iterations")
        if status == "invalid_input":
            assert (
                np.all(np.isnan(result.poses[k])) and np.all(np.isnan(result.lengths[k])) and result.iterations[k] == 0
            )
            continue
        assert result.iterations[k] == iterations
        if status != "max_iterations":  # a diverging Newton's last iterate magnifies rounding
            # the batch loop and the one-call solve: two compiled units, the same answer to rounding
            np.testing.assert_allclose(result.q[k], q, rtol=0, atol=PATH_TOL)
        if status == "converged":
            np.testing.assert_allclose(result.poses[k], pose, rtol=0, atol=PATH_TOL)
            np.testing.assert_allclose(result.lengths[k], lengths, rtol=0, atol=PATH_TOL)
        else:
            assert np.all(np.isnan(result.poses[k])) and np.all(np.isnan(result.lengths[k]))


def mixed_readings(hexa: hm.Hexapod, seed: int) -> np.ndarray:
    """Readings of far poses (some outside the Cardan limits), some beyond the stroke, NaN and inf."""
    poses = box_poses(hexa.home_pose, 120, seed=seed, translation=0.09, angle_deg=40)
    sols = [hexa.inverse(T, check=False) for T in poses]
    rows = np.array([s.q[hexa.closed_loop.prismatic_q] for s in sols])
    rng = np.random.default_rng(seed)
    rows[rng.choice(len(rows), 8, replace=False), rng.integers(0, 6, 8)] = hexa.stroke[0, 1] + 0.01
    rows[3, 2], rows[7, 0] = np.nan, np.inf
    return rows


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_forward_batch_rows_match_forward(name):
    hexa = hexapod(name)
    rows = mixed_readings(hexa, seed=41)
    statuses = set()
    for max_iter in (20, 3):
        result = hexa.forward_batch(rows, max_iter=max_iter)
        expected = per_row(lambda x, g, check, m=max_iter: hexa.forward(x, g, max_iter=m, check=check), rows)
        assert_rows_match(result, expected)
        statuses |= set(result.status)
    assert {"converged", "invalid_input"} <= statuses
    assert "max_iterations" in statuses or name == "3-6"  # 3-6: every assembly from the resultant instead


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_inverse_batch_rows_match_inverse(name):
    hexa = hexapod(name)
    poses = box_poses(hexa.home_pose, 150, seed=42, translation=0.12, angle_deg=45)
    poses[5, 0, 0] = 2.0  # not a rigid transform
    poses[9, 1, 3] = np.nan
    result = hexa.inverse_batch(poses)
    assert_rows_match(result, per_row(hexa.inverse, poses))
    assert {"converged", "out_of_limits", "invalid_input"} <= set(result.status)
    # x, y, z, qx, qy, qz, qw rows: the same poses
    xyzquat = np.array([pin.SE3ToXYZQUAT(pin.SE3(T)) if np.isfinite(T).all() else np.full(7, np.nan) for T in poses])
    xyzquat[5] = [0, 0, 0.4, 0, 0, 0, 1.1]  # not a unit quaternion
    again = hexa.inverse_batch(xyzquat)
    ok = result.converged
    np.testing.assert_allclose(again.lengths[ok], result.lengths[ok], rtol=0, atol=1e-12)
    assert list(again.status[:5]) == list(result.status[:5]) and again.status[5] == "invalid_input"
    assert "quaternion" in again.messages[5]


def test_warm_batches_follow_a_time_series_like_the_cli():
    hexa = hexapod("reference")
    _, poses = trajectory_poses("A", hexa.home_pose, 0.25 / 50, rate_hz=250)
    readings = hexa.inverse_batch(poses, warm=True).lengths
    readings[40] = np.nan  # a bad row: the next row starts from the last good one
    readings[41, 3] = 1.0  # out of stroke
    result = hexa.forward_batch(readings, warm=True)
    assert_rows_match(result, per_row(batch_rule_forward(hexa), readings, warm=True))
    good = result.converged
    assert good.sum() == len(readings) - 2 and np.nanmax(np.abs(result.poses[good] - poses[good])) < 1e-9
    assert np.median(result.iterations[good]) < result.iterations[0]  # warm rows: fewer steps than from home
    start = hexa.forward(readings[0])
    assert_rows_match(
        hexa.forward_batch(readings[1:], start, warm=True), per_row(batch_rule_forward(hexa), readings[1:], start, True)
    )


def test_singular_and_near_singular_rows():
    """The spherical preset is singular at 90 deg of yaw about its home position."""
    hexa = hexapod("spherical")
    poses = np.repeat(hexa.home_pose[None], 7, axis=0)
    poses[:, :3, :3] = rpy_to_matrix(0.0, 0.0, np.radians([60.0, 85.0, 89.0, 89.9, 90.0, 91.0, 120.0]))
    rows = hexa.inverse_batch(poses).lengths
    for guess in (None, hexa.inverse(poses[2])):
        for warm in (False, True):
            for prove in (True, False):
                result = hexa.forward_batch(rows, guess, warm=warm, prove=prove)
                assert_rows_match(result, per_row(batch_rule_forward(hexa, prove), rows, guess, warm))
    statuses = set(hexa.forward_batch(rows, hexa.inverse(poses[2])).status)
    flagged = hexa.forward_batch(rows, hexa.inverse(poses[2]), warm=True).flags
    assert ("near_singular",) in flagged and len(statuses) > 1


@pytest.mark.parametrize("body", [False, True])
def test_a_warm_row_near_a_singularity_is_converged_only_with_its_proof(body):
    """tests/data/three_six_warm_wrong.json: from its guess the warm step converges, flagged near_singular,
    at another assembly 1.1 mm away; forward says uncertified (its Krawczyk proof fails), the batch
    returned it converged."""
    hexa = hexapod("3-6") if body else limits_only("3-6")
    case = json.loads((Path(__file__).parents[1] / "data" / "three_six_warm_wrong.json").read_text())
    guess = hexa.inverse(np.array(case["guess_pose"]), check=False)
    readings = np.array(case["readings_m"])
    T = hexa.home_pose.copy()
    T[:3, 3] += [0.01, 0.0, 0.0]
    rows = np.array([readings, hexa.inverse(T).lengths, readings])
    for warm in (False, True):
        for prove in (True, False):
            result = hexa.forward_batch(rows, guess, warm=warm, prove=prove)
            expected = per_row(batch_rule_forward(hexa, prove), rows, guess, warm)
            assert_rows_match(result, expected)
            assert expected[0][0] == "uncertified" and "Krawczyk" in expected[0][1] and not result.converged[0]


def test_general_path_batches():
    hexa, plain = idle_roll_hexapod(), hexapod("spherical")
    poses = box_poses(plain.home_pose, 12, seed=43)
    back = hexa.inverse_batch(poses)
    assert_rows_match(back, per_row(hexa.inverse, poses))
    np.testing.assert_allclose(back.lengths, plain.inverse_batch(poses).lengths, rtol=0, atol=1e-10)
    rows = back.lengths.copy()
    rows[2, 0] = np.nan
    assert_rows_match(hexa.forward_batch(rows), per_row(batch_rule_forward(hexa), rows))


def test_batches_in_threads_match_one_thread():
    hexa = hm.Hexapod.from_preset("reference")
    rows = mixed_readings(hexa, seed=44)
    expected = hexa.forward_batch(rows)
    results: list = []

    def run() -> None:
        for _ in range(5):
            results.append(hexa.forward_batch(rows))

    threads = [threading.Thread(target=run) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(results) == 20
    for r in results:
        np.testing.assert_array_equal(r.q, expected.q)
        assert list(r.status) == list(expected.status)


@pytest.mark.parametrize(
    "call, pattern",
    [
        (lambda h: h.forward_batch([0.0] * 6), r"expected shape \(N, 6\)"),
        (lambda h: h.forward_batch(np.zeros((3, 5))), r"expected shape \(N, 6\)"),
        (lambda h: h.forward_batch("abc"), r"expected"),
        (lambda h: h.inverse_batch(np.zeros((3, 3, 3))), r"expected shape \(N, 4, 4\)"),
    ],
)
def test_bad_batch_input_raises_one_clear_error(call, pattern):
    with pytest.raises(hm.InputError, match=pattern):
        call(hexapod("reference"))


def test_the_compiled_loops_compile_the_iteration_once():
    # forward_batch's certified attempts, its plain solves from a guess and the readings path (in
    # the loop and from forward) pass certify as a runtime boolean: one signature of iterate_schur
    # (a constant True / False typed as a literal compiled the iteration once per value)
    from hexapod_model.kinematics.newton.iteration import iterate_schur

    hexa = hexapod("reference")
    rows = mixed_readings(hexa, seed=46)
    inside = np.all(np.isfinite(rows) & (rows >= hexa.stroke[:, 0]) & (rows <= hexa.stroke[:, 1]), axis=1)
    followed = [hexa.forward(x, check=False) for x in rows[inside][:40]]  # the readings path from Python
    warm = hexa.forward_batch(rows, warm=True)  # each row from the last converged: the plain solve from a guess
    hexa.forward_batch(rows, hexa.forward(rows[inside][0]))
    if not iterate_schur.signatures:  # its callers came from numba's cache: nothing compiled in this process
        pytest.skip("the compiled loops were loaded from numba's cache; run with an empty NUMBA_CACHE_DIR")
    assert len(iterate_schur.signatures) == 1
    assert any(s.converged and s.iterations > 10 for s in followed) and "converged" in list(warm.status)
