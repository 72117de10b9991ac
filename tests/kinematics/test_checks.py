"""Misuse of the Python API raises one clear InputError; hybrid sets and singular layouts are refused."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.exceptions import CompileWarning
from hexapod_model.lie import rotation_angle

from ..conftest import PRESET_NAMES, hexapod

READINGS = [0.01, 0.0, -0.02, 0.0, 0.015, 0.0]


def _far_pose():
    T = np.eye(4)
    T[0, 3] = 1e308  # overflows in the residual: must not come back as home or as a solver status
    return T


def _other_solution():
    return hexapod("spherical").forward(np.zeros(6))


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda h: h.forward(READINGS, guess=np.zeros(h.nq)), ["guess", "quaternion", "norm 0"]),
        (lambda h: h.forward(READINGS, guess=_other_solution()), ["guess", "another hexapod", "nq = 43"]),
        (lambda h: h.forward(READINGS, guess="home"), ["guess", "'home'", "Solution"]),
        (lambda h: h.forward(READINGS, guess=np.ones(5)), ["guess", "shape (5,)"]),
        (lambda h: h.solve({"platform_joint": "x"}), ["pose", "'x'", "4x4"]),
        (lambda h: h.forward(READINGS, tol="1e-9"), ["tol", "'1e-9'", "(0, 1e-06]"]),
        (lambda h: h.forward(READINGS, tol=-1), ["tol", "-1", "(0, 1e-06]"]),
        (lambda h: h.forward(READINGS, tol=float("nan")), ["tol", "nan"]),
        (lambda h: h.forward(READINGS, tol=0.5), ["tol", "0.5", "(0, 1e-06]"]),
        (lambda h: h.inverse(h.home_pose, tol=True), ["tol", "True"]),
        (lambda h: h.forward(READINGS, max_iter=None), ["max_iter", "None"]),
        (lambda h: h.forward(READINGS, max_iter=2.5), ["max_iter", "2.5"]),
        (lambda h: h.forward(READINGS, max_iter=-1), ["max_iter", "-1"]),
        (lambda h: h.forward([[0.01, 0.0, -0.02], [0.0, 0.015, 0.0]]), ["lengths", "shape (2, 3)"]),
        (lambda h: h.forward(np.array(READINGS) + 1e-3j), ["lengths", "complex"]),
        (lambda h: h.forward([complex(v) for v in READINGS]), ["lengths", "6 real numbers"]),
        (lambda h: h.forward([str(v) for v in READINGS]), ["lengths", "6 real numbers"]),
        (lambda h: h.forward([True] * 6), ["lengths", "bool"]),
        (lambda h: h.solve({"leg1_prismatic": 0.01j}), ["leg1_prismatic", "complex"]),
        (lambda h: h.inverse(np.eye(4) + 0j), ["pose", "complex"]),
        (lambda h: h.inverse(_far_pose()), ["pose", "1e+06 m"]),
    ],
)
def test_api_misuse_raises_one_clear_input_error(call, words):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning / RuntimeWarning on the way
        warnings.simplefilter("ignore", CompileWarning)  # but a first compilation's announcement (a fresh cache)
        with pytest.raises(hm.InputError) as exc:
            call(hexapod("reference"))
    text = str(exc.value)
    assert "\n" not in text and all(w in text for w in words), text


def test_error_messages_print_arrays_on_one_line():
    with pytest.raises(hm.InputError) as exc:
        hexapod("reference").inverse(np.full((4, 4), np.nan))
    assert "\n" not in str(exc.value) and "finite" in str(exc.value)


def test_valid_numbers_of_any_real_type_are_accepted():
    hexa = hexapod("reference")
    ref = hexa.forward(READINGS)
    for lengths in (list(READINGS), tuple(READINGS), np.array(READINGS, dtype=np.float32).astype(float)):
        sol = hexa.forward(lengths, tol=np.float64(1e-12), max_iter=np.int64(20))
        np.testing.assert_allclose(sol.pose, ref.pose, atol=1e-12)
    assert hexa.forward(np.zeros(6, dtype=int), tol=1e-12).converged  # integer readings are real numbers
    assert hexa.forward(READINGS, guess=list(ref.q)).iterations == 0  # a configuration as a list
    assert hexa.forward(READINGS, max_iter=0, check=False).status == "max_iterations"


@pytest.mark.parametrize(
    "held, free",
    [
        ({f"leg{i}_prismatic": 0.01 * (i % 3 - 1) for i in range(1, 6)}, 1),  # five legs: a one-parameter family
        ({"leg1_prismatic": 0.01}, 5),
    ],
)
def test_under_determined_hybrid_solve_is_an_error(held, free):
    with pytest.raises(hm.InputError) as exc:
        hexapod("reference").solve(held)
    text = str(exc.value)
    assert f"under-determined: {free} free direction" in text and "\n" not in text, text


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_determined_and_consistent_over_determined_hybrid_sets_solve(name):
    hexa = hexapod(name)
    T = box_poses(hexa.home_pose, 1, seed=3)[0]
    truth = hexa.inverse(T)
    held = dict(zip(hexa.prismatic_names, truth.lengths))
    sol = hexa.solve(held)  # the six readings: direct kinematics
    assert np.linalg.norm(sol.pose[:3, 3] - T[:3, 3]) < 1e-9 and rotation_angle(sol.pose[:3, :3], T[:3, :3]) < 1e-9
    # add a passive joint at its true value: 37 held values, consistent, still converges to the same pose
    passive = next(n for n in hexa.joint_names if n not in held and n != "platform_joint")
    iq = hexa.model.joints[hexa.model.getJointId(passive)].idx_q
    sol = hexa.solve({**held, passive: float(truth.q[iq])})
    assert sol.converged and np.linalg.norm(sol.pose[:3, 3] - T[:3, 3]) < 1e-9
    # five readings and one Cardan angle: determined, the README's example
    five = dict(list(held.items())[:5])
    sol = hexa.solve({**five, passive: float(truth.q[iq])}, guess=truth)
    assert sol.converged and np.linalg.norm(sol.pose[:3, 3] - T[:3, 3]) < 1e-9


def _degenerate(kind: str) -> hm.HexapodGeometry:
    d = hm.get_preset("reference").to_dict()
    for i, leg in enumerate(d["legs"]):
        leg.pop("base_axis", None)
        leg.pop("platform_axis", None)
        if kind == "vertical":
            leg["platform_anchor"] = [leg["base_anchor"][0], leg["base_anchor"][1], 0.0]
        elif kind == "collinear":
            leg["base_anchor"] = [0.05 * i - 0.12, 0.0, 0.0]
        else:  # every leg on the same two points
            leg["base_anchor"], leg["platform_anchor"] = [0.2, 0.0, 0.0], [0.1, 0.05, 0.0]
    d["name"] = kind
    return hm.geometry_from_dict(d)


@pytest.mark.parametrize("kind", ["vertical", "collinear", "coincident"])
def test_layout_singular_at_home_is_refused(kind):
    with pytest.raises(hm.GeometryError) as exc:
        hm.Hexapod.from_geometry(_degenerate(kind))
    text = str(exc.value)
    assert "home condition number" in text and "exceeds the limit 1e+06" in text and "\n" not in text, text


def test_presets_report_their_home_condition_number():
    for name in PRESET_NAMES:
        assert 1 < hexapod(name).home_condition_number < 100
