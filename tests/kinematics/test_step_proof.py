"""Warm direct kinematics with the Krawczyk proof: ``Hexapod.prove_step`` and the near-singular rule."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.lie import rpy_to_matrix

from ..conftest import limits_only as hexapod  # the cones would rule out the fold poses these cases are about

DATA = Path(__file__).parents[1] / "data"


@pytest.mark.parametrize("compiled", [True, False])
def test_a_warm_step_to_another_assembly_near_a_fold_is_not_converged(compiled):
    # tests/data/three_six_warm_wrong.json: from a guess 2 mm / 1 deg from the truth, the warm solve
    # returned converged (flagged near_singular) at another assembly 1.1 mm / 1.1 deg away
    hexa = hexapod("3-6") if compiled else hm.Hexapod.from_preset("3-6", compiled=False, check_body=False)
    case = json.loads((DATA / "three_six_warm_wrong.json").read_text())
    guess = hexa.inverse(np.array(case["guess_pose"]))
    sol = hexa.forward(np.array(case["readings_m"]), guess, check=False)
    truth = np.array(case["true_pose"])
    right = np.linalg.norm(sol.pose[:3, 3] - truth[:3, 3]) < 1e-9
    assert right or not sol.converged
    if not sol.converged:
        assert sol.proof is not None and not sol.proof.proven and "Krawczyk" in sol.message
    with pytest.raises(hm.AssemblyError):
        hexa.forward(np.array(case["readings_m"]), guess)


@pytest.mark.parametrize("name", ["reference", "3-6"])
def test_prove_step_attaches_the_proof_of_a_small_warm_step(name):
    hexa = hexapod(name)
    T = hexa.home_pose.copy()
    T[:3, 3] += [0.01, -0.005, 0.003]
    start = hexa.inverse(T)
    T[:3, 3] += [2e-4, 0.0, -1e-4]
    readings = hexa.inverse(T).lengths
    sol = hexa.forward(readings, start)
    assert sol.proof is not None and sol.proof.proven  # every warm converged result carries its proof
    assert hexa.forward(readings).proof is None  # a cold one its certificate's checks
    proven = hexa.prove_step(start, sol)
    assert proven.converged and proven.proof == sol.proof  # the same test on the same step
    assert proven.proof.subdivisions >= 1 and proven.proof.position_m < 1e-6
    np.testing.assert_array_equal(proven.pose, sol.pose)  # the proof changes no number


@pytest.mark.parametrize("name", ["reference", "intersecting", "spherical", "guideway", "3-6"])
def test_every_warm_converged_result_carries_its_proof(name):
    """Along trajectory A at 1 kHz every warm converged step is proven; prove=False skips the proof."""
    from hexapod_model.analysis.trajectories import trajectory_poses

    hexa = hexapod(name)
    _, poses = trajectory_poses("A", hexa.home_pose, hexa.base_radius / 50.0, 1000.0)
    ik = hexa.inverse_batch(poses[:400:4])  # 4 ms steps
    readings = ik.lengths[np.asarray(ik.converged, dtype=bool)]
    sol, converged = hexa.forward(readings[0], check=False), 0
    for x in readings[1:]:
        nxt = hexa.forward(x, sol, check=False)
        assert nxt.status != "converged" or (nxt.proof is not None and nxt.proof.proven), nxt.message
        assert nxt.status != "uncertified" or not nxt.proof.proven
        converged += nxt.converged
        bare = hexa.forward(x, sol, check=False, prove=False)
        assert bare.proof is None and bare.status == nxt.status or nxt.status == "uncertified"
        np.testing.assert_array_equal(bare.pose, nxt.pose)  # the proof changes no number
        sol = nxt if nxt.closed else sol
    assert converged >= 0.9 * (len(readings) - 1)


def test_a_long_warm_step_is_proven_in_steps():
    """A guess 3 cm and 5 deg away: one Krawczyk test cannot prove the step; proven steps along the path can."""
    hexa = hexapod("reference")
    T = hexa.home_pose.copy()
    T[:3, 3] += [0.02, -0.01, 0.01]
    guess = hexa.inverse(T)
    T[:3, 3] += [0.03, 0.0, -0.01]
    T[:3, :3] = rpy_to_matrix(0.0, 0.0, np.radians(5.0))
    truth = hexa.inverse(T)
    one = hexa.engine.prover.prove(guess.q, hexa.forward(truth.lengths, guess, prove=False).q)
    sol = hexa.forward(truth.lengths, guess)
    assert not one.proven  # the step alone is too long for one test (or its halves)
    assert sol.converged and sol.proof.proven and sol.proof.subdivisions > 1
    assert np.linalg.norm(sol.pose[:3, 3] - T[:3, 3]) < 1e-9
    assert sol.proof.position_m < 1e-6


@pytest.mark.parametrize("name", ["reference", "intersecting"])
def test_a_far_guess_is_followed_in_proven_steps_sized_from_their_proofs(name):
    """A guess about 0.1 m away is proven in steps; each step's length comes from the sub-intervals
    of the proof before, so few steps are tried longer than a proof reaches (each such costs 32
    failed tests): about 14 tests a step on these presets, where doubling every proven step spent about 50."""
    from hexapod_model.analysis.trajectories import box_poses

    hexa = hexapod(name)
    sols = [s for s in (hexa.inverse(T, check=False) for T in box_poses(hexa.home_pose, 6, seed=12)) if s.converged]
    for before, after in zip(sols, sols[1:]):
        sol = hexa.forward(after.lengths, before, check=False)
        assert sol.converged and sol.proof.proven and sol.proof.subdivisions > 10, sol.proof
        assert sol.proof.tests < 20 * sol.proof.subdivisions, sol.proof
        np.testing.assert_allclose(sol.pose, after.pose, atol=1e-9)  # the plate's own assembly
