"""The ``hexapod`` CLI through ``main(argv)``: URDF generation, fk/ik files, bench."""

from __future__ import annotations

import csv
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.cli.main import main
from hexapod_model.lie import rpy_to_matrix

from ..conftest import PRESET_NAMES, hexapod, limits_only

ROOT = Path(__file__).resolve().parents[2]


def read_rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_urdf_default_and_presets(tmp_path, capsys):
    assert main(["urdf", "-o", str(tmp_path / "my.urdf")]) == 0
    assert (tmp_path / "my.urdf").read_text() == (ROOT / "urdf" / "reference.urdf").read_text()
    assert main(["urdf", "--preset", "3-6", "-o", str(tmp_path / "sensor.urdf")]) == 0
    assert 'type="3d"' in (tmp_path / "sensor.urdf").read_text()
    assert main(["urdf", "--list-presets"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [ln.split()[0] for ln in lines] == list(hm.PRESETS) and all(len(ln.split()) > 2 for ln in lines)


def test_urdf_takes_the_hexapod_as_every_command_does(tmp_path, capsys):
    assert main(["urdf", "3-6", "-o", str(tmp_path / "a.urdf")]) == 0
    assert main(["urdf", "--preset", "3-6", "-o", str(tmp_path / "b.urdf")]) == 0  # the option still works
    assert (tmp_path / "a.urdf").read_text() == (tmp_path / "b.urdf").read_text()
    (tmp_path / "mine.json").write_text(json.dumps({**hm.get_preset("intersecting").to_dict(), "name": "mine"}))
    assert main(["urdf", str(tmp_path / "mine.json"), "-o", str(tmp_path / "mine.urdf")]) == 0
    assert 'robot name="mine"' in (tmp_path / "mine.urdf").read_text()
    capsys.readouterr()
    assert main(["urdf", "3-6", "--preset", "reference"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "3-6" in err[0] and "--preset" in err[0], err
    assert main(["urdf", "referense"]) == 2
    assert "reference" in capsys.readouterr().err


def test_urdf_from_geometry_file(tmp_path, capsys):
    d = hm.get_preset("intersecting").to_dict()
    d["name"] = "mine"
    (tmp_path / "mine.json").write_text(json.dumps(d))
    assert main(["urdf", "--geometry", str(tmp_path / "mine.json"), "-o", str(tmp_path / "mine.urdf")]) == 0
    assert hm.Hexapod.from_urdf(tmp_path / "mine.urdf").forward(np.zeros(6)).converged
    d["legs"][0]["stroke"] = [0.1, 0.2]
    (tmp_path / "bad.json").write_text(json.dumps(d))
    assert main(["urdf", "--geometry", str(tmp_path / "bad.json")]) == 2
    assert "legs[0].stroke" in capsys.readouterr().err


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_fk_ik_files_round_trip(name, tmp_path):
    hexa = limits_only(name)  # the URDF file carries no cones: the kinematics alone
    poses = box_poses(hexa.home_pose, 20, seed=2)
    lengths = np.array([hexa.inverse(T).lengths for T in poses])
    inp = tmp_path / "lengths.csv"
    inp.write_text("l1,l2,l3,l4,l5,l6\n" + "\n".join(",".join(f"{v:.15g}" for v in row) for row in lengths) + "\n")
    urdf = tmp_path / "h.urdf"
    hm.write_urdf(hm.get_preset(name), urdf)
    # 3-6: every assembly is computed (the layout read off the URDF); rows that another assembly within
    # the limits fits about as near the previous pose are ambiguous_assembly, with no pose
    code = 1 if name == "3-6" else 0
    assert main(["fk", str(urdf), str(inp), "-o", str(tmp_path / "poses.csv"), "--no-body-check"]) == code
    rows = read_rows(tmp_path / "poses.csv")
    assert list(rows[0]) == [
        "x",
        "y",
        "z",
        "qx",
        "qy",
        "qz",
        "qw",
        "roll",
        "pitch",
        "yaw",
        "status",
        "iterations",
        "residual",
        "message",
    ]
    ok = np.array([r["status"] == "ok" for r in rows])
    assert ok.all() or (name == "3-6" and {r["status"] for r in rows} == {"ok", "ambiguous_assembly"})
    assert all(r["x"] == "" and "resultant polynomial" in r["message"] for r in np.array(rows)[~ok])
    xyz = np.array([[float(r[c]) for c in "xyz"] for r in np.array(rows)[ok]])
    np.testing.assert_allclose(xyz, poses[ok, :3, 3], atol=1e-9)
    rpy = np.radians([[float(r[c]) for c in ("roll", "pitch", "yaw")] for r in np.array(rows)[ok]])
    np.testing.assert_allclose(rpy_to_matrix(*rpy.T), poses[ok, :3, :3], atol=1e-9)
    # ik back from fk's own output, with the preset name in place of the file (a row without a pose is
    # invalid_input there)
    assert main(["ik", name, str(tmp_path / "poses.csv"), "-o", str(tmp_path / "back.csv"), "--no-body-check"]) == code
    back = np.array([[float(r[f"l{i}"] or "nan") for i in range(1, 7)] for r in read_rows(tmp_path / "back.csv")])
    np.testing.assert_allclose(back[ok], lengths[ok], atol=1e-9)


def test_fk_bad_rows_are_reported_and_the_rest_solved(tmp_path, capsys):
    hexa = hexapod("reference")
    good = [hexa.inverse(T).lengths for T in box_poses(hexa.home_pose, 3, seed=4)]
    lines = [
        "l1,l2,l3,l4,l5,l6",
        ",".join(map(str, good[0])),
        "0.01,nan,0,0,0,0",
        ",".join(map(str, good[1])),
        "0.9,0,0,0,0,0",
        "0.01,0.01,,0,0,0",
        ",".join(map(str, good[2])),
    ]
    (tmp_path / "in.csv").write_text("\n".join(lines) + "\n")
    code = main(["fk", "reference", str(tmp_path / "in.csv"), "-o", str(tmp_path / "out.csv")])
    err = capsys.readouterr().err
    assert code == 1
    assert "3 of 6 rows failed" in err and "row 2" in err and len(err.strip().splitlines()) == 1
    rows = read_rows(tmp_path / "out.csv")
    assert [r["status"] for r in rows] == ["ok", "invalid_input", "ok", "invalid_input", "invalid_input", "ok"]
    assert rows[1]["x"] == "" and rows[1]["qw"] == ""  # no pose presented for a bad row
    for k, T in zip((0, 2, 5), box_poses(hexa.home_pose, 3, seed=4)):
        assert abs(float(rows[k]["z"]) - T[2, 3]) < 1e-9


def test_fk_status_column_says_uncertified_and_ambiguous_assembly(tmp_path, capsys):
    """A warm pose next to a singularity that cannot be certified is uncertified, no pose; readings
    whose path from home is blocked get ambiguous_assembly and no pose."""
    sph = hexapod("spherical")  # singular at 90 deg of yaw about its home position
    yaws = (45.0, 80.0, 90.0)
    lengths = []
    for yaw in yaws:
        T = sph.home_pose.copy()
        T[:3, :3] = rpy_to_matrix(0.0, 0.0, np.radians(yaw))
        lengths.append(sph.inverse(T).lengths)
    (tmp_path / "s.csv").write_text(
        "l1,l2,l3,l4,l5,l6\n" + "\n".join(",".join(f"{v:.17g}" for v in l) for l in lengths)
    )
    assert main(["fk", "spherical", str(tmp_path / "s.csv"), "-o", str(tmp_path / "s_out.csv")]) == 1
    rows = read_rows(tmp_path / "s_out.csv")
    assert [r["status"] for r in rows] == ["ok", "ok", "uncertified"]
    assert rows[2]["yaw"] == ""  # not certified: no pose presented
    assert "row 3 (line 4): uncertified: the assembly connected to the start could not" in capsys.readouterr().err
    # the 3-6 layout without cones and with hair-thin bodies: several assemblies fit these readings
    slim = dict(leg_radius=1e-4, housing_radius=2e-4, plate_thickness=1e-4, base_plate_radius=1e-3)
    geometry = replace(hm.get_preset("3-6"), platform_cone=None, platform_plate_radius=1e-3, **slim)
    (tmp_path / "six.json").write_text(json.dumps(geometry.to_dict()))
    six = hm.Hexapod.from_geometry(geometry)
    T = box_poses(six.home_pose, 600, seed=0, translation=0.1, angle_deg=40)[13]
    (tmp_path / "a.csv").write_text(
        "l1,l2,l3,l4,l5,l6\n" + ",".join(f"{v:.17g}" for v in six.inverse(T).lengths) + "\n"
    )
    assert main(["fk", str(tmp_path / "six.json"), str(tmp_path / "a.csv"), "-o", str(tmp_path / "a_out.csv")]) == 1
    rows = read_rows(tmp_path / "a_out.csv")
    assert rows[0]["status"] == "ambiguous_assembly" and rows[0]["x"] == ""
    assert "ambiguous_assembly: " in capsys.readouterr().err


def test_ik_pose_outside_workspace_row(tmp_path, capsys):
    (tmp_path / "p.csv").write_text("x,y,z,roll,pitch,yaw\n0,0,0.4,0,0,0\n0,0,0.9,0,0,0\n0.01,0,0.41,5,0,0\n")
    assert main(["ik", "reference", str(tmp_path / "p.csv"), "-o", str(tmp_path / "l.csv")]) == 1
    rows = read_rows(tmp_path / "l.csv")
    assert [r["status"] for r in rows] == ["ok", "out_of_limits", "ok"]
    assert rows[1]["l1"] == ""
    assert "stroke limit" in capsys.readouterr().err


def test_missing_columns_and_files(tmp_path, capsys):
    (tmp_path / "x.csv").write_text("a,b\n1,2\n")
    assert main(["fk", "reference", str(tmp_path / "x.csv")]) == 2
    assert "missing columns" in capsys.readouterr().err
    assert main(["fk", "reference", str(tmp_path / "none.csv")]) == 2
    assert main(["fk", str(tmp_path / "none.urdf"), str(tmp_path / "x.csv")]) == 2
    assert "cannot read URDF" in capsys.readouterr().err
    assert main(["fk", "referense", str(tmp_path / "x.csv")]) == 2  # a misspelt preset: the presets are named
    err = capsys.readouterr().err
    assert "referense" in err and all(name in err for name in hm.PRESETS) and len(err.strip().splitlines()) == 1


def test_bench_runs_and_writes_json(tmp_path, capsys):
    assert main(["bench", "--samples", "20", "--json", str(tmp_path / "b.json")]) == 0
    out = capsys.readouterr().out
    assert "warm_fk" in out and "median" in out
    report = json.loads((tmp_path / "b.json").read_text())
    assert report["hexapod"] == "reference" and report["warm_fk"]["n"] >= 1000  # trajectory A, 1 kHz
    assert report["warm_fk"]["iterations_max"] <= 3 and report["cold_fk"]["iterations_max"] <= 8


def test_top_level_conventions(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.strip() == f"hexapod_model {hm.__version__}"
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    commands = [ln.split()[0] for ln in text.splitlines() if ln.startswith("    ") and len(ln.split()) > 1]
    assert {"urdf", "fk", "ik", "bench", "reproduce", "evaluate", "track", "view", "snapshot"} <= set(commands)
    assert "exit codes: 0" in text


def test_python_m_and_stdin_stdout(tmp_path):
    import subprocess
    import sys

    lengths = (ROOT / "docs" / "examples" / "lengths.csv").read_text()
    out = subprocess.run(
        [sys.executable, "-m", "hexapod_model", "fk", "reference", "-", "-o", "-"],
        input=lengths,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    rows = out.stdout.strip().splitlines()
    assert rows[0].startswith("x,y,z,qx") and len(rows) == len(lengths.strip().splitlines())


def test_every_command_accepts_the_three_hexapod_spellings(tmp_path):
    geometry = tmp_path / "g.json"
    geometry.write_text(json.dumps(hm.get_preset("spherical").to_dict()))
    urdf = tmp_path / "g.urdf"
    hm.write_urdf(hm.get_preset("spherical"), urdf)
    lengths = ROOT / "docs" / "examples" / "lengths.csv"
    for spec in ("spherical", str(urdf), str(geometry)):
        assert main(["fk", spec, str(lengths), "-o", str(tmp_path / "p.csv")]) == 0, spec
        assert hm.Hexapod.load(spec).forward(np.zeros(6)).converged
