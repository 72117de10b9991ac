"""Readings within the noise of a fold of the 3-6 readings map are not ``converged``.

tests/data/three_six_near_fold.json: readings 0.01-2.4 mm from those of an in-limit pose at a
fold (a double root of the resultant). Cold, they came back ``converged``, "the only assembly
within the stroke and joint limits", 40-120 mm / 45-110 deg from that fold pose; readings a
fraction of a millimetre away have two more real roots next to the fold pose.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.kinematics.noise_assemblies import REACH, noise_assemblies
from hexapod_model.kinematics.three_six import ThreeSixFK
from hexapod_model.lie import pose_distance

from ..conftest import limits_only as hexapod  # the cones would rule out the fold poses these cases are about

CASES = Path(__file__).parents[1] / "data" / "three_six_near_fold.json"


@functools.cache
def _cases() -> list[dict]:
    return json.loads(CASES.read_text())["cases"]


@pytest.mark.parametrize("k", range(5))
def test_readings_near_a_fold_are_ambiguous_with_the_fold_assemblies_as_candidates(k):
    hexa, case = hexapod("3-6"), _cases()[k]
    readings, fold = np.array(case["readings_m"]), np.array(case["fold_pose"])
    sol = hexa.forward(readings, check=False)
    assert not sol.converged and sol.status == "ambiguous_assembly"
    gaps = [pose_distance(fold, T, hexa.base_radius) for T in sol.candidates]
    assert min(gaps) < 0.03 * hexa.base_radius  # an assembly next to the fold pose (6 mm; the result was 40+ mm away)


@pytest.mark.parametrize("k", range(5))
def test_the_assemblies_appear_within_the_reach_and_close_the_moved_readings(k):
    hexa, case = hexapod("3-6"), _cases()[k]
    fk = ThreeSixFK(hexa.geometry)
    readings = np.array(case["readings_m"])
    near = noise_assemblies(fk, readings)
    assert near
    reach = REACH * fk.length
    for s in near:
        moved = hexa.inverse(s.pose, check=False).lengths
        assert np.linalg.norm(moved - readings) <= reach * (1 + 1e-6)
    assert not noise_assemblies(fk, readings, reach=1e-9)  # not within a nanometre: the pair is complex


def test_readings_far_from_any_fold_have_no_noise_assemblies():
    hexa = hexapod("3-6")
    fk = ThreeSixFK(hexa.geometry)
    assert not noise_assemblies(fk, np.zeros(6))
    assert hexa.forward(np.full(6, 0.002)).converged


@pytest.mark.parametrize("k", range(5))
def test_readings_near_a_fold_are_not_converged_with_the_body_check_either(k):
    """With the preset's 45 deg ball-joint cones (the default), the fold poses lie beyond a cone: still no pose."""
    hexa = hm.Hexapod.from_preset("3-6", compiled=False)
    sol = hexa.forward(np.array(_cases()[k]["readings_m"]), check=False)
    assert not sol.converged and sol.status in ("ambiguous_assembly", "out_of_limits"), sol.status
