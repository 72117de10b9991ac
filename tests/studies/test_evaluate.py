"""Jakobović and Jelenković (2002) §II-III: eliminated leg Jacobian, workspace for an orientation cone, `evaluate`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.jacobian import evaluate_jacobian, kinematic_evaluation, leg_jacobian, textbook_jacobian
from hexapod_model.analysis.workspace import compute_slice, cone_rotations
from hexapod_model.cli.main import main
from hexapod_model.lie import rpy_to_matrix
from hexapod_model.studies.evaluate import Settings, run_evaluation

ROOT = Path(__file__).resolve().parents[2]
MODEL1 = ROOT / "docs" / "geometries" / "seed002_model1.toml"
MODEL2 = ROOT / "docs" / "geometries" / "seed002_model2.toml"


def _pose(hexa, dx, rpy):
    T = hexa.home_pose.copy()
    T[:3, 3] += dx
    T[:3, :3] = rpy_to_matrix(*rpy) @ T[:3, :3]
    return T


@pytest.fixture(scope="module", params=["reference", "spherical", "guideway", "3-6"])
def case(request):
    hexa = hm.Hexapod.from_preset(request.param)
    sol = hexa.inverse(_pose(hexa, [0.012, -0.018, 0.01], [0.12, -0.07, 0.2]))
    return hexa, sol


def test_jacobian_inverts_finite_differences_of_forward_solve(case):
    """J times the twist per unit reading change (central differences of FK) is the identity."""
    hexa, sol = case
    J = leg_jacobian(hexa, sol.q)
    eps, X = 1e-6, np.zeros((6, 6))
    R0 = sol.pose[:3, :3]
    for k in range(6):
        poses = []
        for s in (1.0, -1.0):
            lengths = sol.lengths.copy()
            lengths[k] += s * eps
            T = hexa.forward(lengths, guess=sol, tol=1e-13).pose
            poses.append(pin.SE3(T[:3, :3], T[:3, 3]))
        xi = pin.log6(poses[1].inverse() * poses[0]).vector / (2 * eps)  # platform frame
        X[:, k] = np.r_[R0 @ xi[:3], R0 @ xi[3:]]  # base frame [v; w]
    assert np.abs(J @ X - np.eye(6)).max() < 1e-6


def test_twist_convention_is_base_frame_velocity_of_platform_origin(case):
    """Move the platform origin along base x and turn about base z (about the origin): the IK
    readings change by J's columns 0 and 5."""
    hexa, sol = case
    J, eps = leg_jacobian(hexa, sol.q), 1e-6
    for col, make in (
        (0, lambda e: (np.array([e, 0, 0]), np.eye(3))),
        (5, lambda e: (np.zeros(3), rpy_to_matrix(0, 0, e))),
    ):
        dl = []
        for s in (1.0, -1.0):
            d, Rz = make(s * eps)
            T = sol.pose.copy()
            T[:3, 3] += d
            T[:3, :3] = Rz @ T[:3, :3]
            dl.append(hexa.inverse(T, guess=sol, tol=1e-13).lengths)
        np.testing.assert_allclose((dl[0] - dl[1]) / (2 * eps), J[:, col], atol=1e-6)


def test_spherical_preset_matches_textbook_eq4():
    hexa = hm.Hexapod.from_preset("spherical")
    g = hexa.geometry
    for dx, rpy in (([0, 0, 0], [0, 0, 0]), ([0.03, 0.01, -0.04], [0.2, -0.1, 0.35])):
        sol = hexa.inverse(_pose(hexa, dx, rpy))
        Jt = textbook_jacobian(g.base_points(), g.platform_points(), sol.pose)
        np.testing.assert_allclose(leg_jacobian(hexa, sol.q), Jt, atol=1e-12)


def test_offset_cardan_jacobian_differs_from_textbook():
    """The 12 mm offsets change the relation: the eliminated J is not eq. 4 (the point of eliminating)."""
    hexa = hm.Hexapod.from_preset("reference")
    g = hexa.geometry
    sol = hexa.inverse(_pose(hexa, [0.02, 0, 0], [0.1, 0.2, 0]))
    Jt = textbook_jacobian(g.base_points(), g.platform_points(), sol.pose)
    assert np.abs(leg_jacobian(hexa, sol.q) - Jt).max() > 1e-3


def test_figures_are_consistent_and_unit_scaling_acts_on_rotation_columns():
    hexa = hm.Hexapod.from_preset("reference")
    e1 = kinematic_evaluation(hexa, hexa.q_home)
    s = e1.singular_values
    assert np.all(np.diff(s) <= 0)
    assert e1.condition_number == pytest.approx(s[0] / s[-1])
    assert e1.abs_det == pytest.approx(abs(np.linalg.det(e1.jacobian)), rel=1e-9)
    e2 = evaluate_jacobian(e1.jacobian, 0.1)
    np.testing.assert_array_equal(e2.jacobian[:, :3], e1.jacobian[:, :3])
    np.testing.assert_allclose(e2.jacobian[:, 3:], e1.jacobian[:, 3:] / 0.1)


def test_singular_pose_has_vanishing_sigma_min():
    """The spherical preset is singular at 90 deg yaw (classic 6-6 singularity)."""
    hexa = hm.Hexapod.from_preset("spherical")
    near = kinematic_evaluation(hexa, hexa.inverse(_pose(hexa, [0, 0, 0], [0, 0, np.radians(90)])).q)
    far = kinematic_evaluation(hexa, hexa.q_home)
    assert near.sigma_min < 1e-9 * far.sigma_min
    assert near.abs_det < 1e-9 * far.abs_det


def test_cone_rotations_tilt_the_tool_axis_by_the_cone_angle():
    R = cone_rotations(20.0, 6)
    assert R.shape == (7, 3, 3)
    tilt = np.degrees(np.arccos(R[:, 2, 2]))
    np.testing.assert_allclose(tilt, [0] + [20] * 6, atol=1e-12)
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.tile(np.eye(3), (7, 1, 1)), atol=1e-12)
    # no spin about the tool axis: the tilt axis is horizontal, so R's x column stays in the tilt plane
    for Rk in R[1:]:
        axis = pin.log3(Rk)
        assert abs(axis[2]) < 1e-12


def test_slice_contains_home_and_excludes_far_points():
    hexa = hm.Hexapod.load(str(MODEL1))
    home = hexa.home_pose[:3, 3]
    xs = home[0] + np.array([-2.0, 0.0, 2.0])
    r = compute_slice(hexa, 0, home[2], xs, np.array([home[1]]), cone_rotations(10, 4), 0.25)
    assert r.inside.tolist() == [[False, True, False]]
    assert np.isnan(r.kappa[0, 0]) and np.isfinite(r.kappa[0, 1]) and r.kappa[0, 1] >= 1.0


def test_seed002_models_load_with_table1_dimensions():
    g1, g2 = hm.load_geometry(MODEL1), hm.load_geometry(MODEL2)
    assert g1.joint_type == "spherical" and g2.joint_type == "guideway"
    lengths = np.array([g1.home_leg_axis(i)[1] for i in range(6)])
    np.testing.assert_allclose(lengths + np.array([leg.stroke for leg in g1.legs]).T, [[0.45] * 6, [0.85] * 6])
    np.testing.assert_allclose(np.linalg.norm(g1.base_points()[:, :2], axis=1), 0.50)
    np.testing.assert_allclose(np.linalg.norm(g1.platform_points()[:, :2], axis=1), 0.25)
    np.testing.assert_allclose(np.linalg.norm(g2.platform_points()[:, :2], axis=1), 0.30)
    rail = np.array([leg.stroke for leg in g2.legs])
    np.testing.assert_allclose(rail[:, 1] - rail[:, 0], 0.999 * np.hypot(0.65, 0.20))  # r 75 -> 10, h 20
    assert np.degrees(g1.cardan_limit) == pytest.approx(45) and np.degrees(g2.cardan_limit) == pytest.approx(45)
    hm.Hexapod.from_geometry(g2)  # assembles at home


def test_model1_averages_near_paper_table2():
    """Our reading of Jakobović and Jelenković (2002) (rotations normalised by the platform radius) reproduces Table II
    for model 1 within a few per cent even on a coarse grid."""
    r = run_evaluation(str(MODEL1), Settings(grid=9, cone_deg=15, cone_samples=4), workers=1)
    assert r["points_inside"] > 10
    assert r["average"]["kappa"] == pytest.approx(1.835, rel=0.1)
    assert r["average"]["sigma_min"] == pytest.approx(1.022, rel=0.1)
    assert r["average"]["abs_det"] == pytest.approx(5.842, rel=0.15)


def test_evaluate_command_writes_figure_and_resumes(tmp_path, capsys):
    out, js = tmp_path / "ev", tmp_path / "ev.json"
    argv = [
        "evaluate",
        "3-6",
        "--grid",
        "5",
        "--cone-samples",
        "3",
        "--workers",
        "2",
        "--out",
        str(out),
        "--json",
        str(js),
    ]
    assert main(argv) == 0
    first = json.loads(js.read_text())
    assert (out / "evaluate_sections.png").stat().st_size > 1000
    assert first["points_inside"] > 0 and first["volume_m3"] > 0 and first["resumed_slices"] == 0
    assert main(argv) == 0  # all slices come from the checkpoint
    second = json.loads(js.read_text())
    assert second["resumed_slices"] == second["grid"]["nz"]
    assert second["points_inside"] == first["points_inside"]
    assert "paper" in capsys.readouterr().out


def test_urdf_without_geometry_gets_its_sizes_from_the_model(tmp_path):
    from hexapod_model.studies.evaluate import platform_radius
    from hexapod_model.tracking.tracker import characteristic_length

    path = tmp_path / "ref.urdf"
    path.write_text(hm.geometry_to_urdf(hm.get_preset("reference")))
    bare, preset = hm.Hexapod.load(str(path)), hm.Hexapod.from_preset("reference")
    assert bare.geometry is None
    assert platform_radius(bare) == pytest.approx(platform_radius(preset), rel=0.02)
    assert characteristic_length(bare) == pytest.approx(characteristic_length(preset), rel=0.02)


def test_slices_on_dask_workers_equal_the_slices_in_this_process():
    """The same slices computed by two LocalCluster workers and in this process: the same workspace."""
    pytest.importorskip("distributed", reason="pip install -e '.[sweep]'")
    settings = Settings(grid=5, cone_deg=10, cone_samples=3)
    here = run_evaluation("3-6", settings, workers=1)
    there = run_evaluation("3-6", settings, workers=2)
    assert here["points_inside"] == there["points_inside"] > 0
    np.testing.assert_array_equal(here["_arrays"]["inside"], there["_arrays"]["inside"])
    for key in ("kappa", "sigma_min", "abs_det"):
        assert here["average"][key] == pytest.approx(there["average"][key], rel=1e-12)
    for key, value in here["worst"].items():
        assert value == pytest.approx(there["worst"][key], rel=1e-12)
