"""Geometry dataclasses and files: validation names the bad field and value."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.description.geometry import geometry_from_dict, load_geometry

from ..conftest import PRESET_NAMES, hexapod


def _dict(name="reference"):
    return hm.get_preset(name).to_dict()


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_presets_round_trip_through_dict(name):
    g = hm.get_preset(name)
    assert geometry_from_dict(g.to_dict()) == g


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_preset_is_well_conditioned_at_home(name):
    # a layout singular at home would make every solve near home meaningless
    sol = hexapod(name).forward(np.zeros(6))
    assert sol.converged and sol.iterations == 0
    assert sol.condition_number < 1e3


def test_list_of_presets_has_the_issue_names():
    assert {"reference", "intersecting", "spherical", "3-6", "guideway"} <= set(hm.PRESETS)


def test_toml_and_json_files_load(tmp_path):
    d = _dict()
    (tmp_path / "g.json").write_text(json.dumps(d))
    assert load_geometry(tmp_path / "g.json") == hm.get_preset("reference")
    legs = "\n".join(
        f"[[legs]]\nbase_anchor = {list(leg['base_anchor'])}\nplatform_anchor = {list(leg['platform_anchor'])}\n"
        f"stroke = {list(leg['stroke'])}\n"
        for leg in d["legs"]
    )
    (tmp_path / "g.toml").write_text(
        f'name = "mine"\njoint_type = "cardan"\nhome_height = 0.4\nbase_offset = 0.01\nplatform_offset = 0.01\n'
        f"cardan_limit_deg = 60\n{legs}"
    )
    g = load_geometry(tmp_path / "g.toml")
    assert g.name == "mine" and math.isclose(g.cardan_limit, math.radians(60))
    import yaml

    (tmp_path / "g.yaml").write_text(yaml.safe_dump(d))
    assert load_geometry(tmp_path / "g.yaml") == hm.get_preset("reference")


@pytest.mark.parametrize(
    "mutate, field, pattern",
    [
        (lambda d: d["legs"].pop(), "legs", "exactly 6 legs"),
        (lambda d: d.update(joint_type="ball"), "joint_type", "must be one of"),
        (lambda d: d.update(home_height=-0.1), "home_height", r"must lie in \(0"),
        (lambda d: d.update(cardan_limit=2.0), "cardan_limit", "must lie in"),
        (lambda d: d.update(base_offset="big"), "base_offset", "expected a number"),
        (lambda d: d["legs"][2].update(stroke=[0.1, 0.2]), r"legs\[2\].stroke", "min < 0 < max"),
        (lambda d: d["legs"][1].update(base_anchor=[0, 0]), r"legs\[1\].base_anchor", "expected 3 numbers"),
        (lambda d: d["legs"][4].update(base_anchor=[0, float("nan"), 0]), r"legs\[4\].base_anchor", "finite"),
        (lambda d: d["legs"][0].update(base_axis=[0, 0, 1]), r"legs\[0\].base_axis", "perpendicular"),
        (lambda d: d.update(colour="red"), "colour", "unknown field"),
        (lambda d: d.pop("home_height"), "home_height", "required field is missing"),
        (lambda d: d["legs"][3].update(guideway=[1, 0, 0]), r"legs\[3\].guideway", "only guideway legs"),
    ],
)
def test_malformed_geometry_names_field_and_value(mutate, field, pattern):
    d = _dict()
    d["legs"] = [dict(leg) for leg in d["legs"]]
    mutate(d)
    with pytest.raises(hm.GeometryError, match=rf"{field}.*{pattern}"):
        geometry_from_dict(d)


def test_malformed_files(tmp_path):
    (tmp_path / "bad.toml").write_text("name = [unclosed")
    with pytest.raises(hm.GeometryError, match="not valid TOML"):
        load_geometry(tmp_path / "bad.toml")
    (tmp_path / "g.yaml").write_text("name: [x")
    with pytest.raises(hm.GeometryError, match="not valid YAML"):
        load_geometry(tmp_path / "g.yaml")
    (tmp_path / "g.xml").write_text("<x/>")
    with pytest.raises(hm.GeometryError, match=r"\.toml, \.yaml or \.json"):
        load_geometry(tmp_path / "g.xml")
    with pytest.raises(hm.GeometryError, match="cannot read"):
        load_geometry(tmp_path / "missing.toml")


def test_geometry_is_frozen():
    g = hm.get_preset("reference")
    with pytest.raises(dataclasses.FrozenInstanceError):
        g.home_height = 1.0
