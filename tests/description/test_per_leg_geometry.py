"""Per-leg joint parameters: offsets, tilted axes, encoder models; TOML files; the URDF round trip."""

from __future__ import annotations

import dataclasses
import re
import tomllib

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.standard import StandardModel
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.geometry_toml import compact, geometry_to_toml, save_geometry
from hexapod_model.description.legs import axes_of
from hexapod_model.description.model import ClosedLoopModel


def perturbed(seed: int = 1, encoders: bool = True) -> hm.HexapodGeometry:
    """The reference hexapod with every per-leg parameter off nominal (tilted axes included)."""
    g = hm.get_preset("reference")
    rng = np.random.default_rng(seed)
    legs = []
    for i, leg in enumerate(g.legs):
        ax = axes_of(g, i)
        a = ax.base[:, 0] + rng.normal(0, 5e-3, 3)
        c = ax.platform[:, 0] + rng.normal(0, 5e-3, 3)
        legs.append(
            dataclasses.replace(
                leg,
                base_anchor=tuple(np.add(leg.base_anchor, rng.normal(0, 5e-4, 3))),
                platform_anchor=tuple(np.add(leg.platform_anchor, rng.normal(0, 5e-4, 3))),
                base_axis=tuple(a / np.linalg.norm(a)),
                platform_axis=tuple(c / np.linalg.norm(c)),
                base_offset=0.012 + rng.normal(0, 5e-4),
                platform_offset=0.012 + rng.normal(0, 5e-4),
                encoder_zero=float(rng.normal(0, 1e-3)) if encoders else 0.0,
                encoder_scale=float(rng.normal(0, 1e-3)) if encoders else 0.0,
            )
        )
    return dataclasses.replace(g, name="perturbed", legs=tuple(legs))


def test_urdf_puts_the_joints_where_the_geometry_says():
    g = perturbed()
    hexa = hm.Hexapod.from_geometry(g)
    bare = hm.Hexapod(ClosedLoopModel(hm.geometry_to_urdf(g)))  # centres read off the URDF
    sm = StandardModel.from_hexapod(bare)
    np.testing.assert_allclose(sm.base_points, g.base_points(), atol=1e-12)
    np.testing.assert_allclose(sm.platform_points, g.platform_points(), atol=1e-12)
    m, d = hexa.model, hexa.model.createData()
    pin.forwardKinematics(m, d, hexa.q_home)
    for i, leg in enumerate(hexa.closed_loop.legs):
        first, last = d.oMi[leg.joints[0]], d.oMi[leg.joints[-1]]
        np.testing.assert_allclose(first.rotation[:, 0], g.legs[i].base_axis, atol=1e-12)
        np.testing.assert_allclose(last.rotation[:, 0], g.legs[i].platform_axis, atol=1e-12)
        # the two axes of each Cardan joint are the leg's own offset apart
        second = d.oMi[leg.joints[1]]
        eb, ep = g.offsets(i)
        assert abs(np.linalg.norm(second.translation - first.translation) - eb) < 1e-12
        assert abs(np.linalg.norm(last.translation - d.oMi[leg.joints[-2]].translation) - ep) < 1e-12


def test_encoder_model_maps_readings_to_joints():
    g = perturbed()
    hexa = hm.Hexapod.from_geometry(g)
    zero = np.array([leg.encoder_zero for leg in g.legs])
    scale = np.array([leg.encoder_scale for leg in g.legs])
    home = hexa.forward(zero)
    assert home.iterations == 0
    np.testing.assert_allclose(home.pose, hexa.home_pose, atol=1e-12)
    lo = np.array([leg.stroke[0] for leg in g.legs])
    np.testing.assert_allclose(hexa.stroke[:, 0], zero + (1 + scale) * lo, atol=1e-15)
    for T in box_poses(hexa.home_pose, 5, seed=3):
        sol = hexa.inverse(T)
        np.testing.assert_allclose(sol.lengths, zero + (1 + scale) * sol.q[hexa.closed_loop.prismatic_q], atol=1e-15)
        np.testing.assert_allclose(hexa.forward(sol.lengths).pose, T, atol=1e-9)
    bad = zero.copy()
    bad[2] = hexa.stroke[2, 1] + 1e-3
    with pytest.raises(hm.LimitError, match=r"leg3_prismatic = .* outside \[.*\] m") as exc:
        hexa.forward(bad)
    assert abs(exc.value.upper - hexa.stroke[2, 1]) < 1e-12  # the limit in readings, as given


def test_presets_have_no_encoder_elements_and_identity_readings():
    hexa = hm.Hexapod.from_preset("reference")
    assert "<encoder" not in hm.geometry_to_urdf(hexa.geometry)
    np.testing.assert_array_equal(hexa.stroke, [leg.stroke for leg in hexa.geometry.legs])


def test_toml_round_trip_is_exact_and_uniform_values_stay_short(tmp_path):
    g = perturbed()
    path = save_geometry(g, tmp_path / "g.toml", comment="calibrated\nsecond line")
    assert hm.load_geometry(path) == compact(g)
    assert hm.geometry_to_urdf(hm.load_geometry(path)) == hm.geometry_to_urdf(g)
    uniform = dataclasses.replace(
        hm.get_preset("reference"),
        legs=tuple(dataclasses.replace(leg, base_offset=0.013) for leg in hm.get_preset("reference").legs),
    )
    text = geometry_to_toml(uniform)
    data = tomllib.loads(text)
    assert data["base_offset"] == 0.013 and all("base_offset" not in leg for leg in data["legs"])
    assert not any(k.startswith(("encoder", "base_axis", "platform_axis")) for leg in data["legs"] for k in leg)


@pytest.mark.parametrize(
    "change, field, pattern",
    [
        ({"encoder_scale": 0.7}, "encoder_scale", r"must lie in \[-0.5, 0.5\]"),
        ({"encoder_zero": float("nan")}, "encoder_zero", "must lie in"),
        ({"base_offset": -0.001}, "base_offset", "must lie in"),
        ({"base_axis": (0.0, 0.0, 1.0)}, r"legs\[0\].base_axis", "perpendicular .* within 10 deg"),
    ],
)
def test_bad_per_leg_values_name_the_field(change, field, pattern):
    d = hm.get_preset("reference").to_dict()
    d["legs"][0].update(change)
    with pytest.raises(hm.GeometryError, match=rf"{field}.*{pattern}"):
        hm.geometry_from_dict(d)


def test_platform_offset_per_leg_only_for_cardan_legs():
    d = hm.get_preset("spherical").to_dict()
    d["legs"][3]["platform_offset"] = 0.01
    with pytest.raises(hm.GeometryError, match=r"legs\[3\].platform_offset.*only cardan"):
        hm.geometry_from_dict(d)


def test_malformed_encoder_elements_are_rejected():
    text = hm.geometry_to_urdf(perturbed())
    with pytest.raises(hm.UrdfError, match="must name a leg's prismatic joint"):
        ClosedLoopModel(text.replace('joint="leg2_prismatic"', 'joint="leg2_roll"'))
    with pytest.raises(hm.UrdfError, match="must be numbers"):
        ClosedLoopModel(re.sub(r'(<encoder joint="leg1_prismatic" zero=")[^"]*', r"\1x", text))


def test_a_cardan_geometry_is_read_back_off_its_urdf():
    from hexapod_model.description.urdf_geometry import geometry_of_urdf

    g = perturbed()
    back = geometry_of_urdf(ClosedLoopModel(hm.geometry_to_urdf(g), "p.urdf"))
    np.testing.assert_allclose(back.base_points(), g.base_points(), atol=1e-12)
    np.testing.assert_allclose(back.platform_points(), g.platform_points(), atol=1e-12)
    for a, b in zip(back.legs, g.legs):
        assert abs(abs(np.dot(a.base_axis, b.base_axis)) - 1) < 1e-12
        assert abs(a.base_offset - b.base_offset) < 1e-12 and abs(a.encoder_zero - b.encoder_zero) < 1e-12
    with pytest.raises(hm.UrdfError, match="cardan legs"):
        geometry_of_urdf(ClosedLoopModel(hm.geometry_to_urdf(hm.get_preset("spherical"))))


def test_per_leg_example_of_the_geometry_doc_loads():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "geometry.md").read_text()
    block = re.findall(r"```toml\n(.*?)```", text, re.S)[1]
    d = hm.get_preset("reference").to_dict()
    d["legs"][0] = tomllib.loads(block)["legs"][0]
    g = hm.geometry_from_dict(d)
    assert g.offsets(0) == (0.01243, 0.01187) and g.legs[0].encoder_zero == 0.00081
    sol = hm.Hexapod.from_geometry(g).forward([0.00081, 0, 0, 0, 0, 0])
    assert sol.converged and sol.iterations == 0  # the reading at home is the home pose


def test_mjcf_export_refuses_an_encoder_model():
    from hexapod_model.description.mjcf import geometry_to_mjcf

    with pytest.raises(hm.UrdfError, match="encoder"):
        geometry_to_mjcf(perturbed())
    assert "<mujoco" in geometry_to_mjcf(perturbed(encoders=False))  # tilted axes and offsets are fine
