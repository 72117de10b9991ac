"""Readings within the noise of a fold of the 3-6 readings map are not ``converged``.

tests/data/three_six_near_fold.json: readings 0.01-2.4 mm from those of an in-limit pose at a
fold (a double root of the resultant). Cold, they came back ``converged``, "the only assembly
within the stroke and joint limits", 40-120 mm / 45-110 deg from that fold pose; readings a
fraction of a millimetre away have two more real roots next to the fold pose. Per reading the
five lie 0.8, 5, 17, 18 and 121 um from a fold: within the noise reach (6 sigma) of readings known
to 25 um; at the encoders' 1 um (the presets' ``encoder_sigma``) two of them are.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.kinematics.noise_assemblies import NOISE_SIGMAS, noise_assemblies, noise_reach
from hexapod_model.kinematics.three_six import ThreeSixFK
from hexapod_model.lie import pose_distance

from ..conftest import limits_only as hexapod  # the cones would rule out the fold poses these cases are about

CASES = Path(__file__).parents[1] / "data" / "three_six_near_fold.json"


@functools.cache
def _cases() -> list[dict]:
    return json.loads(CASES.read_text())["cases"]


NOISY = 25e-6  # m: a reading noise within whose 6 sigma all five cases lie


@functools.cache
def noisy() -> hm.Hexapod:
    """The 3-6 preset (stroke and joint limits only) whose readings are known to ``NOISY`` (m)."""
    geometry = dataclasses.replace(hm.get_preset("3-6"), encoder_sigma=NOISY)
    return hm.Hexapod.from_geometry(geometry, check_body=False)


@pytest.mark.parametrize("k", range(5))
def test_readings_near_a_fold_are_ambiguous_with_the_fold_assemblies_as_candidates(k):
    hexa, case = noisy(), _cases()[k]
    readings, fold = np.array(case["readings_m"]), np.array(case["fold_pose"])
    sol = hexa.forward(readings, check=False)
    assert not sol.converged and sol.status == "ambiguous_assembly"
    gaps = [pose_distance(fold, T, hexa.base_radius) for T in sol.candidates]
    assert min(gaps) < 0.03 * hexa.base_radius  # an assembly next to the fold pose (6 mm; the result was 40+ mm away)


@pytest.mark.parametrize("k", range(5))
def test_the_reach_is_k_sigma_of_the_geometrys_encoder_noise(k):
    """At the presets' 1 um a case is ambiguous exactly when a fold lies within 6 um of each reading;
    otherwise its one assembly within the limits is converged, the only one for its exact readings."""
    hexa, case = hexapod("3-6"), _cases()[k]
    readings = np.array(case["readings_m"])
    fk = ThreeSixFK(hexa.geometry)
    reach = noise_reach(hexa.geometry.encoder_sigma)
    assert reach == NOISE_SIGMAS * 1e-6
    sol = hexa.forward(readings, check=False)
    if noise_assemblies(fk, readings, reach):
        assert sol.status == "ambiguous_assembly"
    else:
        assert sol.converged and len(hexa.assemblies(readings).solutions) == 1
        assert noise_assemblies(fk, readings, noise_reach(NOISY))  # a noisier sensor would not know it


@pytest.mark.parametrize("k", range(5))
def test_the_assemblies_appear_within_the_reach_and_close_the_moved_readings(k):
    hexa, case = noisy(), _cases()[k]
    fk = ThreeSixFK(hexa.geometry)
    readings = np.array(case["readings_m"])
    reach = noise_reach(NOISY)
    near = noise_assemblies(fk, readings, reach)
    assert near
    for s in near:
        moved = hexa.inverse(s.pose, check=False).lengths
        assert np.max(np.abs(moved - readings)) <= reach * (1 + 1e-6)  # every reading within k sigma
    assert not noise_assemblies(fk, readings, 1e-9)  # not within a nanometre: the pair is complex


def test_the_readings_own_assemblies_next_to_a_pair_are_not_new(monkeypatch):
    """A pair whose readings are moved towards it finds the readings' own assemblies there too (moved with
    them): they are not new. At home the 3-6 resultant has triple roots, whose gap gradient is the
    rounding's (LAPACK's roots differ in their last bits between processors): on one machine's a
    pair at -0.47 was taken, and the own assemblies 0.18 rad from it came back as noise assemblies."""
    from hexapod_model.kinematics import noise_assemblies as module

    hexa = hexapod("3-6")
    fk = ThreeSixFK(hexa.geometry)
    own = fk.solve_all(np.zeros(6))
    z = np.array([0.5 * np.exp(1j * own[0].psi[0])])  # a complex root inside the circle at an own assembly's angle
    monkeypatch.setattr(module, "_gaps", lambda fk, lengths: (z, np.full((1, 6), 1e4)))  # steep: taken
    assert not noise_assemblies(fk, np.zeros(6), noise_reach(NOISY))


def test_readings_far_from_any_fold_have_no_noise_assemblies():
    hexa = hexapod("3-6")
    fk = ThreeSixFK(hexa.geometry)
    assert not noise_assemblies(fk, np.zeros(6), noise_reach(NOISY))
    assert hexa.forward(np.full(6, 0.002)).converged


@pytest.mark.parametrize("k", range(5))
def test_readings_near_a_fold_are_not_converged_with_the_body_check_either(k):
    """With the preset's 45 deg ball-joint cones (the default), the fold poses lie beyond a cone: still no pose."""
    hexa = hm.Hexapod.from_preset("3-6", compiled=False)
    sol = hexa.forward(np.array(_cases()[k]["readings_m"]), check=False)
    assert not sol.converged and sol.status in ("ambiguous_assembly", "out_of_limits"), sol.status


def test_a_declared_encoder_sigma_survives_the_geometry_file():
    """The noise reach reads ``encoder_sigma``: a 3-6 geometry saved with it and loaded gives the same answers
    (the field was written only for hexapods with redundant sensors)."""
    from hexapod_model.description.geometry import geometry_from_dict

    geometry = noisy().geometry
    assert geometry_from_dict(geometry.to_dict()).encoder_sigma == NOISY
    assert "encoder_sigma" not in hm.get_preset("3-6").to_dict()  # the default is left out, as before
