"""``hexapod calibrate`` on a hexapod with extra sensors: the CSV's extra columns, the report with and without them."""

from __future__ import annotations

import csv
import json
import math

import pytest

import hexapod_model as hm
from hexapod_model.cli.main import main
from hexapod_model.io.calibration_csv import load_poses

FAST = ["--folds", "2", "--seed", "2"]


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """reference_tilt simulated: its JSON, report folder and output."""
    out = tmp_path_factory.mktemp("tilt")
    args = ["calibrate", "reference_tilt", "--simulate", "--poses", "60", *FAST]
    args += ["-o", str(out / "cal.toml"), "--json", str(out / "cal.json"), "--report", str(out / "rep")]
    assert main(args) == 0
    return out


def _finite(stats: dict) -> bool:
    return all(isinstance(v, float) and math.isfinite(v) for v in stats.values())


def test_the_json_gives_the_held_out_error_with_and_without_the_extra_sensors(simulated):
    report = json.loads((simulated / "cal.json").read_text())
    assert report["extra_sensors"]["readings"] == ["tilt_x", "tilt_y"] and report["extra_sensors"]["used"]
    assert math.isfinite(report["extra_sensors"]["residual_rms_sigmas"])
    for key in ("before", "after", "after_without_extra_sensors"):
        assert {"translation_mean_mm", "rotation_mean_deg"} <= set(report[key]) and _finite(report[key])
    names = {p["name"]: p for p in report["parameters"]}
    assert names["inclinometer.mount.x_rad"]["identifiable"]
    geom = hm.load_geometry(simulated / "cal.toml")
    assert geom.inclinometer is not None and geom.inclinometer.rpy != (0.0, 0.0, 0.0)  # written identified
    text = (simulated / "rep" / "report.txt").read_text()
    assert "after: calibrated, extra readings" in text and "after: calibrated, six legs only" in text


def test_the_csv_carries_the_extra_readings_and_six_columns_still_work(simulated, tmp_path, capsys):
    data = simulated / "rep" / "simulated_measured.csv"
    with open(data) as fh:
        rows = list(csv.reader(fh))
    assert rows[0][:9] == ["l1", "l2", "l3", "l4", "l5", "l6", "tilt_x", "tilt_y", "x"]
    assert load_poses(data, hm.get_preset("reference_tilt")).extra == 2
    assert load_poses(data).extra == 0  # a six-leg hexapod reads its six columns only
    args = ["calibrate", "reference_tilt", str(data), *FAST, "--json", str(tmp_path / "j.json")]
    assert main(args) == 0
    first, again = (json.loads(p.read_text()) for p in (simulated / "cal.json", tmp_path / "j.json"))
    assert again["after_without_extra_sensors"] == pytest.approx(first["after_without_extra_sensors"], rel=1e-6)
    six = tmp_path / "six.csv"
    with open(six, "w", newline="") as fh:
        csv.writer(fh).writerows([r[:6] + r[8:] for r in rows])
    assert main(["calibrate", "reference_tilt", str(six), *FAST, "--json", str(tmp_path / "s.json")]) == 0
    report = json.loads((tmp_path / "s.json").read_text())
    assert not report["extra_sensors"]["used"] and "after_without_extra_sensors" not in report
    assert report["after"] == pytest.approx(first["after_without_extra_sensors"], rel=1e-6)  # the six-leg fit
    assert "no readings in the data" in capsys.readouterr().out


def test_some_but_not_all_extra_columns_is_one_line(simulated, tmp_path):
    rows = list(csv.reader(open(simulated / "rep" / "simulated_measured.csv")))
    bad = tmp_path / "bad.csv"
    with open(bad, "w", newline="") as fh:
        csv.writer(fh).writerows([r[:7] + r[8:] for r in rows])  # tilt_x without tilt_y
    with pytest.raises(hm.InputError, match="tilt_x, tilt_y or none.*missing tilt_y"):
        load_poses(bad, hm.get_preset("reference_tilt"))
    assert main(["calibrate", "reference_tilt", str(bad)]) == 2
