"""Measuring legs and inclinometers in geometries, files and the URDF variant."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.description.sensor_layout import SensorLayout, read_sensors, rpy_matrix
from hexapod_model.description.sensors import Inclinometer, MeasuringLeg


@pytest.mark.parametrize("name", ["reference7", "reference_tilt"])
def test_presets_add_sensors_to_the_reference_legs(name):
    g, ref = hm.get_preset(name), hm.get_preset("reference")
    assert g.redundant and not ref.redundant and g.legs == ref.legs
    assert g.reading_names[:6] == tuple(f"leg{i}" for i in range(1, 7))
    assert g.reading_names[6:] == (("leg7",) if name == "reference7" else ("tilt_x", "tilt_y"))


@pytest.mark.parametrize("name", ["reference7", "reference_tilt", "reference"])
def test_file_form_round_trips(tmp_path, name):
    g = hm.get_preset(name)
    d = g.to_dict()
    assert ("encoder_sigma" in d) == g.redundant
    path = tmp_path / "g.json"
    path.write_text(json.dumps(d))
    assert hm.load_geometry(path) == g


def test_inclinometer_in_degrees_and_bad_fields(tmp_path):
    d = hm.get_preset("reference").to_dict()
    d["inclinometer"] = {"rpy_deg": [0, 0, 30], "sigma": 1e-5}
    g = hm.geometry_from_dict(d)
    assert g.inclinometer == Inclinometer(rpy=(0.0, 0.0, np.radians(30)), sigma=1e-5)
    d["inclinometer"] = {"sigma": 0.0}
    with pytest.raises(hm.GeometryError, match=r"inclinometer.sigma.*must lie in \(0, 1\]"):
        hm.geometry_from_dict(d)
    d["inclinometer"] = {"yaw": 1.0}
    with pytest.raises(hm.GeometryError, match="inclinometer.yaw"):
        hm.geometry_from_dict(d)
    del d["inclinometer"]
    d["measuring_legs"] = [{"base_anchor": [0.25, 0, 0], "platform_anchor": [-0.15, 0, 0], "stroke": [0.1, 0.2]}]
    with pytest.raises(hm.GeometryError, match=r"measuring_legs\[0\].stroke"):
        hm.geometry_from_dict(d)
    d["measuring_legs"] = [{"base_anchor": [0.25, 0, 0], "stroke": [-0.1, 0.2]}]
    with pytest.raises(hm.GeometryError, match=r"measuring_legs\[0\].platform_anchor.*missing"):
        hm.geometry_from_dict(d)
    d["measuring_legs"] = []
    d["encoder_sigma"] = -1e-6
    with pytest.raises(hm.GeometryError, match="encoder_sigma"):
        hm.geometry_from_dict(d)


def test_rpy_matrix_is_the_urdf_convention():
    rpy = (0.1, -0.2, 0.3)
    np.testing.assert_allclose(rpy_matrix(rpy), pin.rpy.rpyToMatrix(*rpy), atol=1e-15)


@pytest.mark.parametrize("name", ["reference7", "reference_tilt"])
def test_urdf_variant_reads_back_the_layout(name):
    g = hm.get_preset(name)
    urdf = hm.geometry_to_urdf(g)
    assert len(hm.read_closures(urdf)) == 6  # the measuring leg's distance closure is not a leg's
    a, b = SensorLayout.from_geometry(g), read_sensors(urdf)
    assert a is not None and b is not None and a.names == b.names
    for field in ("base", "platform", "stroke", "zero", "scale", "sigmas"):
        np.testing.assert_allclose(getattr(a, field), getattr(b, field), atol=1e-13)
    assert (a.tilt_rotation is None) == (b.tilt_rotation is None)
    assert read_sensors(hm.geometry_to_urdf(hm.get_preset("reference"))) is None


def test_urdf_sensor_link_must_be_fixed_where_the_contract_says():
    urdf = hm.geometry_to_urdf(hm.get_preset("reference7")).replace(
        '<parent link="base_link" />\n    <child link="leg7_base" />',
        '<parent link="platform" />\n    <child link="leg7_base" />',
    )
    with pytest.raises(hm.UrdfError, match="fixed to 'base_link' .'leg7_base'."):
        read_sensors(urdf)


def test_measuring_leg_values_are_checked():
    with pytest.raises(hm.GeometryError, match="encoder_scale"):
        MeasuringLeg((0, 0, 0), (0, 0, 0.1), (-0.1, 0.1), encoder_scale=0.9)


def test_mjcf_keeps_the_sensor_frames_and_solves_six_legs(tmp_path):
    path = tmp_path / "r7.xml"
    path.write_text(hm.geometry_to_mjcf(hm.get_preset("reference7")))
    hexa = hm.Hexapod.from_mjcf(path)
    assert hexa.redundancy is None and hexa.reading_names == tuple(f"leg{i}" for i in range(1, 7))
    assert hexa.model.existFrame("leg7_base") and hexa.model.existFrame("leg7_anchor")


def test_geometry_toml_writes_the_sensors_and_reads_back_exactly(tmp_path):
    from hexapod_model.description.geometry_toml import save_geometry

    both = hm.get_preset("reference7")
    both = hm.HexapodGeometry(
        **{**vars(both), "inclinometer": Inclinometer(rpy=(0.1, -0.2, 0.3), sigma=3e-5), "name": "both"}
    )
    path = save_geometry(both, tmp_path / "both.toml")
    assert hm.load_geometry(path) == both
