"""Warm direct kinematics with the Krawczyk proof: ``Hexapod.prove_step`` and the near-singular rule."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm

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
