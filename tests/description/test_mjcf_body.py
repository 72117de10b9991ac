"""The body check of a hexapod loaded from MJCF: the same bodies, pairs, cones and answers as from its URDF."""

from __future__ import annotations

import dataclasses
import functools
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.description.geometry import load_geometry
from hexapod_model.description.mjcf import COLLISION_GROUP, geometry_to_mjcf
from hexapod_model.description.mjcf_loader import load_mjcf_text
from hexapod_model.exceptions import MjcfError
from hexapod_model.kinematics.body_check import body_limits
from hexapod_model.kinematics.clearance import query_of
from hexapod_model.lie import xyz_rpy_to_pose

from ..conftest import PRESET_NAMES

ROOT = Path(__file__).resolve().parents[2]
THICK = ROOT / "docs" / "geometries" / "thick_legs.toml"
TWIST = (0.0, 0.0, 0.0, 0.0, 0.0, 75.0)  # deg: the thick legs' platform housing meets a neighbour's rod


@functools.cache
def pair(path: Path = THICK) -> tuple[hm.Hexapod, hm.Hexapod]:
    """The hexapod of a geometry file from the geometry (its URDF) and from its MJCF."""
    g = load_geometry(path)
    return hm.Hexapod.from_geometry(g, compiled=False), hm.Hexapod(
        load_mjcf_text(geometry_to_mjcf(g), f"{g.name}.xml"), compiled=False
    )


def test_a_twist_into_collision_is_collision_naming_the_same_pair_from_both():
    urdf, mjcf = pair()
    T = urdf.home_pose @ xyz_rpy_to_pose(TWIST)
    a, b = urdf.inverse(T, check=False), mjcf.inverse(T, check=False)
    assert a.status == b.status == "collision"
    assert a.message == b.message and "leg" in a.message
    with pytest.raises(hm.WorkspaceError, match="collision"):
        mjcf.inverse(T)
    fa, fb = urdf.forward(a.lengths, check=False), mjcf.forward(a.lengths, check=False)
    assert "collision" in fa.flags and "collision" in fb.flags


def test_the_mjcf_hexapod_has_the_urdf_bodies_and_pairs():
    urdf, mjcf = pair()
    qu, qm = query_of(urdf), query_of(mjcf)
    assert qu.pairs == qm.pairs and len(qm.pairs) > 0
    assert qu.collision.owners == qm.collision.owners


def test_clearance_agrees_on_seeded_poses():
    urdf, mjcf = pair()
    rng = np.random.default_rng(32)
    for _ in range(20):
        T = urdf.home_pose @ xyz_rpy_to_pose(np.r_[rng.uniform(-0.04, 0.04, 3), rng.uniform(-25.0, 25.0, 3)])
        q = urdf.inverse(T, check=False).q
        a, b = urdf.clearance(q), mjcf.clearance(q)
        assert abs(a.distance - b.distance) < 1e-9
        every = query_of(urdf).all_pairs(q)
        np.testing.assert_allclose(query_of(mjcf).all_pairs(q), every, rtol=0, atol=1e-9)
        # two pairs of a symmetric pose may tie to 1e-16 m: the pair named is one at the smallest distance
        assert abs(every[query_of(urdf).pairs.index(b.pair)] - a.distance) < 1e-9
        if a.pair == b.pair:
            np.testing.assert_allclose(a.points, b.points, atol=1e-9)


@pytest.mark.parametrize("name", ["reference", "3-6"])
def test_the_mjcf_carries_the_cones_and_min_clearance(name):
    g = dataclasses.replace(hm.get_preset(name), min_clearance=0.002)
    urdf = hm.Hexapod.from_geometry(g, compiled=False)
    mjcf = hm.Hexapod(load_mjcf_text(geometry_to_mjcf(g), f"{name}.xml"), compiled=False)
    a, b = body_limits(urdf.closed_loop, urdf.geometry), body_limits(mjcf.closed_loop, None)
    assert np.isfinite(a[0]).any()
    np.testing.assert_array_equal(a[0], b[0])
    assert a[1] == b[1] == 0.002
    assert query_of(mjcf).min_clearance == 0.002
    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(40):
        T = urdf.home_pose @ xyz_rpy_to_pose(np.r_[rng.uniform(-0.1, 0.1, 3), rng.uniform(-40.0, 40.0, 3)])
        sa, sb = urdf.inverse(T, check=False), mjcf.inverse(T, check=False)
        assert (sa.status, sa.message) == (sb.status, sb.message)
        seen.add(sa.status)
    assert "cone_limit" in seen or name == "reference"


def test_a_bad_cone_in_an_mjcf_is_named(tmp_path):
    text = geometry_to_mjcf(load_geometry(THICK))
    bad = re.sub(r'(name="hexapod_leg2_base_cone" data=")[^"]*', r"\g<1>-1", text)
    assert bad != text
    with pytest.raises(MjcfError, match="hexapod_leg2_base_cone") as err:
        load_mjcf_text(bad, "bad.xml")
    assert "bad.xml" in str(err.value) and "\n" not in str(err.value)


def _without_collision_geoms(text: str) -> str:
    root = ET.fromstring(text)
    for body in root.iter("body"):
        for geom in body.findall("geom"):
            if geom.get("group") == str(COLLISION_GROUP):
                body.remove(geom)
    return ET.tostring(root, encoding="unicode")


def test_an_mjcf_without_collision_bodies_needs_check_body_false():
    urdf, _ = pair()
    bare = _without_collision_geoms(geometry_to_mjcf(load_geometry(THICK)))
    with pytest.raises(MjcfError, match="no collision bodies.*check_body=False") as err:
        hm.Hexapod(load_mjcf_text(bare, "bare.xml"), compiled=False)
    assert "bare.xml" in str(err.value) and "\n" not in str(err.value)
    hexa = hm.Hexapod(load_mjcf_text(bare, "bare.xml"), compiled=False, check_body=False)
    with pytest.raises(MjcfError, match="no collision bodies"):
        hexa.check_body = True
    assert not hexa.check_body
    T = urdf.home_pose @ xyz_rpy_to_pose(TWIST)  # in collision: a solve the caller asked to leave unchecked
    assert hexa.inverse(T).status == "converged"


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_every_preset_from_mjcf_has_the_urdf_clearance(name):
    g = hm.get_preset(name)
    urdf = hm.Hexapod.from_geometry(g, compiled=False)
    mjcf = hm.Hexapod(load_mjcf_text(geometry_to_mjcf(g), f"{name}.xml"), compiled=False)
    assert query_of(urdf).pairs == query_of(mjcf).pairs
    q = urdf.inverse(urdf.home_pose @ xyz_rpy_to_pose([0.01, 0.0, 0.0, 3.0, 2.0, 5.0]), check=False).q
    np.testing.assert_allclose(query_of(mjcf).all_pairs(q), query_of(urdf).all_pairs(q), rtol=0, atol=1e-9)
    assert abs(urdf.clearance(q).distance - mjcf.clearance(q).distance) < 1e-9
