"""``hexapod calibrate`` and ``hexapod reproduce --scenario geometric-errors`` through ``main(argv)``."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.cli.main import main

FAST = ["--folds", "2", "--hold", "*_axis.*"]  # 54 unknowns: 20 training poses are enough


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """One simulated run: its files, JSON and output."""
    out = tmp_path_factory.mktemp("cal")
    args = ["calibrate", "reference", "--simulate", "--poses", "40", "--seed", "3", *FAST]
    args += ["-o", str(out / "cal.toml"), "--json", str(out / "cal.json"), "--report", str(out / "rep")]
    assert main(args) == 0
    return out


def test_simulate_writes_geometry_json_report_and_figures(simulated):
    report = json.loads((simulated / "cal.json").read_text())
    for key in ("before", "after", "true_geometry"):
        assert set(report[key]) >= {"translation_mean_mm", "translation_std_mm", "translation_max_mm"}
        assert set(report[key]) >= {"rotation_mean_deg", "rotation_std_deg", "rotation_max_deg"}
    geom = hm.load_geometry(simulated / "cal.toml")
    assert geom.name == "reference_calibrated" and any(leg.encoder_zero != 0 for leg in geom.legs)
    ps = {p["name"]: p for p in report["parameters"]}
    assert geom.legs[2].encoder_zero == pytest.approx(ps["leg3.encoder_zero_m"]["identified"], abs=1e-15)
    names = sorted(p.name for p in (simulated / "rep").glob("*.png"))
    assert names == ["calibration_errors.png", "calibration_parameters.png", "calibration_singular_values.png"]
    assert all((simulated / "rep" / n).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for n in names)
    assert "held at nominal" in (simulated / "rep" / "report.txt").read_text()


def test_calibrate_from_a_measured_csv(simulated, tmp_path, capsys):
    data = simulated / "rep" / "simulated_measured.csv"
    args = ["calibrate", "reference", str(data), *FAST, "--seed", "3"]  # the same folds as the simulation
    args += ["-o", str(tmp_path / "c.toml"), "--json", str(tmp_path / "j")]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "before: nominal, frames fitted" in out and "after: calibrated" in out
    first, second = (json.loads(p.read_text()) for p in (simulated / "cal.json", tmp_path / "j"))
    assert first["after"] == pytest.approx(second["after"], rel=1e-6)  # the same data gives the same result
    assert "true_geometry" not in second


def test_a_calibration_no_better_than_nominal_is_not_written_unless_forced(tmp_path, capsys):
    """docs/examples/measured.csv: the held-out error rises 0.4731 -> 0.5029 mm; the file was
    written with exit 0."""
    data = Path(__file__).resolve().parents[2] / "docs" / "examples" / "measured.csv"
    out, js = tmp_path / "c.toml", tmp_path / "c.json"
    assert main(["calibrate", "reference", str(data), "-o", str(out), "--json", str(js)]) == 1
    assert not out.exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not written" in err[0] and "0.4731 mm (nominal) -> 0.5029 mm (calibrated)" in err[0]
    decision = json.loads(js.read_text())["decision"]
    assert decision["better_than_nominal"] is False and decision["written"] is False
    assert decision["held_out_translation_mean_mm"]["calibrated"] > decision["held_out_translation_mean_mm"]["nominal"]
    assert main(["calibrate", "reference", str(data), "-o", str(out), "--json", str(js), "--force"]) == 0
    assert hm.load_geometry(out).name == "reference_calibrated"
    assert json.loads(js.read_text())["decision"]["written"] is True


def test_a_calibration_better_than_nominal_says_so(simulated):
    decision = json.loads((simulated / "cal.json").read_text())["decision"]
    assert decision["better_than_nominal"] is True and decision["written"] is True
    figures = decision["held_out_translation_mean_mm"]
    assert figures["nominal"] - figures["calibrated"] > decision["uncertainty_mm"] > 0


def test_plan_writes_reachable_poses(tmp_path, capsys):
    out = tmp_path / "poses.csv"
    assert main(["calibrate", "reference", "--plan", "27", "--candidates", "120", "-o", str(out)]) == 0
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 27 and {"x", "qw", "roll", "l1", "l6"} <= set(rows[0])
    hexa = hm.Hexapod.from_preset("reference")
    for row in rows[:5]:
        T = hexa.forward([float(row[f"l{i}"]) for i in range(1, 7)]).pose
        assert np.allclose(T[:3, 3], [float(row[c]) for c in "xyz"], atol=1e-9)
    assert "chosen from" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args, words",
    [
        (["calibrate", "reference"], ["exactly one of"]),
        (["calibrate", "reference", "x.csv", "--simulate"], ["exactly one of"]),
        (["calibrate", "reference", "--plan", "30"], ["-o poses.csv"]),
        (["calibrate", "reference", "--simulate", "-o", "out.json"], [".toml"]),
        (["calibrate", "reference", "missing.csv"], ["missing.csv"]),
        (["calibrate", "spherical", "--simulate"], ["cardan"]),
        (["calibrate", "reference", "--simulate", "--poses", "10"], ["need at least 26 measured poses"]),
        (["calibrate", "reference", "--simulate", "--hold", "nothing"], ["matches no parameter"]),
        (["calibrate", "reference", "--plan", "5", "-o", "p.csv"], ["need at least 26 poses"]),
    ],
)
def test_bad_input_is_one_clear_line(args, words, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert all(w in err for w in words), err


def test_an_outlier_row_of_a_csv_is_named(simulated, tmp_path, capsys):
    lines = (simulated / "rep" / "simulated_measured.csv").read_text().splitlines()
    cells = lines[10].split(",")
    cells[6] = repr(float(cells[6]) + 0.005)  # x of line 11 off by 5 mm
    lines[10] = ",".join(cells)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    assert main(["calibrate", "reference", str(bad), *FAST]) == 2
    err = capsys.readouterr().err
    assert "line 11" in err and "outlier" in err and " mm" in err


def test_output_never_overwrites_the_input(simulated, capsys):
    data = simulated / "rep" / "simulated_measured.csv"
    before = data.read_bytes()
    assert main(["calibrate", "reference", str(data), "--json", str(data)]) == 2
    assert data.read_bytes() == before and "is also an input" in capsys.readouterr().err


def test_reproduce_geometric_errors_scenario(tmp_path, capsys):
    out = tmp_path / "t1.json"
    args = ["reproduce", "--scenario", "geometric-errors", "--poses", "30", "--calibration-poses", "40"]
    assert main([*args, "--json", str(out)]) == 0
    report = json.loads(out.read_text())
    assert {"spherical", "nominal", "calibrated", "reading"} <= set(report) and report["poses"] == 30
    text = capsys.readouterr().out
    assert "reading of the paper" in text and "Calibrated" in text
    assert main(["reproduce", "--scenario", "geometric-errors", "--data", str(Path("x.csv"))]) == 2


def test_a_urdf_is_a_nominal_too(tmp_path):
    urdf = hm.write_urdf(hm.get_preset("reference"), tmp_path / "ref.urdf")
    out = tmp_path / "p.csv"
    assert main(["calibrate", str(urdf), "--plan", "27", "--candidates", "60", "-o", str(out)]) == 0
    assert len(out.read_text().splitlines()) == 28
