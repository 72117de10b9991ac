"""Lengths 100x a hexapod's base radius are refused in one line that suspects the unit."""

from __future__ import annotations

import pytest

import hexapod_model as hm
from hexapod_model.analysis.statics import fixture_stiffness, leg_forces
from hexapod_model.cli.main import main
from hexapod_model.description.geometry import geometry_from_dict
from hexapod_model.description.plausibility import PLAUSIBLE_RATIO, implausible
from hexapod_model.exceptions import GeometryError, InputError
from hexapod_model.studies.sweep_spec import load_spec

from ..conftest import PRESET_NAMES


def test_the_message_names_the_value_the_base_radius_and_the_unit():
    why = implausible("z", 415.0, 0.25)
    assert why == "z = 415 m is 1660x the base radius 0.25 m (at most 100x): is it in mm?"
    assert implausible("z", 0.415, 0.25) == "" and implausible("z", -0.25 * PLAUSIBLE_RATIO, 0.25) == ""
    assert "is it in cm?" in implausible("x", 41.5, 0.25)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_no_preset_length_is_near_the_limit(name):
    g = hm.get_preset(name)
    r = g.base_radius
    lengths = [g.home_height] + [v for leg in g.legs for v in (*leg.platform_anchor, *leg.stroke)]
    assert r > 0 and max(abs(v) for v in lengths) < 0.1 * PLAUSIBLE_RATIO * r


def test_statics_pose_in_mm_names_z_and_the_unit(capsys):
    hexa = hm.Hexapod.from_preset("reference", compiled=False)
    T = hexa.home_pose.copy()
    T[2, 3] = 415.0  # mm meant
    wrench = [0, 0, 100.0, 0, 0, 0]
    for call in (lambda: leg_forces(hexa, T, wrench), lambda: fixture_stiffness(hexa, T, 2e7)):
        with pytest.raises(InputError, match=r"z = 415 m is 16\d\dx the base radius 0\.25\d* m .*is it in mm\?"):
            call()
    assert (
        main(
            ["statics", "reference", "--pose", "0", "0", "415", "0", "0", "0", "--wrench", "0", "0", "1", "0", "0", "0"]
        )
        == 2
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "z = 415 m" in err[0] and "is it in mm?" in err[0], err


def test_ik_rows_in_mm_are_invalid_input_naming_the_unit(tmp_path, capsys):
    poses = tmp_path / "poses.csv"
    poses.write_text("x,y,z,roll,pitch,yaw\n0,0,0.41,0,0,0\n10,-20,410,0,0,0\n")
    assert main(["ik", "reference", str(poses), "-o", str(tmp_path / "out.csv")]) == 1
    rows = (tmp_path / "out.csv").read_text().splitlines()
    assert rows[1].split(",")[6] == "ok" and ",invalid_input," in rows[2] and "is it in mm?" in rows[2]
    assert "row 2" in capsys.readouterr().err


def test_geometry_with_platform_anchors_in_mm_is_refused():
    d = hm.get_preset("reference").to_dict()
    for leg in d["legs"]:
        leg["platform_anchor"] = [1000.0 * v for v in leg["platform_anchor"]]
    with pytest.raises(GeometryError, match=r"legs\[0\]\.platform_anchor.*base radius 0\.25 m .*is it in mm\?"):
        geometry_from_dict(d)


def test_sweep_radii_in_mm_are_refused(tmp_path, capsys):
    spec = tmp_path / "mm.toml"
    spec.write_text('base = "reference"\n[parameters]\nplatform_radius = [120.0, 150.0]\n')
    with pytest.raises(InputError, match=r"parameters\.platform_radius.*120 m is 480x the base radius .*is it in mm\?"):
        load_spec(spec)
    assert main(["sweep", str(spec), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is it in mm?" in err[0], err
