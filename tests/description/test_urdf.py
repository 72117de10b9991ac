"""Generated URDFs: contract, both parsers, drift against urdf/, malformed files."""

from __future__ import annotations

import io
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

import hexapod_model as hm
from hexapod_model.description.model import ClosedLoopModel

from ..conftest import PRESET_NAMES, hexapod

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_committed_urdf_matches_generator(name):
    path = ROOT / "urdf" / f"{name}.urdf"
    assert path.read_text() == hm.geometry_to_urdf(hm.get_preset(name)), (
        f"{path} drifted from the generator: run python scripts/generate_urdfs.py"
    )


def test_generate_script_check_mode():
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "generate_urdfs.py"), "--check"], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stdout + out.stderr


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_contract_holds_in_pinocchio_and_yourdfpy(name):
    text = (ROOT / "urdf" / f"{name}.urdf").read_text()
    robot = yourdfpy.URDF.load(io.StringIO(text), build_scene_graph=True, load_meshes=False)
    floating = [j for j in robot.robot.joints if j.type == "floating"]
    assert len(floating) == 1 and floating[0].parent == robot.base_link == "base_link"
    closures = hm.read_closures(text)
    assert [c.name for c in closures] == [f"leg{i}" for i in range(1, 7)]
    kind = "3d" if hm.get_preset(name).joint_type != "cardan" else "6d"
    assert {c.kind for c in closures} == {kind}
    for c in closures:  # exactly one prismatic joint from the base to each tip
        chain, link = [], c.link1
        parents = {j.child: j for j in robot.robot.joints}
        while link != robot.base_link:
            chain.append(parents[link])
            link = parents[link].parent
        assert sum(j.type == "prismatic" for j in chain) == 1
        assert all(j.limit is not None for j in chain if j.type in ("revolute", "prismatic"))
    model = pin.buildModelFromXML(text)
    assert sum(model.joints[j].shortname() == "JointModelFreeFlyer" for j in range(model.njoints)) == 1
    clm = ClosedLoopModel(text)
    assert clm.closure_errors(pin.neutral(model)).max() < 1e-12  # zero configuration is assembled
    # the floating joint's origin is the home pose
    assert np.allclose(clm.home.translation, [0, 0, hm.get_preset(name).home_height])


def test_urdf_has_visuals_for_a_viewer():
    text = hm.geometry_to_urdf(hm.get_preset("reference"))
    geom = pin.buildGeomFromUrdfString(pin.buildModelFromXML(text), text, pin.GeometryType.VISUAL)
    names = " ".join(g.name for g in geom.geometryObjects)
    for part in ("base_link", "platform", "cylinder", "rod", "base_yoke", "platform_cross"):
        assert part in names


def _reference_text() -> str:
    return hm.geometry_to_urdf(hm.get_preset("reference"))


@pytest.mark.parametrize(
    "edit, pattern",
    [
        (lambda t: t.replace('type="floating"', 'type="fixed"'), "exactly one floating joint"),
        (lambda t: t.replace('link2="leg3_anchor"', 'link2="leg3_nowhere"'), "names a missing link2"),
        (lambda t: re.sub(r"<loop_closure[^>]*/>", "", t), "declares no <loop_closure>"),
        (
            lambda t: t.replace('name="leg2_roll" type="revolute"', 'name="leg2_roll" type="prismatic"'),
            "exactly one prismatic joint, found 2",
        ),
        (
            lambda t: t.replace('name="leg5_roll" type="revolute"', 'name="leg5_roll" type="continuous"'),
            "unsupported joint type",
        ),
        (lambda t: t.replace('type="6d" link1="leg4_tip"', 'type="3d" link1="leg4_tip"'), "same type"),
        (
            lambda t: t.replace('link1="leg1_tip" link2="leg1_anchor"', 'link1="leg1_anchor" link2="leg1_tip"'),
            "must be fixed to the platform",
        ),
        (lambda t: t.replace('<robot name="reference">', '<robot name="reference"'), "not well-formed XML"),
    ],
)
def test_malformed_urdf_is_rejected(edit, pattern):
    with pytest.raises(hm.UrdfError, match=pattern):
        ClosedLoopModel(edit(_reference_text()), "bad.urdf")


def test_urdf_whose_zero_configuration_is_not_assembled():
    text = _reference_text()
    m = re.search(r'(<joint name="leg2_anchor_joint" type="fixed">\s*<origin xyz=")([^ ]+)', text)
    moved = text[: m.start(2)] + repr(float(m.group(2)) + 0.01) + text[m.end(2) :]
    with pytest.raises(hm.UrdfError, match="does not close the loop"):
        ClosedLoopModel(moved)


def test_from_urdf_file_and_missing_file(tmp_path):
    path = hm.write_urdf(hm.get_preset("3-6"), tmp_path / "s.urdf")
    hexa = hm.Hexapod.from_urdf(path)
    assert hexa.closed_loop.kind == "3d" and hexa.geometry is None
    with pytest.raises(hm.UrdfError, match="cannot read URDF"):
        hm.Hexapod.from_urdf(tmp_path / "nope.urdf")


def test_preset_by_name_equals_loaded_file():
    a = hexapod("reference")
    b = hm.Hexapod.from_urdf(ROOT / "urdf" / "reference.urdf")
    assert a.joint_names == b.joint_names
    np.testing.assert_array_equal(a.stroke, b.stroke)


def test_numbers_are_written_with_fixed_precision():
    """Generated bytes must not depend on the last bits of a machine's floating point."""
    from hexapod_model.description.urdf import DECIMALS, format_number

    assert format_number(-7.4e-18) == "0" and format_number(-0.0) == "0" and format_number(4e-14) == "0"
    assert format_number(0.1 + 1e-17) == "0.1" == format_number(0.1 - 1e-17)
    assert format_number(-0.25) == "-0.25" and format_number(3.0) == "3"
    assert format_number(1 / 3) == "0." + "3" * DECIMALS
    for name in PRESET_NAMES:
        text = (ROOT / "urdf" / f"{name}.urdf").read_text()
        numbers = re.findall(r'(?:xyz|rpy|size|radius|length|lower|upper)="([^"]*)"', text)
        for value in " ".join(numbers).split():
            assert "e" not in value and value != "-0", value
            assert len(value.partition(".")[2]) <= DECIMALS, value


def test_validate_urdf_names_the_problem_yourdfpy_finds():
    from hexapod_model.description.urdf import validate_urdf

    text = (ROOT / "urdf" / "reference.urdf").read_text()
    validate_urdf(text)  # the generated files pass
    bad = text.replace('type="revolute"', 'type="revolut"', 1)
    with pytest.raises(hm.UrdfError, match="revolut"):
        validate_urdf(bad, "bad.urdf")
    with pytest.raises(hm.UrdfError, match="not a valid URDF"):
        ClosedLoopModel(bad, "bad.urdf")  # Pinocchio's rejection is explained by yourdfpy's finding


def test_written_rpy_reproduces_the_rotation_at_and_near_gimbal_lock():
    """An ``<origin>``'s ``rpy`` gives back its rotation to the written precision (1e-13 rad), at pitch +-90 deg too."""
    from hexapod_model.description.urdf import _rpy
    from hexapod_model.lie import rpy_to_matrix

    rng = np.random.default_rng(41)
    R = [pin.exp3(rng.normal(size=3)) for _ in range(50)]
    for pitch in (np.pi / 2, -np.pi / 2, np.pi / 2 - 1e-9, -np.pi / 2 + 1e-6):
        R += [pin.rpy.rpyToMatrix(roll, pitch, yaw) for roll, yaw in ((0.3, -1.2), (-2.9, 0.0), (1.0, 2.0))]
    for Rk in R:
        rpy = [float(v) for v in _rpy(Rk).split()]
        np.testing.assert_allclose(rpy_to_matrix(*rpy), Rk, rtol=0, atol=1e-12)
