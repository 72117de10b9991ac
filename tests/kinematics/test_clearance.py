"""Clearance between the collision bodies, the pairs checked, and the joint cones."""

from __future__ import annotations

import itertools
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.cli.main import main
from hexapod_model.kinematics.cones import check_cones
from hexapod_model.lie import xyz_rpy_to_pose

ROOT = Path(__file__).resolve().parents[2]
THICK = ROOT / "docs" / "geometries" / "thick_legs.toml"
TWIST = xyz_rpy_to_pose([0.0, 0.0, 0.40, 0.0, 0.0, 85.0])  # 85 deg yaw about home


@pytest.fixture(scope="module")
def thick() -> hm.Hexapod:
    return hm.Hexapod.load(THICK, compiled=False)


def _segment_distance(p1, q1, p2, q2, n: int = 20001) -> float:
    """Distance of two segments by dense sampling of the first (accurate to ~1e-9 m here)."""
    s = np.linspace(0.0, 1.0, n)[:, None]
    a = p1 + s * (q1 - p1)
    d = q2 - p2
    t = np.clip((a - p2) @ d / (d @ d), 0.0, 1.0)[:, None]
    return float(np.min(np.linalg.norm(a - (p2 + t * d), axis=1)))


def test_twisted_thick_legs_collide_naming_two_legs(thick):
    home = thick.clearance(thick.home_pose)
    assert not home.collision and home.distance > 0
    c = thick.clearance(TWIST)
    assert c.collision
    legs = {name.split("_")[0] for name in c.pair}
    assert len(legs) == 2 and all(leg.startswith("leg") for leg in legs)
    assert c.pair[0] in c.message() and c.pair[1] in c.message() and "collision" in c.message()


def test_rod_distance_agrees_with_the_leg_axes(thick):
    """The rods' capsule distance is the distance of their axis segments minus the two radii."""
    sol = thick.inverse(TWIST, check=False)  # collision: its configuration is measured
    query = hm.kinematics.clearance.query_of(thick)
    distances = query.all_pairs(sol.q)
    m, data = thick.model, thick.model.createData()
    pin.forwardKinematics(m, data, sol.q)
    k = query.pairs.index(("leg2_rod", "leg3_rod"))
    rest = []
    for leg in (2, 3):
        j = m.getJointId(f"leg{leg}_prismatic")
        M = data.oMi[j]
        axes = hm.description.legs.axes_of(thick.geometry, leg - 1)
        short = float(axes.rest) + thick.geometry.legs[leg - 1].stroke[0]
        z = M.rotation[:, 2]
        top = M.translation + z * float(axes.rest)
        rest.append((top - z * short, top))
    expected = _segment_distance(*rest[0], *rest[1]) - 2 * thick.geometry.leg_radius
    assert abs(distances[k] - expected) < 1e-8


@pytest.mark.parametrize("name", ["reference", "3-6", "guideway"])
def test_clearance_is_pinocchio_distance_on_the_urdf_bodies(name):
    """Every checked pair's distance equals Pinocchio's computeDistances on the URDF file's own bodies.

    Both at the query's GJK tolerance: coal's default (1e-6) leaves up to 1.2 um on a capsule near
    a plate's rim (:func:`test_plate_distances_are_exact`).
    """
    hexa = hm.Hexapod.from_preset(name, compiled=False)
    rng = np.random.default_rng(7)
    pose = hexa.home_pose.copy()
    pose[:3, 3] += rng.uniform(-0.02, 0.02, 3)
    sol = hexa.inverse(pose, check=False)
    query = hm.kinematics.clearance.query_of(hexa)
    distances = query.all_pairs(sol.q)
    text = (ROOT / "urdf" / f"{name}.urdf").read_text()
    model = pin.buildModelFromXML(text)
    geom = pin.buildGeomFromUrdfString(model, text, pin.GeometryType.COLLISION)
    geom.addAllCollisionPairs()
    gdata = pin.GeometryData(geom)
    for request in gdata.distanceRequests:
        request.gjk_tolerance = hm.kinematics.clearance.GJK_TOLERANCE
        request.gjk_max_iterations = hm.kinematics.clearance.GJK_MAX_ITERATIONS
    pin.computeDistances(model, model.createData(), geom, gdata, sol.q)
    by_index = {(p.first, p.second): r.min_distance for p, r in zip(geom.collisionPairs, gdata.distanceResults)}
    for p, d in zip(query.collision.geometry.collisionPairs, distances):
        assert abs(by_index[(p.first, p.second)] - d) <= 1e-9


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("spec", ["reference", "spherical", "3-6", "guideway", str(THICK)])
def test_fast_query_is_coal_on_every_pair(spec, compiled):
    """The kernel's smallest distance and pair are coal's on all pairs, to 1e-9 m, over poses up to a collision."""
    hexa = hm.Hexapod.load(spec, compiled=compiled)
    query = hm.kinematics.clearance.query_of(hexa)
    rng = np.random.default_rng(3)
    for _ in range(12):
        offset = np.concatenate([rng.uniform(-0.06, 0.06, 3), rng.uniform(-30.0, 30.0, 2), rng.uniform(-85, 85, 1)])
        pose = xyz_rpy_to_pose(offset + [0.0, 0.0, hexa.home_pose[2, 3], 0.0, 0.0, 0.0])
        sol = hexa.inverse(pose, check=False)
        if sol.status not in ("converged", "out_of_limits"):
            continue
        c = hexa.clearance(sol.q)
        distances = query.all_pairs(sol.q)
        k = int(np.argmin(distances))
        assert abs(c.distance - distances[k]) <= 1e-9
        assert c.pair == query.pairs[k] or abs(distances[query.pairs.index(c.pair)] - distances[k]) <= 1e-9
        if c.distance > 0:
            assert abs(np.linalg.norm(c.points[1] - c.points[0]) - c.distance) <= 1e-9


@pytest.mark.parametrize("name", ["reference", "spherical", "3-6", "guideway"])
def test_pairs_in_contact_by_construction_are_left_out(name):
    hexa = hm.Hexapod.from_preset(name, compiled=False)
    pairs = hm.kinematics.clearance.query_of(hexa).pairs
    for a, b in pairs:
        assert a.split("_")[0] != b.split("_")[0]  # never two bodies of one leg (nor one plate)
    assert ("base_plate", "leg1_base_housing") not in pairs and ("platform_plate", "leg1_platform_housing") not in pairs
    assert ("base_plate", "leg1_cylinder" if name != "guideway" else "leg1_strut") in pairs
    if name == "3-6":  # legs 1 and 2 meet at one ball joint
        assert not any({a.split("_")[0], b.split("_")[0]} == {"leg1", "leg2"} for a, b in pairs)
        assert any({a.split("_")[0], b.split("_")[0]} == {"leg1", "leg3"} for a, b in pairs)


def test_min_clearance_turns_a_clear_pose_into_a_collision():
    geom = hm.get_preset("reference")
    hexa = hm.Hexapod.from_geometry(geom, compiled=False)
    d = hexa.clearance(hexa.home_pose).distance
    tight = hm.Hexapod.from_geometry(replace(geom, min_clearance=d + 1e-3), compiled=False)
    assert tight.clearance(tight.home_pose).collision


def test_cardan_cone_is_the_angle_between_leg_directions():
    """With intersecting axes the base Cardan's deflection is the angle of the leg from its home direction."""
    hexa = hm.Hexapod.from_preset("intersecting", compiled=False)
    pose = xyz_rpy_to_pose([0.03, -0.02, 0.43, 10.0, -5.0, 20.0])
    sol = hexa.inverse(pose)
    angles = check_cones(hexa.closed_loop, hexa.geometry, sol.q).angles
    g = hexa.geometry
    for i in range(6):
        b = np.asarray(g.legs[i].base_anchor)
        p = np.asarray(g.legs[i].platform_anchor)
        now = pose[:3, :3] @ p + pose[:3, 3] - b
        home = p + g.home_translation - b
        cos = now @ home / np.linalg.norm(now) / np.linalg.norm(home)
        assert abs(angles[i, 0] - np.arccos(np.clip(cos, -1, 1))) < 1e-9


def test_ball_cone_is_the_leg_angle_seen_from_the_platform():
    hexa = hm.Hexapod.from_preset("3-6", compiled=False)
    pose = xyz_rpy_to_pose([0.02, 0.01, 0.21, 15.0, 0.0, -10.0])
    sol = hexa.inverse(pose)
    cones = check_cones(hexa.closed_loop, hexa.geometry, sol.q)
    g = hexa.geometry
    R = pose[:3, :3]
    for i in range(6):
        b, p = np.asarray(g.legs[i].base_anchor), np.asarray(g.legs[i].platform_anchor)
        now = R.T @ (R @ p + pose[:3, 3] - b)
        home = p + g.home_translation - b
        cos = now @ home / np.linalg.norm(now) / np.linalg.norm(home)
        assert abs(cones.angles[i, 1] - np.arccos(np.clip(cos, -1, 1))) < 1e-9
    assert np.all(cones.limits[:, 1] == pytest.approx(np.radians(45.0)))


def test_cone_limit_is_named():
    hexa = hm.Hexapod.from_preset("3-6", compiled=False)
    sol = hexa.inverse(xyz_rpy_to_pose([0.0, 0.0, 0.22, 0.0, 0.0, 40.0]), check=False)
    cones = check_cones(hexa.closed_loop, hexa.geometry, sol.q)
    if not cones.within:
        assert cones.message().startswith("cone_limit: leg")


@pytest.mark.parametrize(
    ("field", "value", "words"),
    [
        ("leg_radius", 0.03, "must be below housing_radius"),
        ("platform_cone_deg", 100.0, "cone half-angle"),
        ("envelope", [0.1, 0.1], "6 finite half-widths"),
        ("min_clearance", -0.001, "must lie in [0"),
    ],
)
def test_body_field_errors_are_one_line(field, value, words):
    data = hm.get_preset("spherical").to_dict() | {field: value}
    with pytest.raises(hm.GeometryError) as err:
        hm.geometry_from_dict(data)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_body_fields_round_trip():
    g = replace(hm.get_preset("3-6"), leg_radius=0.01, min_clearance=0.002, envelope=(0.1, 0.1, 0.05, 0.5, 0.5, 0.5))
    assert hm.geometry_from_dict(g.to_dict()) == g


def test_cli_clearance_prints_the_pair_and_writes_json(tmp_path, capsys):
    out = tmp_path / "c.json"
    code = main(["clearance", str(THICK), "--pose", "0", "0", "0.4", "0", "0", "85", "--json", str(out)])
    assert code == 1
    text = capsys.readouterr().out
    report = json.loads(out.read_text())
    assert report["collision"] and report["pair"][0] in text and report["distance_m"] < 0
    assert main(["clearance", "reference"]) == 0


def test_clearance_input_errors(thick):
    with pytest.raises(hm.InputError, match="4x4 pose"):
        thick.clearance(np.zeros(5))
    with pytest.raises(hm.InputError, match="finite"):
        thick.clearance(np.full(thick.nq, np.nan))


def test_every_pair_once():
    hexa = hm.Hexapod.from_preset("reference", compiled=False)
    pairs = hm.kinematics.clearance.query_of(hexa).pairs
    assert len(set(pairs)) == len(pairs)
    assert all(a != b for a, b in itertools.chain(pairs))


@pytest.mark.parametrize("name", ["reference", "3-6", "guideway"])
def test_mjcf_carries_the_urdf_collision_bodies(name):
    import xml.etree.ElementTree as ET

    from hexapod_model.description.mjcf import COLLISION_GROUP, geometry_to_mjcf
    from hexapod_model.description.urdf import geometry_to_urdf

    geom = hm.get_preset(name)
    urdf = ET.fromstring(geometry_to_urdf(geom))
    capsules = {c.get("name") for c in urdf.iter("capsule")}
    bodies = {c.get("name"): c.find("geometry")[0] for c in urdf.iter("collision")}
    mjcf = ET.fromstring(geometry_to_mjcf(geom))
    geoms = {g.get("name"): g for g in mjcf.iter("geom") if g.get("group") == str(COLLISION_GROUP)}
    assert set(geoms) == set(bodies)
    for name_, shape in bodies.items():
        g = geoms[name_]
        assert g.get("contype") == g.get("conaffinity") == "0"
        assert g.get("type") == ("capsule" if name_ in capsules else shape.tag)
        assert float(g.get("size").split()[0]) == pytest.approx(float(shape.get("radius")), abs=1e-13)


def test_a_urdf_without_collision_bodies_is_named():
    import re

    from hexapod_model.description.model import ClosedLoopModel

    text = (ROOT / "urdf" / "reference.urdf").read_text()
    bare = re.sub(
        r"\s*<collision .*?</collision>|\s*<collision_checking>.*?</collision_checking>", "", text, flags=re.S
    )
    assert "<collision" not in bare
    with pytest.raises(hm.UrdfError, match="no collision bodies.*check_body=False") as err:
        hm.Hexapod(ClosedLoopModel(bare, "bare.urdf"), compiled=False)  # the body check cannot run: said
    assert "bare.urdf" in str(err.value) and "\n" not in str(err.value)
    hexa = hm.Hexapod(ClosedLoopModel(bare, "bare.urdf"), compiled=False, check_body=False)
    with pytest.raises(hm.UrdfError, match="no collision bodies") as err:
        hexa.clearance(hexa.q_home)
    assert "bare.urdf" in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("name", sorted(hm.PRESETS))
def test_every_preset_is_clear_at_home(name):
    """A bundled preset's home pose is one its machine takes: inverse kinematics reaches it, no two bodies touch.

    The guideway model's crossing struts, mirror images about a plane of symmetry with their
    platform joints on one circle, met exactly at home: a collision of its own home pose.
    """
    hexa = hm.Hexapod.from_preset(name, compiled=False)
    sol = hexa.inverse(hexa.home_pose, check=False)
    assert sol.status == "converged", sol.message
    clearance = hm.kinematics.clearance.query_of(hexa)(sol.q)
    assert clearance.distance > max(hexa.geometry.min_clearance, 1e-3), clearance
