"""``hexapod sweep`` over sensor placements: its ranking is ``rank_placements``' for the same candidates."""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path

import pytest

import hexapod_model as hm
from hexapod_model.analysis.placement import rank_placements
from hexapod_model.cli.main import main
from hexapod_model.description.sensors import Inclinometer
from hexapod_model.studies.sweep import run_sweep
from hexapod_model.studies.sweep_spec import apply_parameters, load_spec

pytest.importorskip("distributed", reason="pip install -e '.[sweep]'")

ROOT = Path(__file__).resolve().parents[2]
LEG_SPEC = """\
base = "reference7"
[placement]
grid = 2
half_width = 0.02
workspace = false
[parameters]
measuring_base_y = [0.0, 0.1]
measuring_platform_x = [-0.15, 0.15]
"""


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_a_sweep_of_seventh_leg_anchors_ranks_them_as_rank_placements(tmp_path):
    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(LEG_SPEC)
    spec = load_spec(spec_path)
    result = run_sweep(spec, tmp_path / "out", workers=1)  # a LocalCluster of one process
    ref7 = hm.get_preset("reference7")
    (leg7,) = ref7.measuring_legs
    values = spec.candidates()
    candidates = tuple(
        dataclasses.replace(
            leg7,
            base_anchor=(leg7.base_anchor[0], v["measuring_base_y"], leg7.base_anchor[2]),
            platform_anchor=(v["measuring_platform_x"], *leg7.platform_anchor[1:]),
        )
        for v in values
    )
    expected = rank_placements(dataclasses.replace(ref7, measuring_legs=()), candidates, half_width=0.02, grid=2)
    ranked = result["ranked"]
    ids = [r["id"] for r in result["rows"]]
    assert [ids.index(r["id"]) for r in ranked] == [s.index for s in expected]
    # the same function on the same geometry, read back exactly from the candidate's file: the same floats
    assert [r["placement_worst_m"] for r in ranked] == [s.worst for s in expected]
    assert [r["placement_points_inside"] for r in ranked] == [s.inside for s in expected] == [4] * 4
    table = _rows(tmp_path / "out" / "placement.csv")
    assert [int(r["placement_rank"]) for r in table] == [1, 2, 3, 4]
    assert [r["id"] for r in table] == [r["id"] for r in ranked]
    assert [float(r["placement_worst_m"]) for r in table] == [s.worst for s in expected]
    swept = _rows(tmp_path / "out" / "sweep.csv")
    assert {r["id"]: int(r["placement_rank"]) for r in swept} == {r["id"]: int(r["placement_rank"]) for r in table}
    assert all(r["volume_m3"] == "nan" for r in swept)  # workspace = false: not computed


TILT_SPEC = """\
base = "reference_tilt"
[placement]
grid = 2
half_width = 0.02
workspace = false
[parameters]
inclinometer_roll_deg = [0.0, 30.0, 90.0]
inclinometer_pitch_deg = [0.0, 30.0]
"""


def test_the_cli_sweeps_inclinometer_mountings_ranks_them_and_names_an_invalid_one(tmp_path, capsys):
    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(TILT_SPEC)
    assert main(["sweep", str(spec_path), "--out", str(tmp_path / "out"), "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "placement: best" in out and "worst_um" in out and not (tmp_path / "out" / "pareto.png").exists()
    rows = _rows(tmp_path / "out" / "sweep.csv")
    vertical = [r for r in rows if (r["inclinometer_roll_deg"], r["inclinometer_pitch_deg"]) == ("90.0", "0.0")]
    assert vertical[0]["status"] == "invalid" and "y axis rises 90 deg" in vertical[0]["reason"]
    ok = [r for r in rows if r["status"] == "ok"]
    tilt = hm.get_preset("reference_tilt")
    candidates = tuple(
        Inclinometer(
            (math.radians(float(r["inclinometer_roll_deg"])), math.radians(float(r["inclinometer_pitch_deg"])), 0.0)
        )
        for r in ok
    )
    expected = rank_placements(dataclasses.replace(tilt, inclinometer=None), candidates, half_width=0.02, grid=2)
    table = _rows(tmp_path / "out" / "placement.csv")
    assert [r["id"] for r in table] == [ok[s.index]["id"] for s in expected]
    assert [float(r["placement_worst_m"]) for r in table] == [s.worst for s in expected]


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ('base = "reference"\n[parameters]\nmeasuring_base_x = [0.2]\n', "no measuring leg to move"),
        ('base = "reference7"\n[parameters]\ninclinometer_yaw_deg = [10.0]\n', "declares no inclinometer"),
        ('base = "reference_tilt"\n[parameters]\ninclinometer_pitch_deg = [100.0]\n', "beyond +-90 deg"),
        ('base = "reference"\n[placement]\n[parameters]\nhome_height = [0.4]\n', "declares no measuring leg or"),
        ('base = "reference7"\n[placement]\ngrid = 1\n[parameters]\nhome_height = [0.4]\n', "placement.grid"),
        ('base = "reference7"\n[placement]\nsize = 1\n[parameters]\nhome_height = [0.4]\n', "placement.size"),
        ('base = "reference7"\n[placement]\nworkspace = 1\n[parameters]\nhome_height = [0.4]\n', "true or false"),
        ('base = "reference7"\n[placement]\nhalf_width = 50\n[parameters]\nhome_height = [0.4]\n', "half_width"),
    ],
)
def test_placement_spec_errors_name_the_value(tmp_path, capsys, text, named):
    spec = tmp_path / "spec.toml"
    spec.write_text(text)
    assert main(["sweep", str(spec), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert named in err and len(err.splitlines()) == 1 and "Traceback" not in err


def test_sensor_parameters_move_only_the_last_measuring_leg_and_the_inclinometer():
    ref7 = hm.get_preset("reference7")
    g = apply_parameters(ref7, {"measuring_platform_y": 0.05, "home_height": 0.41}, "moved")
    assert g.measuring_legs[0].platform_anchor == (ref7.measuring_legs[0].platform_anchor[0], 0.05, 0.0)
    assert g.measuring_legs[0].base_anchor == ref7.measuring_legs[0].base_anchor and g.home_height == 0.41
    tilt = apply_parameters(
        hm.get_preset("reference_tilt"), {"inclinometer_yaw_deg": 30.0, "inclinometer_sigma": 1e-5}, "t"
    )
    assert tilt.inclinometer == Inclinometer((0.0, 0.0, math.radians(30.0)), 1e-5)


def test_the_example_placement_spec_reads():
    spec = load_spec(ROOT / "docs" / "examples" / "placement_sweep.toml")
    assert spec.placement is not None and not spec.placement.workspace and len(spec.candidates()) == 6
