"""`hexapod changeover plan` of docs/examples/fixture.toml and docs/examples/recipe.toml (both fixtures move).

The plan's final carried pose is each target (0.01 mm, 0.001 deg); the UR10's forward
kinematics of every ``q`` is its ``flange_in_robot`` (1e-6 m) and, while carrying,
``base_in_robot * platform_pose * coupling``; every carried pose solves within the stroke and
joint limits; ``qd`` stays within the URDF's velocity limits; the JSON and CSV hold the same
points; a target the arm cannot reach, or a carry through a too small singularity margin, is
refused in one line naming the fixture, exit 1.
"""

from __future__ import annotations

import csv
import importlib.metadata
import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

try:
    importlib.metadata.distribution("example-robot-data")
except importlib.metadata.PackageNotFoundError:
    pytest.skip("example-robot-data is not installed: pip install 'hexapod_model[plan]'", allow_module_level=True)
pytest.importorskip("coal", reason="coal is not installed: pip install 'hexapod_model[plan]'")
pytest.importorskip("coal", reason="coal is not installed: pip install 'hexapod_model[plan]'")

from hexapod_model.cli.main import main  # noqa: E402
from hexapod_model.lie import xyz_rpy_to_pose  # noqa: E402
from hexapod_model.planning import PHASES, Plan  # noqa: E402
from hexapod_model.planning.robot import Arm  # noqa: E402
from hexapod_model.planning.scurve import DEFAULT_CARRY_JERK  # noqa: E402
from hexapod_model.planning.visit import MAX_POINT_DT  # noqa: E402
from hexapod_model.planning.writers import csv_header, read_plan  # noqa: E402

from ..conftest import hexapod  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "docs/examples/fixture.toml"
RECIPE = ROOT / "docs/examples/recipe.toml"


def _plan(tmp: Path, *extra: str, config: Path = CONFIG) -> int:
    args = ["changeover", "plan", str(config), "--recipe-file", str(RECIPE), "--from-home"]
    return main([*args, "-o", str(tmp / "plan.json"), "--csv", str(tmp / "plan.csv"), *extra])


@pytest.fixture(scope="module")
def planned(tmp_path_factory) -> tuple[Path, Plan, dict]:
    tmp = tmp_path_factory.mktemp("plan")
    assert _plan(tmp) == 0
    doc = json.loads((tmp / "plan.json").read_text())
    return tmp, read_plan(tmp / "plan.json"), doc


def _T(row: np.ndarray) -> np.ndarray:
    return pin.XYZQUATToSE3(np.asarray(row, dtype=float)).homogeneous


def test_the_last_carried_pose_is_each_target(planned):
    _, plan, _ = planned
    recipe = {"left": [0.0, 0.003, 0.405, 1.0, 0.0, -2.0], "right": [0.01, -0.02, 0.412, 5.0, -3.0, 10.0]}
    assert set(plan.order) == {"left", "right"}
    for name, target in recipe.items():
        rows = [k for k in range(len(plan.t)) if plan.phase[k] == "carry" and plan.fixture[k] == name]
        last = _T(plan.platform_pose[rows[-1]])
        err = pin.log6(pin.SE3(np.linalg.inv(xyz_rpy_to_pose(target)) @ last)).vector
        assert np.linalg.norm(err[:3]) < 0.01e-3
        assert math.degrees(np.linalg.norm(err[3:])) < 0.001


def test_every_q_gives_its_flange_and_the_carried_plate(planned):
    _, plan, _ = planned
    flanges = Arm.load().fk_many(plan.q)
    cells = {f.name: f for f in plan.fixtures}
    for k, F in enumerate(flanges):
        want = _T(plan.flange_in_robot[k])
        assert np.abs(F[:3, 3] - want[:3, 3]).max() < 1e-6
        assert np.linalg.norm(pin.log3(F[:3, :3].T @ want[:3, :3])) < 1e-6
        if plan.phase[k] == "carry":
            c = cells[plan.fixture[k]]
            held = c.base_in_robot @ _T(plan.platform_pose[k]) @ c.coupling
            assert np.abs(held[:3, 3] - F[:3, 3]).max() < 1e-6
        else:
            assert np.isnan(plan.platform_pose[k]).all() and np.isnan(plan.readings[k]).all()


def test_every_carried_pose_is_within_the_hexapods_limits(planned):
    _, plan, _ = planned
    hexa = hexapod("reference")
    carried = [k for k in range(len(plan.t)) if plan.phase[k] == "carry"]
    assert len(carried) > 100
    for k in carried:
        sol = hexa.inverse(_T(plan.platform_pose[k]))  # raises outside the stroke or a joint limit
        np.testing.assert_allclose(sol.lengths, plan.readings[k], atol=1e-9)
    m = plan.margins
    assert m.stroke > 0 and m.joint > 0 and m.singularity >= 0.2 and m.clearance >= 0.02


def test_the_timing_keeps_the_velocity_limits_and_the_phases_in_order(planned):
    _, plan, _ = planned
    arm = Arm.load()
    assert np.all(np.abs(plan.qd) <= arm.velocity)
    assert np.all(np.abs(plan.qdd) <= arm.acceleration * (1 + 1e-9))
    assert np.all(np.diff(plan.t) >= 0) and plan.total_time == pytest.approx(plan.t[-1])
    for name in plan.order:
        phases = [p for p, f in zip(plan.phase, plan.fixture) if f == name]
        seen = list(dict.fromkeys(phases))
        assert seen == list(PHASES)
    assert np.all(plan.qd[0] == 0) and np.all(plan.qd[-1] == 0)
    np.testing.assert_array_equal(plan.q[0], plan.q[-1])  # back at the arm's start


def _second_differences(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``2 x[t_k, t_k+1, t_k+2]``: each is the second derivative somewhere in ``[t_k, t_k+2]``."""
    v = np.diff(x, axis=0) / np.diff(t)[:, None]
    return 2.0 * np.diff(v, axis=0) / (t[2:] - t[:-2])[:, None]


def test_the_carried_plate_accelerates_within_its_jerk_limit(planned):
    _, plan, doc = planned
    jerks = doc["summary"]["settings"]["carry_jerk_m_s3"]
    assert jerks == {"left": DEFAULT_CARRY_JERK, "right": DEFAULT_CARRY_JERK}
    for name in plan.order:
        rows = [k for k in range(len(plan.t)) if plan.phase[k] == "carry" and plan.fixture[k] == name]
        t = plan.t[rows]
        watched = np.hstack([plan.platform_pose[rows][:, :3], plan.readings[rows]])  # origin (m), legs (m)
        acc = _second_differences(t, watched)
        # a jerk within J moves the second derivative by at most J * (t_k+3 - t_k) between two of them,
        # and from rest (zero acceleration at t_0) by at most J * (t_2 - t_0) for the first
        assert np.all(np.abs(np.diff(acc, axis=0)) <= jerks[name] * (t[3:] - t[:-3])[:, None] * (1 + 1e-6))
        assert np.all(np.abs(acc[0]) <= jerks[name] * (t[2] - t[0]) * (1 + 1e-6))
        assert np.all(np.abs(acc[-1]) <= jerks[name] * (t[-1] - t[-3]) * (1 + 1e-6))
        assert np.diff(t).max() <= MAX_POINT_DT * (1 + 1e-9)  # dense enough in time for a player to interpolate


def test_the_json_and_the_csv(planned):
    tmp, plan, doc = planned
    assert doc["joint_names"] == list(plan.joint_names) and len(doc["joint_names"]) == 6
    assert set(doc["summary"]) >= {"total_time", "order", "order_method", "margins", "settings"}
    assert set(doc["summary"]["margins"]) >= {"stroke_mm", "joint_deg", "singularity", "clearance_mm"}
    keys = {"t", "q", "qd", "qdd", "phase", "fixture", "flange_in_robot", "platform_pose", "readings"}
    for p in doc["points"]:
        assert set(p) == keys and p["phase"] in PHASES
        assert len(p["q"]) == len(p["qd"]) == len(p["qdd"]) == 6 and len(p["flange_in_robot"]) == 7
        assert (p["platform_pose"] is None) == (p["phase"] != "carry") == (p["readings"] is None)
    with (tmp / "plan.csv").open() as f:
        rows = list(csv.reader(f))
    assert rows[0] == csv_header(plan) and len(rows) == len(plan.t) + 1
    for k in (0, len(plan.t) // 2, len(plan.t) - 1):
        row = dict(zip(rows[0], rows[k + 1]))
        assert float(row["t"]) == plan.t[k] and row["phase"] == plan.phase[k]
        assert [float(row[f"q_{n}"]) for n in plan.joint_names] == list(plan.q[k])


def test_two_runs_give_the_same_plan(planned, tmp_path):
    _, _, doc = planned
    assert _plan(tmp_path) == 0
    assert json.loads((tmp_path / "plan.json").read_text()) == doc


def _moved(tmp_path: Path, old: str, new: str) -> Path:
    text = CONFIG.read_text()
    assert old in text
    p = tmp_path / "fixture.toml"
    p.write_text(text.replace(old, new))
    return p


def test_a_target_out_of_the_arms_reach_is_refused_in_one_line(tmp_path, capsys):
    config = _moved(tmp_path, "[0.75, -0.40, 0.0, 0.0, 0.0, 90.0]", "[1.60, -0.40, 0.0, 0.0, 0.0, 90.0]")
    assert _plan(tmp_path, config=config) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fixture 'right'" in err[0] and "cannot reach" in err[0]
    assert not (tmp_path / "plan.json").exists()


def test_a_singularity_margin_threshold_blocks_the_carry(tmp_path, capsys):
    assert _plan(tmp_path, "--min-singularity-margin", "0.999") == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "singularity margin" in err[0] and "of the way" in err[0]


def test_a_fixture_without_a_cell_is_refused(tmp_path, capsys):
    text = CONFIG.read_text()
    cut = text.index("[fixtures.cell]\nbase_in_robot = [0.75, -0.40")
    p = tmp_path / "fixture.toml"
    p.write_text(text[:cut])
    assert _plan(tmp_path, config=p) == 2
    assert "no [fixtures.cell]" in capsys.readouterr().err
