"""MJCF export and Pinocchio's MJCF loader: same tree as the URDF, same kinematics, round trips, bad files."""

from __future__ import annotations

import functools
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.mjcf import geometry_to_mjcf, urdf_to_mjcf
from hexapod_model.description.mjcf_loader import load_mjcf, load_mjcf_text, read_equalities
from hexapod_model.description.model import ClosedLoopModel, same_placement
from hexapod_model.description.urdf import DECIMALS, leg_frame
from hexapod_model.exceptions import MjcfError

from ..conftest import PRESET_NAMES, hexapod, limits_only

MJCF_PAGE = (Path(__file__).resolve().parents[2] / "docs" / "mjcf.md").read_text()


@functools.cache
def mjcf_hexapod(name: str) -> hm.Hexapod:
    """Cached Hexapod of preset ``name`` loaded from its MJCF through Pinocchio's parser."""
    return hm.Hexapod(load_mjcf_text(geometry_to_mjcf(hm.get_preset(name)), f"{name}.xml"), check_body=False)


def per_leg_geometry() -> hm.HexapodGeometry:
    """A user geometry with per-leg strokes and Cardan axes (not the preset defaults)."""
    d = hm.get_preset("reference").to_dict()
    d["name"] = "per_leg"
    g = hm.get_preset("reference")
    for i, leg in enumerate(d["legs"]):
        leg["stroke"] = [-0.10 - 0.01 * i, 0.12 + 0.005 * i]
        w, _ = g.home_leg_axis(i)
        a = leg_frame(g, i)[:, 0]
        tilt = np.cos(0.1 * (i + 1)) * a + np.sin(0.1 * (i + 1)) * np.cross(w, a)  # base axis turned about the leg
        leg["base_axis"] = tilt.tolist()
        leg["platform_axis"] = (np.cos(0.2 * i) * a - np.sin(0.2 * i) * np.cross(w, a)).tolist()
    return hm.geometry_from_dict(d)


def assert_same_model(a: hm.Hexapod, b: hm.Hexapod) -> None:
    """Joint names and order, placements, limits, closures and home of two loaded hexapods agree."""
    ma, mb = a.model, b.model
    assert a.joint_names == b.joint_names and a.prismatic_names == b.prismatic_names
    assert [ma.joints[j].shortname() for j in range(ma.njoints)] == [
        mb.joints[j].shortname() for j in range(mb.njoints)
    ]
    for j in range(1, ma.njoints):
        assert same_placement(ma.jointPlacements[j], mb.jointPlacements[j]), ma.names[j]
    np.testing.assert_allclose(ma.lowerPositionLimit, mb.lowerPositionLimit, atol=1e-12)
    np.testing.assert_allclose(ma.upperPositionLimit, mb.upperPositionLimit, atol=1e-12)
    np.testing.assert_allclose(a.home_pose, b.home_pose, atol=1e-12)
    np.testing.assert_allclose(a.stroke, b.stroke, atol=1e-12)
    assert a.closed_loop.kind == b.closed_loop.kind
    for ca, cb in zip(a.constraint_models, b.constraint_models):
        assert type(ca) is type(cb) and ca.name == cb.name
        assert (ca.joint1_id, ca.joint2_id) == (cb.joint1_id, cb.joint2_id)
        assert same_placement(ca.joint1_placement, cb.joint1_placement)
        assert same_placement(ca.joint2_placement, cb.joint2_placement)
    assert b.closure_residual(b.q_home).max() < 1e-12


def worst_disagreement(name: str, n: int, seed: int) -> tuple[int, dict[str, float]]:
    """IK and FK of ``n`` random box poses through the URDF and the MJCF path: solves, worst gaps."""
    urdf, mjcf = limits_only(name), mjcf_hexapod(name)  # the kinematics: the MJCF carries no cones
    worst = dict.fromkeys(("ik lengths", "ik q", "fk pose", "fk q", "candidates", "near closure"), 0.0)
    solved = 0
    for T in box_poses(urdf.home_pose, n, seed=seed):
        a, b = urdf.inverse(T, check=False), mjcf.inverse(T, check=False)
        assert a.status == b.status
        if not a.converged:
            continue
        fa, fb = urdf.forward(a.lengths, check=False), mjcf.forward(a.lengths, check=False)
        assert fa.status == fb.status  # (3-6: ambiguous_assembly alike, the layout read off the MJCF)
        assert len(fa.candidates) == len(fb.candidates)
        solved += 1
        pairs = [("ik lengths", a.lengths, b.lengths), ("ik q", a.q, b.q)]
        if fa.converged:
            pairs += [("fk pose", fa.pose, fb.pose), ("fk q", fa.q, fb.q)]
        # exact candidates come from the 3-6 resultant of each model's own layout (read to 1e-13 m
        # off the file) and come first; the noise-reach ones (Assemblies.near, last) are poses of
        # readings moved by up to the reach along an estimated root gap, a move that two layouts
        # 1e-13 m apart reproduce to about 1e-6 m, amplified near the fold: each must instead be an
        # assembly of the other model for its own moved readings (inverse kinematics, 1e-12 m)
        near_a, near_b = urdf.assemblies(a.lengths).near, mjcf.assemblies(a.lengths).near
        assert len(near_a) == len(near_b)
        exact = len(fa.candidates) - len(near_a)
        pairs += [("candidates", np.asarray(x), np.asarray(y)) for x, y in zip(fa.candidates[:exact], fb.candidates)]
        for key, x, y in pairs:
            worst[key] = max(worst[key], float(np.abs(x - y).max()))
        for s, other in [(s, mjcf) for s in near_a] + [(s, urdf) for s in near_b]:
            closure = float(np.abs(other.inverse(s.pose, check=False).lengths - s.lengths).max())
            worst["near closure"] = max(worst["near closure"], closure)
    return solved, worst


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_pinocchio_mjcf_loader_gives_the_urdf_kinematics(name):
    solved, worst = worst_disagreement(name, 200, seed=11)
    assert solved >= 190, solved  # the box is inside every preset's workspace but for a few corners
    assert worst.pop("candidates") < 1e-10, worst  # m and rotation-matrix entries
    assert max(worst.values()) < 1e-12, worst


@pytest.mark.slow
@pytest.mark.parametrize("name", PRESET_NAMES)
def test_pinocchio_mjcf_loader_on_1000_poses(name):
    solved, worst = worst_disagreement(name, 1000, seed=12)
    assert solved >= 950, solved
    assert worst.pop("candidates") < 1e-10, worst  # m and rotation-matrix entries
    assert max(worst.values()) < 1e-12, worst


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_round_trip_of_every_preset(name):
    assert_same_model(hexapod(name), mjcf_hexapod(name))
    names = [f.name for f in mjcf_hexapod(name).model.frames]
    assert len(set(names)) == len(names)  # model.getFrameId(name) works for every frame


def test_round_trip_of_a_per_leg_geometry_file(tmp_path):
    geom = per_leg_geometry()
    path = tmp_path / "per_leg.json"
    path.write_text(json.dumps(geom.to_dict()))
    from_file = hm.Hexapod.load(path)
    (tmp_path / "per_leg.xml").write_text(geometry_to_mjcf(hm.load_geometry(path)))
    back = hm.Hexapod.load(tmp_path / "per_leg.xml")
    assert_same_model(from_file, back)
    assert len({tuple(s) for s in back.stroke}) == 6  # the per-leg values made it through
    lengths = np.array([0.01, -0.02, 0.015, 0.0, -0.005, 0.02])
    np.testing.assert_allclose(back.forward(lengths).pose, from_file.forward(lengths).pose, atol=1e-12)


def _rotated_home_urdf(angle: float) -> str:
    """The reference URDF with its platform frame turned by ``angle`` (rad) about z at home."""
    from hexapod_model.description.urdf import _rpy, format_number

    root = ET.fromstring(hm.geometry_to_urdf(hm.get_preset("reference")))
    Rz = pin.rpy.rpyToMatrix(0.0, 0.0, angle)
    for j in root.findall("joint"):
        origin = j.find("origin")
        if j.get("name") == "platform_joint":
            origin.set("rpy", f"0 0 {format_number(angle)}")
        elif j.find("parent").get("link") == "platform":
            xyz = np.array([float(v) for v in origin.get("xyz").split()])
            R = pin.rpy.rpyToMatrix(*[float(v) for v in origin.get("rpy").split()])
            origin.set("xyz", " ".join(format_number(v) for v in Rz.T @ xyz))
            origin.set("rpy", _rpy(Rz.T @ R))
    return ET.tostring(root, encoding="unicode")


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_mjcf_has_a_light_and_a_floor_that_touches_nothing(name):
    """MuJoCo renders a scene without a light dark: one light above, a floor plane below every geom."""
    root = ET.fromstring(geometry_to_mjcf(hm.get_preset(name)))
    world = root.find("worldbody")
    lights = world.findall("light")
    assert len(lights) == 1 and float(lights[0].get("pos").split()[2]) > 0
    (floor,) = [g for g in world.findall("geom") if g.get("type") == "plane"]
    assert floor.get("contype") == "0" and floor.get("conaffinity") == "0"  # never a contact with the model
    z_floor = float(floor.get("pos").split()[2])
    base = world.find("body")
    lowest = min(
        float(g.get("pos", "0 0 0").split()[2]) - float(g.get("size").split()[-1])
        for g in base.findall("geom")
        if g.get("type") in ("cylinder", "box", "sphere")
    )
    assert z_floor < lowest  # below the base plate: no geom of the model under it


def test_rotated_home_pose_survives_pinocchio_free_flyer_placement():
    """Pinocchio 4.1 places a rotated free body at (I, p - R p); the loader puts it back at home."""
    text = _rotated_home_urdf(0.4)
    urdf = hm.Hexapod(ClosedLoopModel(text))
    mjcf = hm.Hexapod(load_mjcf_text(urdf_to_mjcf(text)))
    assert_same_model(urdf, mjcf)
    assert abs(np.arctan2(mjcf.home_pose[1, 0], mjcf.home_pose[0, 0]) - 0.4) < 1e-12
    lengths = np.array([0.02, 0.0, -0.01, 0.01, 0.0, -0.02])
    np.testing.assert_allclose(mjcf.forward(lengths).pose, urdf.forward(lengths).pose, atol=1e-12)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_mjcf_holds_the_urdf_tree_closures_and_actuators(name):
    urdf_root = ET.fromstring(hm.geometry_to_urdf(hm.get_preset(name)))
    text = geometry_to_mjcf(hm.get_preset(name), actuated=True)
    root = ET.fromstring(text)
    kinds = {"revolute": "hinge", "prismatic": "slide"}
    joints = {j.get("name"): j for j in root.iter("joint") if j.get("name")}
    for uj in urdf_root.findall("joint"):
        if uj.get("type") in kinds:
            mj = joints.pop(uj.get("name"))
            assert mj.get("type") == kinds[uj.get("type")]
            assert mj.get("axis") == uj.find("axis").get("xyz")
            assert mj.get("range") == f"{uj.find('limit').get('lower')} {uj.find('limit').get('upper')}"
    assert not joints  # nothing else, and one free joint for the platform
    assert [f.get("name") for f in root.iter("freejoint")] == ["platform_joint"]
    assert [b.get("name") for b in root.find("worldbody").findall("body")] == ["base_link"]  # the tree Pinocchio reads
    closures = hm.read_closures(hm.geometry_to_urdf(hm.get_preset(name)))
    tag = "weld" if closures[0].kind == "6d" else "connect"
    eq = [el for el in root.find("equality") if el.tag == tag]
    assert [(e.get("name"), e.get("site1"), e.get("site2")) for e in eq] == [
        (c.name, f"{c.link1}_site", f"{c.link2}_site") for c in closures
    ]
    for k in range(1, 7):  # a comment says which closure is which leg
        assert re.search(rf"<!-- leg{k}: the tip of the leg of leg{k}_prismatic \(leg{k}_tip\)", text)
    acts = root.find("actuator").findall("position")
    assert [a.get("joint") for a in acts] == list(hexapod(name).prismatic_names)
    for a, (lo, hi) in zip(acts, hexapod(name).stroke):
        assert [float(v) for v in a.get("ctrlrange").split()] == [lo, hi]
    assert geometry_to_mjcf(hm.get_preset(name)).count("<position") == 0


def test_numbers_are_written_with_fixed_precision():
    """The bytes do not depend on the machine: fixed decimals, no exponent, no -0."""
    for name in PRESET_NAMES:
        text = geometry_to_mjcf(hm.get_preset(name), actuated=True)
        for attr in ("pos", "quat", "size", "range", "axis", "rgba", "diaginertia", "mass", "solref", "solimp", "kp"):
            for value in " ".join(re.findall(rf' {attr}="([^"]*)"', text)).split():
                assert "e" not in value and value != "-0", (attr, value)
                assert len(value.partition(".")[2]) <= DECIMALS, (attr, value)


def test_visuals_that_cannot_be_translated_are_named_in_the_file():
    text = hm.geometry_to_urdf(hm.get_preset("spherical"))
    text = text.replace('<cylinder radius="0.02"', '<mesh filename="package://x/leg.stl"', 1)
    text = re.sub(r'(<mesh filename="package://x/leg.stl")[^/]*/>', r"\1/>", text)
    out = urdf_to_mjcf(text)
    assert re.search(r"<!-- visuals left out .*leg1_base_cross_visual1 \(mesh\)", out)
    assert load_mjcf_text(out).kind == "3d"


def _reference_mjcf() -> str:
    return geometry_to_mjcf(hm.get_preset("reference"))


@pytest.mark.parametrize(
    "edit, pattern",
    [
        (lambda t: re.sub(r"<weld [^>]*/>", "", t), "declares no weld or connect"),
        (lambda t: t.replace('site1="leg2_tip_site"', 'body1="leg2_tip"'), r"equality lacks \['site1'\]"),
        (lambda t: t.replace('<weld name="leg3"', '<weld active="false" name="leg3"'), "inactive equality"),
        (lambda t: t.replace('site2="leg4_anchor_site"', 'site2="leg4_nowhere"'), "names a site missing from"),
        (
            lambda t: t.replace('site2="leg4_anchor_site"', 'site2="s"').replace(
                "</worldbody>", '<body name="b"><site name="s"/></body></worldbody>'
            ),
            "names a site missing from the first body",
        ),
        (lambda t: re.sub(r"<worldbody>.*</worldbody>", "<worldbody/>", t, flags=re.S), "no <body> under"),
        (lambda t: t.replace("</equality>", '<joint joint1="leg1_roll" /></equality>'), "only weld and connect"),
        (
            lambda t: t.replace('name="leg1_roll" type="hinge"', 'name="leg1_roll" ref="0.1" type="hinge"'),
            r"must be zero.*'leg1_roll'",
        ),
        (lambda t: t.replace('<weld name="leg5"', '<connect name="leg5"'), "same type"),
        (
            lambda t: t.replace(
                'site1="leg1_tip_site" site2="leg1_anchor_site"', 'site1="leg1_anchor_site" site2="leg1_tip_site"'
            ),
            "must be fixed to the platform",
        ),
        (lambda t: re.sub(r'(<body name="leg2_anchor" pos=")([^ ]+)', r"\g<1>0.3", t), "does not close the loop"),
        (lambda t: t.replace("<mujoco ", "<robot ").replace("</mujoco>", "</robot>"), "root element"),
        (lambda t: t.replace("</mujoco>", ""), "not well-formed"),
    ],
)
def test_malformed_mjcf_is_rejected(edit, pattern, tmp_path):
    path = tmp_path / "bad.xml"
    path.write_text(edit(_reference_mjcf()))
    with pytest.raises(MjcfError, match=pattern) as err:
        hm.Hexapod.load(path)
    assert str(path) in str(err.value) and isinstance(err.value, hm.UrdfError)


def test_missing_file_and_equalities_in_file_order(tmp_path):
    with pytest.raises(MjcfError, match="cannot read MJCF"):
        load_mjcf(tmp_path / "nope.xml")
    closures = read_equalities(_reference_mjcf())
    assert [(c.name, c.kind, c.link1) for c in closures] == [(f"leg{i}", "6d", f"leg{i}_tip_site") for i in range(1, 7)]


def test_viewer_geometry_of_an_mjcf_hexapod():
    visual = mjcf_hexapod("reference").closed_loop.visual_model()
    names = {g.name for g in visual.geometryObjects}
    assert len(names) == len(hexapod("reference").closed_loop.visual_model().geometryObjects)
    assert {"base_link_visual0", "leg1_cylinder_visual0", "platform_visual0"} <= names


def python_block(text: str, marker: str) -> str:
    """The ```python block of ``text`` that contains ``marker``."""
    return next(b for b in re.findall(r"```python\n(.*?)```", text, re.S) if marker in b)


def test_mjcf_page_python_block_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "reference.xml").write_text(geometry_to_mjcf(hm.get_preset("reference"), actuated=True))
    env: dict = {}
    exec(compile(python_block(MJCF_PAGE, "buildModelAndConstraintsFromMJCF"), "docs/mjcf.md", "exec"), env)
    assert len(env["welds"]) == 6 and len(env["connects"]) == 0 and env["model"].nq == env["hexa"].nq
    assert env["hexa"].forward(np.full(6, 0.01)).converged
