"""The simulated calibration study, the honest Table 1 scenario and Fig. 7's conditioning comparison."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.conditioning import condition_numbers
from hexapod_model.calibration.frames import Noise, error_stats, pose_errors, predict
from hexapod_model.calibration.parameters import ParameterSet
from hexapod_model.studies.calibrate import Errors, run_calibration, simulate
from hexapod_model.studies.calibrate_report import format_report, report_json
from hexapod_model.studies.reproduce import simulate as simulate_reproduce
from hexapod_model.studies.table1 import format_table1, run_table1


def test_simulated_truth_stays_within_the_documented_errors():
    nominal = hm.get_preset("reference")
    sim = simulate(nominal, 12, seed=3)
    ps = ParameterSet(nominal)
    delta = ps.delta_of(sim.true_geometry)
    errors = Errors()
    bound = {"centre": errors.centre_m, "axis": errors.axis_rad, "offset": errors.offset_m, "zero": 1e-3}
    for k, p in enumerate(ps.parameters):
        limit = next(v for key, v in bound.items() if key in p.kind)
        assert abs(delta[k]) <= limit * (1 + 1e-6), p.name
    assert np.abs(delta).max() > 0.5 * 1e-3  # and they are not all tiny
    rot = np.degrees(np.arccos((np.trace(sim.measuring_frame[:3, :3]) - 1) / 2))
    assert 0 < rot <= 30 and np.all(np.abs(sim.measuring_frame[:3, 3]) <= 0.5)
    # measured = frames around the true poses, plus the stated noise only
    err = pose_errors(predict(sim.measuring_frame, sim.true_poses, sim.marker_frame), sim.data.measured)
    assert 0.05 < np.mean(err[0]) < 0.3  # mm: 0.1 mm per coordinate


def test_small_study_report_and_json():
    sim = simulate(hm.get_preset("reference"), 40, seed=1)
    result = run_calibration(sim.nominal, sim.data, folds=2, seed=1, simulation=sim, hold=("*_axis.*",))
    report = report_json(result)
    keys = {"translation_mean_mm", "translation_std_mm", "translation_max_mm"}
    keys |= {"rotation_mean_deg", "rotation_std_deg", "rotation_max_deg"}
    assert {"before", "after", "true_geometry", "measuring_frame", "marker_frame", "parameters"} <= set(report)
    assert all(set(report[k]) == keys for k in ("before", "after", "true_geometry"))
    assert np.array(report["measuring_frame"]).shape == (4, 4) and np.array(report["marker_frame"]).shape == (4, 4)
    params = report["parameters"]
    fields = {"name", "nominal", "identified", "sigma", "identifiable"}
    assert len(params) == 78 and all(set(p) == fields for p in params)
    held = [p for p in params if not p["identifiable"]]
    assert held and all(p["sigma"] is None and p["identified"] == p["nominal"] for p in held)
    assert report["after"]["translation_mean_mm"] < report["before"]["translation_mean_mm"]
    assert report["truth"]["within_3_sigma"] == report["truth"]["identifiable"]
    text = format_report(result, Noise(), details=True)
    assert "held at nominal" in text and "true geometry (same data)" in text and "leg6.encoder_zero_m" in text


@pytest.mark.slow
def test_the_simulated_study_meets_its_targets():
    """Reference preset, 100 poses (docs/calibration.md quotes benchmarks/calibration_study.py)."""
    sim = simulate(hm.get_preset("reference"), 100, seed=0)
    result = run_calibration(sim.nominal, sim.data, simulation=sim)
    after, true = error_stats(result.validation.after), error_stats(result.true_errors)
    assert after["translation_mean_mm"] <= 1.5 * true["translation_mean_mm"]
    assert after["rotation_mean_deg"] <= 1.5 * true["rotation_mean_deg"]
    ident = result.identification
    z = (ident.delta - result.truth) / ident.sigma
    assert np.all(np.abs(z[ident.identifiable]) <= 3.0)
    nominal_true_frames = pose_errors(predict(sim.measuring_frame, _nominal_poses(sim), sim.marker_frame),
                                      sim.data.measured)  # fmt: skip
    assert np.mean(nominal_true_frames[0]) > 1.0  # mm: the errors matter before calibration
    assert np.mean(result.validation.before[0]) > 2 * after["translation_mean_mm"]


def _nominal_poses(sim):
    hexa = hm.Hexapod.from_geometry(sim.nominal)
    return np.array([hexa.forward(r).pose for r in sim.data.readings])


def test_table1_with_geometric_errors_orders_the_models():
    report = run_table1(hm.get_preset("reference"), test_poses=60, calibration_poses=40, seed=2)
    t = {m: report[m]["translation_mean_mm"] for m in ("spherical", "nominal", "calibrated")}
    assert t["calibrated"] < t["nominal"] < t["spherical"]
    assert report["calibrated"]["translation_mean_mm"] < 0.3  # mm: near the 0.1 mm/axis measurement noise
    text = format_table1(report)
    assert "0.6205" in text and "3.1684" in text and "Calibrated" in text


def test_reduced_formulation_conditioning_is_row_scaling():
    hexa = hm.Hexapod.from_preset("reference")
    data = simulate_reproduce(hexa, 8, seed=4, encoder_noise=0.0)
    c = condition_numbers(hexa, data.readings)
    assert c["poses"] == 8 and c["gram_difference"] < 1e-10  # J9^T J9 = 2 J3^T J3
    assert c["si"]["full"] > c["si"]["reduced"]  # the paper's Fig. 7
    assert c["mm"]["full"] < c["mm"]["reduced"]  # the order reverses in millimetres
    same = c["rotation_rows_over_sqrt2"]
    assert abs(same["full"] - same["reduced"]) < 1e-8 * same["reduced"]  # same metric: same conditioning
