"""Output files: never an input, checked before any work, written atomically."""

from __future__ import annotations

import json

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.cli.main import main

HEADER = "l1,l2,l3,l4,l5,l6"


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


@pytest.fixture
def files(tmp_path):
    (tmp_path / "l.csv").write_text(HEADER + "\n0.01,0,-0.02,0,0.015,0\n")
    hm.write_urdf(hm.get_preset("reference"), tmp_path / "X.urdf")
    (tmp_path / "g.json").write_text(json.dumps(hm.get_preset("intersecting").to_dict()))
    return tmp_path


def _unchanged(path, before):
    return path.read_bytes() == before


@pytest.mark.parametrize(
    "argv, target",
    [
        (["fk", "reference", "{d}/l.csv", "-o", "{d}/l.csv"], "l.csv"),
        (["fk", "{d}/X.urdf", "{d}/l.csv", "-o", "{d}/X.urdf"], "X.urdf"),  # the HEXAPOD input too
        (["ik", "{d}/X.urdf", "{d}/l.csv", "-o", "{d}/X.urdf"], "X.urdf"),
        (["bench", "{d}/X.urdf", "--samples", "5", "--json", "{d}/X.urdf"], "X.urdf"),
        (["urdf", "--geometry", "{d}/g.json", "-o", "{d}/g.json"], "g.json"),
        (["snapshot", "{d}/X.urdf", "-o", "{d}/X.urdf"], "X.urdf"),
        (["snapshot", "{d}/X.urdf", "-o", "{d}/s.html", "--png", "{d}/X.urdf"], "X.urdf"),
        (["reproduce", "--urdf", "{d}/X.urdf", "--poses", "5", "--json", "{d}/X.urdf"], "X.urdf"),
        (["track", "{d}/X.urdf", "--json", "{d}/X.urdf"], "X.urdf"),
        (["track", "{d}/X.urdf", "--readings", "{d}/l.csv", "-o", "{d}/X.urdf"], "X.urdf"),
    ],
)
def test_an_input_is_never_an_output(files, capsys, argv, target):
    before = (files / target).read_bytes()
    code, err = run(capsys, *[a.format(d=files) for a in argv])
    assert code == 2 and "is also an input; choose another output file" in err and len(err.splitlines()) == 1
    assert _unchanged(files / target, before)


def test_snapshot_html_and_png_must_differ(files, capsys):
    code, err = run(capsys, "snapshot", "reference", "-o", files / "s.html", "--png", files / "s.html")
    assert code == 2 and "--png" in err and not (files / "s.html").exists()


@pytest.mark.parametrize("output, words", [("missing/p.csv", "folder"), (".", "is a folder")])
def test_unusable_output_is_one_line_before_solving(files, capsys, output, words):
    code, err = run(capsys, "fk", "reference", files / "l.csv", "-o", files / output)
    assert code == 2 and words in err and len(err.splitlines()) == 1 and "Traceback" not in err


def test_reproduce_json_in_the_fresh_out_folder(files, capsys):
    out = files / "rp"
    code, err = run(
        capsys, "reproduce", "--poses", "10", "--convergence-poses", "0", "--out", out, "--json", out / "r.json"
    )
    assert code == 0, err
    assert json.loads((out / "r.json").read_text())["poses"] == 10
    assert sorted(p.name for p in out.iterdir()) == [
        "r.json",
        "reproduce_errors_cardan.png",
        "reproduce_errors_standard.png",
        "reproduce_histograms.png",
    ]  # no temporary file left beside the outputs
    (files / "f").write_text("")
    code, err = run(capsys, "reproduce", "--poses", "10", "--out", files / "f")
    assert code == 2 and "is a file; name a folder" in err


def test_a_failing_fk_leaves_the_previous_output_untouched(files, capsys):
    (files / "p.csv").write_text("previous results\n")
    rows = "0.01,0,-0.02,0,0.015,0\n" * 3000
    (files / "bad.csv").write_bytes((HEADER + "\n" + rows).encode() + b"0.01,0,0,0,0,\xff\n")
    code, err = run(capsys, "fk", "reference", files / "bad.csv", "-o", files / "p.csv")
    assert code == 2 and "line 3002: not UTF-8" in err
    assert (files / "p.csv").read_text() == "previous results\n"
    assert sorted(p.name for p in files.iterdir()) == ["X.urdf", "bad.csv", "g.json", "l.csv", "p.csv"]


def test_singular_geometry_is_not_written_as_a_urdf(files, capsys):
    d = hm.get_preset("reference").to_dict()
    for leg in d["legs"]:  # vertical legs: the platform turns about z and slides freely at home
        leg.pop("base_axis", None)
        leg.pop("platform_axis", None)
        leg["platform_anchor"] = [leg["base_anchor"][0], leg["base_anchor"][1], 0.0]
    (files / "v.json").write_text(json.dumps(d))
    code, err = run(capsys, "urdf", "--geometry", files / "v.json", "-o", files / "v.urdf")
    assert code == 2 and "home condition number" in err and "limit 1e+06" in err and len(err.splitlines()) == 1
    assert not (files / "v.urdf").exists()
    code, err = run(capsys, "fk", files / "v.json", files / "l.csv")
    assert code == 2 and "home condition number" in err
    assert np.isfinite(hm.Hexapod.from_preset("reference").home_condition_number)
