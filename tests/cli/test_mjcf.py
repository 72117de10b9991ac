"""``hexapod mjcf``: every preset from the command line, files read back by every command, refusals."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.cli.main import main
from hexapod_model.description.mjcf import geometry_to_mjcf

from ..conftest import PRESET_NAMES

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_mjcf_of_every_preset_is_read_back_by_fk(name, tmp_path, capsys):
    out = tmp_path / f"{name}.xml"
    assert main(["mjcf", name, "-o", str(out)]) == 0
    assert out.read_text() == geometry_to_mjcf(hm.get_preset(name))
    assert f"wrote {out}" in capsys.readouterr().err
    lengths = ROOT / "docs/examples/lengths.csv"
    # the 3-6 preset checks every assembly (its layout is read off the MJCF model too): these
    # readings (another preset's) are ambiguous_assembly there, from either file
    # (the MJCF carries no cones: both solve without the body check, the kinematics alone)
    code = 1 if name == "3-6" else 0
    assert main(["fk", name, str(lengths), "-o", str(tmp_path / "urdf.csv"), "--no-body-check"]) == code
    assert main(["fk", str(out), str(lengths), "-o", str(tmp_path / "mjcf.csv"), "--no-body-check"]) == code
    with open(tmp_path / "urdf.csv", newline="") as fa, open(tmp_path / "mjcf.csv", newline="") as fb:
        a, b = list(csv.DictReader(fa)), list(csv.DictReader(fb))
    assert [r["status"] for r in a] == [r["status"] for r in b]
    for ra, rb in zip(a, b):
        for col in ("x", "y", "z", "qx", "qy", "qz", "qw"):
            if ra[col] or rb[col]:
                assert abs(float(ra[col]) - float(rb[col])) <= 1e-11, (col, ra, rb)


def test_actuated_stdout_and_geometry_file(tmp_path, capsys):
    assert main(["mjcf", "guideway", "--actuated"]) == 0
    text = capsys.readouterr().out
    assert text == geometry_to_mjcf(hm.get_preset("guideway"), actuated=True) and text.count("<position ") == 6
    d = hm.get_preset("spherical").to_dict()
    d["name"] = "mine"
    d["legs"][2]["stroke"] = [-0.05, 0.3]
    (tmp_path / "mine.json").write_text(json.dumps(d))
    assert main(["mjcf", str(tmp_path / "mine.json"), "-o", str(tmp_path / "mine.xml")]) == 0
    hexa = hm.Hexapod.load(tmp_path / "mine.xml")
    np.testing.assert_allclose(hexa.stroke[2], [-0.05, 0.3])
    urdf = tmp_path / "mine.urdf"
    assert main(["urdf", "--geometry", str(tmp_path / "mine.json"), "-o", str(urdf)]) == 0
    assert main(["mjcf", str(urdf), "-o", str(tmp_path / "from_urdf.xml")]) == 0
    # the same file but for the geometry's cones and min_clearance, which the URDF cannot carry
    mine, from_urdf = (tmp_path / "mine.xml").read_text(), (tmp_path / "from_urdf.xml").read_text()
    custom = re.search(r"\n *<custom>.*?</custom>", mine, flags=re.S)
    assert custom is not None and "hexapod_min_clearance" in custom.group(0)
    assert "<custom>" not in from_urdf
    assert from_urdf == mine.replace(custom.group(0), "")


def test_refusals_are_one_line_with_exit_code_2(tmp_path, capsys):
    xml = tmp_path / "r.xml"
    assert main(["mjcf", "reference", "-o", str(xml)]) == 0
    before = xml.read_text()
    cases = [
        (["mjcf", "reference", "-o", str(tmp_path / "r.txt")], "ending in .xml or .mjcf"),
        (["mjcf", str(xml), "-o", str(tmp_path / "again.xml")], "is an MJCF file already"),
        (["mjcf", str(xml), "-o", str(xml)], "is also an input"),
        (["mjcf", "reference", "-o", str(tmp_path / "no" / "r.xml")], "does not exist"),
        (["mjcf", "nonsense", "-o", str(tmp_path / "n.xml")], "nonsense"),
    ]
    capsys.readouterr()
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.startswith("hexapod mjcf: error: ") and message in err and err.count("\n") == 1, err
    assert xml.read_text() == before and not (tmp_path / "r.txt").exists()
