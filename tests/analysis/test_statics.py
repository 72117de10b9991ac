"""Statics of the locked fixture: virtual work by finite differences, MuJoCo's constraint forces at rest."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.statics import (
    fixture_stiffness,
    joint_centres,
    leg_forces,
    loads_at,
    wrench_at_origin,
)
from hexapod_model.cli.main import main
from hexapod_model.description.mjcf import geometry_to_mjcf
from hexapod_model.description.mjcf_loader import mujoco_qpos
from hexapod_model.exceptions import InputError
from hexapod_model.lie import rpy_to_matrix

from ..conftest import PRESET_NAMES, hexapod

VIRTUAL_WORK_TOL = 1e-8  # W . dx - t . dl per unit wrench, central differences of IK (step 1e-6 m, rad)
MUJOCO_TOL = 1e-5  # leg forces and leg wrenches, relative to the largest leg force
MUJOCO_MOMENT_TOL = 1e-4  # Cardan moments, relative to the largest Cardan moment
WRENCH = np.array([30.0, -50.0, 200.0, 5.0, -8.0, 3.0])  # N, N m


def _pose(hexa, offset=(0.01, -0.02, 0.015), rpy=(0.1, -0.05, 0.2)):
    T = hexa.home_pose.copy()
    T[:3, 3] += offset
    T[:3, :3] = rpy_to_matrix(*rpy)
    return T


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_virtual_work_by_finite_differences(name):
    """For every platform twist direction, the work of the wrench equals the work of the leg forces on the
    leg length changes that inverse kinematics gives (central differences)."""
    hexa = hexapod(name)
    T = _pose(hexa)
    loads = leg_forces(hexa, T, WRENCH, frame="base")
    sol = hexa.inverse(T)
    eps = 1e-6
    for k in range(6):
        dl = []
        for s in (1.0, -1.0):
            xi = np.zeros(6)
            xi[k] = s * eps
            T2 = T.copy()
            T2[:3, 3] += xi[:3]
            T2[:3, :3] = pin.exp3(xi[3:]) @ T[:3, :3]
            dl.append(hexa.inverse(T2, guess=sol, tol=1e-13).lengths)
        work = loads.axial_force @ ((dl[0] - dl[1]) / (2 * eps))
        assert abs(work - WRENCH[k]) < VIRTUAL_WORK_TOL * np.abs(WRENCH).max(), (k, work, WRENCH[k])


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_platform_equilibrium_and_two_force_members(name):
    """The leg wrenches balance the applied one; only offset Cardans carry moments (and transverse force)."""
    hexa = hexapod(name)
    T = _pose(hexa)
    loads = leg_forces(hexa, T, WRENCH, frame="base")
    platform_c, _ = joint_centres(hexa, hexa.inverse(T).q)
    o = T[:3, 3]
    np.testing.assert_allclose(loads.leg_force.sum(0), -WRENCH[:3], atol=1e-9)
    moments = loads.platform_moment + np.cross(platform_c - o, loads.leg_force)
    np.testing.assert_allclose(moments.sum(0), -WRENCH[3:], atol=1e-9)
    scale = loads.largest_axial_force
    offsets = hexa.geometry.base_offset + hexa.geometry.platform_offset
    if name == "reference":
        assert np.abs(loads.platform_moment).max() > 1e-4 * scale  # not a two-force member
        assert loads.transverse_force.max() > 1e-4 * scale
    elif hexa.closed_loop.kind == "3d" or offsets == 0.0:
        assert np.abs(loads.platform_moment).max() < 1e-10 * scale  # ball joint / intersecting axes
    if name in ("intersecting", "spherical", "3-6"):
        assert loads.transverse_force.max() < 1e-10 * scale
        assert np.abs(loads.base_moment).max() < 1e-10 * scale


def test_wrench_frames_and_points():
    """A force at a tool point in platform coordinates equals its base-frame force plus moment."""
    hexa = hexapod("reference")
    T = _pose(hexa)
    f, p = np.array([10.0, -20.0, 5.0]), np.array([0.02, 0.03, 0.15])
    a = leg_forces(hexa, T, np.r_[f, 0, 0, 0], frame="platform", point=p)
    R, o = T[:3, :3], T[:3, 3]
    b = leg_forces(hexa, T, np.r_[R @ f, 0, 0, 0], frame="base", point=o + R @ p)
    c = leg_forces(hexa, T, np.r_[R @ f, np.cross(R @ p, R @ f)], frame="base")
    np.testing.assert_allclose(a.axial_force, b.axial_force, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(a.axial_force, c.axial_force, rtol=1e-12, atol=1e-12)
    with pytest.raises(InputError, match="frame"):
        wrench_at_origin(T, np.zeros(6), frame="tool")
    with pytest.raises(InputError, match="wrench"):
        leg_forces(hexa, T, [1.0, 2.0])


def test_stiffness_against_forward_kinematics():
    """Legs as springs: lengthen each by t/k and the platform moves by K^-1 W (small loads)."""
    hexa = hexapod("reference")
    T, k = _pose(hexa), 2.0e7
    W = WRENCH * 1e-3
    stiff = fixture_stiffness(hexa, T, k)
    loads = leg_forces(hexa, T, W, frame="base")
    sol = hexa.inverse(T)
    moved = hexa.forward(sol.lengths + loads.axial_force / k, guess=sol, tol=1e-14).pose
    dx = np.r_[moved[:3, 3] - T[:3, 3], pin.log3(moved[:3, :3] @ T[:3, :3].T)]
    expected = np.linalg.solve(stiff.matrix, W)
    assert np.abs(dx - expected).max() < 1e-4 * np.abs(expected).max()
    C = np.linalg.inv(stiff.matrix)
    assert stiff.translational == pytest.approx(1 / np.linalg.eigvalsh(C[:3, :3]).max())


def _mujoco_at_rest(hexa, q, wrench, timestep=2e-4):
    """MuJoCo at rest: the exported MJCF, each leg's prismatic joint held by a joint equality (the brake),
    the wrench applied to the platform at its origin, no gravity; returns (model, data)."""
    mujoco = pytest.importorskip("mujoco", reason="MuJoCo is a test dependency: pip install -e '.[test]'")
    lengths = q[hexa.closed_loop.prismatic_q]
    brakes = "".join(
        f'<joint name="brake{i}" joint1="{n}" polycoef="{float(lengths[i])!r} 0 0 0 0" solref="{2 * timestep} 1"/>'
        for i, n in enumerate(hexa.prismatic_names)
    )
    m = mujoco.MjModel.from_xml_string(geometry_to_mjcf(hexa.geometry).replace("</equality>", brakes + "</equality>"))
    m.opt.gravity[:] = 0.0
    m.opt.timestep = timestep
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    m.eq_solref[:6] = (2 * timestep, 1.0)  # stiffer closures than the file's: smaller deflection under load
    d = mujoco.MjData(m)
    d.qpos[:] = mujoco_qpos(hexa.closed_loop, q, m)
    b = m.body("platform").id
    mujoco.mj_forward(m, d)
    for step in range(100_000):
        d.qfrc_applied[:] = 0.0
        mujoco.mj_applyFT(m, d, wrench[:3], wrench[3:], d.xpos[b].copy(), b, d.qfrc_applied)
        mujoco.mj_step(m, d)
        if step > 100 and step % 100 == 0 and np.abs(d.qvel).max() < 1e-10:
            break
    else:
        raise AssertionError("MuJoCo did not come to rest")
    mujoco.mj_forward(m, d)
    return m, d


@pytest.mark.parametrize("name", ["reference", "intersecting", "spherical", "3-6"])
@pytest.mark.parametrize(
    "where", [((0.01, -0.02, 0.015), (0.1, -0.05, 0.2)), ((-0.03, 0.02, -0.03), (-0.2, 0.25, -0.3))]
)
def test_mujoco_constraint_forces_at_rest(name, where):
    """The brake equalities' forces are the axial leg forces; each closure's force on the platform is the
    leg's force and moment (a small wrench: MuJoCo's soft closures deflect in proportion to the load)."""
    mujoco = pytest.importorskip("mujoco", reason="MuJoCo is a test dependency: pip install -e '.[test]'")

    hexa = hexapod(name)
    T = _pose(hexa, *where)
    sol = hexa.inverse(T)
    W = WRENCH * 1e-3
    ours = loads_at(hexa, sol.q, W, frame="base")
    m, d = _mujoco_at_rest(hexa, sol.q, W)
    n = d.nefc
    eq = d.efc_type[:n] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    ids, force = d.efc_id[:n], d.efc_force[:n]
    tension = -np.array([force[eq & (ids == 6 + i)][0] for i in range(6)])  # the brake pushes: tau = -t
    scale = ours.largest_axial_force
    assert np.abs(tension - ours.axial_force).max() < MUJOCO_TOL * scale
    J = d.efc_J[: n * m.nv].reshape(n, m.nv)
    a = m.joint("platform_joint").dofadr[0]
    R = d.xmat[m.body("platform").id].reshape(3, 3)
    platform_c, _ = joint_centres(hexa, sol.q)
    o = T[:3, 3]
    cardan = np.empty((6, 3))
    for k in range(6):
        rows = eq & (ids == k)
        g = J[rows][:, a : a + 6].T @ force[rows]  # free joint: world force, torque in the body frame
        f, moment_o = g[:3], R @ g[3:]
        assert np.abs(f - ours.leg_force[k]).max() < MUJOCO_TOL * scale
        cardan[k] = moment_o - np.cross(platform_c[k] - o, f)
    largest = np.abs(ours.platform_moment).max()
    if largest > 1e-6 * scale:
        assert np.abs(cardan - ours.platform_moment).max() < MUJOCO_MOMENT_TOL * largest
    else:
        assert np.abs(cardan).max() < MUJOCO_TOL * scale


def test_statics_cli_margin_and_bad_input(tmp_path, capsys):
    g = hm.get_preset("reference")
    from dataclasses import replace

    from hexapod_model.description.geometry_toml import save_geometry

    path = save_geometry(replace(g, brake_capacity=100.0), tmp_path / "fixture.toml")
    assert hm.load_geometry(path).brake_capacity == 100.0
    assert (
        main(["statics", str(path), "--wrench", "0", "0", "-500", "0", "20", "0", "--json", str(tmp_path / "s.json")])
        == 0
    )
    out = capsys.readouterr().out
    assert "brake capacity 100 N: load margin" in out and "a brake SLIPS" in out
    import json

    report = json.loads((tmp_path / "s.json").read_text())
    assert report["margin_N"] == pytest.approx(100.0 - report["largest_axial_force_N"])
    assert report["margin_N"] < 0
    assert main(["statics", "reference", "--wrench", "0", "0", "inf", "0", "0", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "wrench" in err[0]
    assert main(["statics", "reference", "--wrench", "0", "0", "1", "0", "0", "0", "--brake-capacity", "-3"]) == 2
    assert "--brake-capacity" in capsys.readouterr().err


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_joint_centres_at_home_are_the_geometry_anchors(name):
    hexa = hexapod(name)
    g = hexa.geometry
    platform_c, base_c = joint_centres(hexa, hexa.q_home)
    np.testing.assert_allclose(base_c, g.base_points(), atol=1e-12)
    np.testing.assert_allclose(platform_c, g.platform_points() + g.home_translation, atol=1e-12)


def test_urdf_and_mjcf_files_give_the_geometry_loads(tmp_path):
    """Without a geometry (URDF, MJCF) the loads come from the model alone: the same numbers."""
    hexa = hexapod("reference")
    T = _pose(hexa)
    ours = leg_forces(hexa, T, WRENCH)
    (tmp_path / "r.urdf").write_text(hm.geometry_to_urdf(hexa.geometry))
    (tmp_path / "r.xml").write_text(geometry_to_mjcf(hexa.geometry))
    for path in ("r.urdf", "r.xml"):
        other = hm.Hexapod.load(str(tmp_path / path), compiled=False)
        assert other.geometry is None
        theirs = leg_forces(other, T, WRENCH)
        for field in ("axial_force", "leg_force", "platform_moment", "base_moment"):
            np.testing.assert_allclose(
                getattr(theirs, field), getattr(ours, field), atol=1e-9 * ours.largest_axial_force
            )


def test_singular_pose_is_refused_not_answered(capsys):
    """The spherical preset is singular at 90 deg yaw: no finite leg forces hold every wrench there."""
    from hexapod_model.exceptions import SingularityError

    hexa = hexapod("spherical")
    T = hexa.home_pose.copy()
    T[:3, :3] = rpy_to_matrix(0.0, 0.0, np.radians(90.0))
    with pytest.raises(SingularityError, match="condition number"):
        leg_forces(hexa, T, WRENCH)
    z = hexa.home_pose[2, 3]
    assert (
        main(["statics", "spherical", "--pose", "0", "0", str(z), "0", "0", "90", "--wrench", *"0 0 -1 0 0 0".split()])
        == 1
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "singular" in err[0]
