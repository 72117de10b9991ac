"""MuJoCo reads the exported MJCF as we do: closures, forward kinematics, and a simulation at rest."""

from __future__ import annotations

import functools
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.mjcf import EQUALITY_SOLIMP, EQUALITY_SOLREF, geometry_to_mjcf, urdf_to_mjcf
from hexapod_model.description.mjcf_loader import load_mjcf_text, mujoco_qpos, q_of_mujoco_qpos

from ..conftest import PRESET_NAMES, limits_only
from .test_mjcf import _rotated_home_urdf

mujoco = pytest.importorskip("mujoco", reason="MuJoCo is a test dependency: pip install -e '.[test]'")

ROOT = Path(__file__).resolve().parents[2]
CLOSED_TOL = 1e-10  # m and rad: equality violations of solved configurations
REST_TOL = 1e-9  # m and rad: platform pose at rest against forward kinematics


@functools.cache
def mj_model(name: str):
    """MuJoCo's model of preset ``name`` (not to be modified: shared by the tests)."""
    return mujoco.MjModel.from_xml_string(geometry_to_mjcf(hm.get_preset(name)))


def equality_violations(m, d) -> list[np.ndarray]:
    """``efc_pos`` rows of each equality constraint after ``mj_forward`` (position rows first)."""
    rows = d.efc_type[: d.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    ids, pos = d.efc_id[: d.nefc][rows], d.efc_pos[: d.nefc][rows]
    return [pos[ids == k] for k in range(m.neq)]


def violations_at(m, hexa: hm.Hexapod, q: np.ndarray) -> list[np.ndarray]:
    d = mujoco.MjData(m)
    d.qpos[:] = mujoco_qpos(hexa.closed_loop, q, m)
    mujoco.mj_forward(m, d)
    return equality_violations(m, d)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_mujoco_equalities_hold_on_solved_configurations(name):
    hexa, m = limits_only(name), mj_model(name)
    assert (
        m.neq == 6
        and list(m.eq_type)
        == [mujoco.mjtEq.mjEQ_WELD if hexa.closed_loop.kind == "6d" else mujoco.mjtEq.mjEQ_CONNECT] * 6
    )
    np.testing.assert_allclose(m.eq_solref, [EQUALITY_SOLREF] * 6)
    np.testing.assert_allclose(m.eq_solimp, [EQUALITY_SOLIMP] * 6)
    rows = 6 if hexa.closed_loop.kind == "6d" else 3
    solved, worst = 0, 0.0
    for T in box_poses(hexa.home_pose, 100, seed=21):
        sol = hexa.inverse(T, check=False)
        if not sol.converged:
            continue
        solved += 1
        v = violations_at(m, hexa, sol.q)
        assert [len(x) for x in v] == [rows] * 6
        worst = max(worst, max(float(np.abs(x).max()) for x in v))
        d = mujoco.MjData(m)  # and MuJoCo puts the platform where we do
        d.qpos[:] = mujoco_qpos(hexa.closed_loop, sol.q, m)
        mujoco.mj_kinematics(m, d)
        b = m.body("platform").id
        np.testing.assert_allclose(d.xpos[b], T[:3, 3], atol=1e-12)
        np.testing.assert_allclose(d.xmat[b].reshape(3, 3), T[:3, :3], atol=1e-12)
        np.testing.assert_allclose(q_of_mujoco_qpos(hexa.closed_loop, d.qpos, m), sol.q, atol=1e-14)
    assert solved >= 95 and worst < CLOSED_TOL, (solved, worst)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_mujoco_equalities_on_an_unclosed_configuration(name):
    """Every joint of leg 3 moved by 0.05: MuJoCo's violation of leg 3 is what Pinocchio's frames say.

    ``weld``: position of the tip minus the anchor (world frame, m), then the vector part of the
    quaternion of ``R_anchor^T R_tip`` (w >= 0); ``connect``: the position rows only.
    """
    hexa, m = limits_only(name), mj_model(name)
    q = hexa.q_home.copy()
    leg = hexa.closed_loop.legs[2]
    for j in leg.joints:
        q[hexa.model.joints[j].idx_q] += 0.05
    v = violations_at(m, hexa, q)
    c = hexa.constraint_models[2]
    data, cdata = hexa.model.createData(), c.createData()
    pin.computeJointJacobians(hexa.model, data, q)
    c.calc(hexa.model, data, cdata)
    expected = cdata.oMc1.translation - cdata.oMc2.translation
    if hexa.closed_loop.kind == "6d":
        quat = pin.Quaternion(cdata.c1Mc2.rotation.T)  # R_anchor^T R_tip
        expected = np.r_[expected, np.sign(quat.w) * quat.coeffs()[:3]]
        assert np.linalg.norm(expected[3:]) > 0.01  # the orientation is off too
    assert np.linalg.norm(expected[:3]) > 0.01
    np.testing.assert_allclose(v[2], expected, atol=1e-12)
    for k in (0, 1, 3, 4, 5):
        assert np.abs(v[k]).max() < CLOSED_TOL


def settle(m, d, max_time: float = 5.0) -> None:
    """Step until every joint velocity is below 1e-9 (checked every 100 steps) or ``max_time`` (s)."""
    while d.time < max_time:
        mujoco.mj_step(m, d, nstep=100)
        if np.abs(d.qvel).max() < 1e-9:
            return
    raise AssertionError(f"not at rest after {max_time} s: |qvel| = {np.abs(d.qvel).max():.2g}")


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_mujoco_simulation_settles_where_forward_says(name):
    """No gravity, the actuators at the readings of random poses: at rest, the platform is at ``forward``."""
    hexa = limits_only(name)
    m = mujoco.MjModel.from_xml_string(geometry_to_mjcf(hm.get_preset(name), actuated=True))
    m.opt.gravity[:] = 0.0
    poses = box_poses(hexa.home_pose, 3, seed=31, translation=0.03, angle_deg=15.0)
    for T in poses:
        lengths = hexa.inverse(T).lengths
        expected = hexa.forward(lengths).pose
        d = mujoco.MjData(m)  # at qpos0: home, loops closed
        d.ctrl[:] = lengths
        settle(m, d)
        pose = hexa.pose_of(q_of_mujoco_qpos(hexa.closed_loop, d.qpos, m))
        assert np.abs(pose[:3, 3] - expected[:3, 3]).max() < REST_TOL
        assert np.linalg.norm(pin.log3(pose[:3, :3].T @ expected[:3, :3])) < REST_TOL
        assert np.abs(d.qpos[[m.joint(n).qposadr[0] for n in hexa.prismatic_names]] - lengths).max() < REST_TOL


def test_rotated_home_pose_in_mujoco():
    """MuJoCo's qpos0 of a file whose platform is turned at home closes the loops; MuJoCo and we agree on q."""
    text = urdf_to_mjcf(_rotated_home_urdf(0.4))
    m = mujoco.MjModel.from_xml_string(text)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    assert max(np.abs(x).max() for x in equality_violations(m, d)) < CLOSED_TOL
    clm = load_mjcf_text(text)
    np.testing.assert_allclose(mujoco_qpos(clm, clm.q_home, m), m.qpos0, atol=1e-13)


def test_benchmark_script_reports_every_check(tmp_path):
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "mjcf_checks.py"), "3-6", "--poses", "5", "--rest", "1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert "solref (0.005, 1.0)" in out.stdout and "pin (5 poses)" in out.stdout and "rest (1 poses)" in out.stdout


def test_picture_script_renders_headless(tmp_path):
    png = tmp_path / "mjcf.png"
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "make_mjcf_image.py"), "--out", str(png)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    if out.returncode != 0 and re.search(r"EGL|OpenGL|gladLoadGL|MUJOCO_GL", out.stderr):
        pytest.skip(f"no headless OpenGL here (libegl1 or libosmesa6): {out.stderr.strip().splitlines()[-1]}")
    assert out.returncode == 0, out.stderr
    assert re.search(r"at rest after .* s of simulation: platform .* m from forward kinematics", out.stdout)
    from PIL import Image

    image = np.asarray(Image.open(png).convert("RGB"), dtype=float)
    assert image.shape == (720, 960, 3) and image.std() > 20  # a scene, not a blank frame


def test_docs_qpos_example_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "reference.xml").write_text(geometry_to_mjcf(hm.get_preset("reference")))
    block = re.search(r"```python\n(.*?)```", (ROOT / "docs" / "mjcf.md").read_text(), re.S).group(1)
    env: dict = {}
    exec(compile(block, "docs/mjcf.md", "exec"), env)
    rows = env["d"].efc_type[: env["d"].nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    assert rows.sum() == 36 and np.abs(env["d"].efc_pos[: env["d"].nefc][rows]).max() < CLOSED_TOL
    np.testing.assert_allclose(env["q"], env["sol"].q, atol=1e-14)
