"""`hexapod changeover plan` from the store: the stored lock poses and a stored recipe; `hexapod view --plan`."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pinocchio as pin

import hexapod_model as hm
from hexapod_model.cli import plan_view
from hexapod_model.cli.main import main
from hexapod_model.lie import matrix_to_quaternion, xyz_rpy_to_pose
from hexapod_model.planning.writers import read_plan
from hexapod_model.service.store import LockEvent, Store
from hexapod_model.service.targets.target import recipe_from_json, target_from_json

from ..conftest import hexapod
from .test_plan import CONFIG, RECIPE, planned  # noqa: F401  (the module's plan)

ROOT = Path(__file__).resolve().parents[2]
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}
LOCKS = {"left": [0.004, -0.002, 0.401, 0.5, -0.3, 1.0], "right": [-0.003, 0.001, 0.399, -0.4, 0.2, -1.5]}


def test_the_plan_starts_at_the_stored_lock_poses_and_ends_at_a_stored_recipe(tmp_path):
    config = tmp_path / "fixture.toml"
    config.write_text(CONFIG.read_text())  # its store: fixture.sqlite next to it
    hexa = hexapod("reference")
    with Store(tmp_path / "fixture.sqlite") as store:
        for name, values in LOCKS.items():
            T = xyz_rpy_to_pose(values)
            sol = hexa.inverse(T)
            store.add_lock(
                LockEvent(name, 1.0, T[:3, 3], matrix_to_quaternion(T[:3, :3]), sol.lengths, "ok", "-", sol.q)
            )
        body = {"targets": tomllib.loads(RECIPE.read_text())["targets"]}
        store.targets.put_recipe(recipe_from_json(body, "bracket", {n: hexa for n in LOCKS}, "test", 1.0))
    out = tmp_path / "plan.json"
    assert main(["changeover", "plan", str(config), "--recipe", "bracket", "-o", str(out)]) == 0
    plan = read_plan(out)
    for name, values in LOCKS.items():
        first = next(k for k in range(len(plan.t)) if plan.phase[k] == "carry" and plan.fixture[k] == name)
        got = pin.XYZQUATToSE3(plan.platform_pose[first]).homogeneous
        np.testing.assert_allclose(got, xyz_rpy_to_pose(values), atol=1e-12)
    assert main(["changeover", "plan", str(config), "--recipe", "other", "-o", str(out)]) == 2


def test_view_plays_the_plan(planned, monkeypatch, capsys):  # noqa: F811
    tmp, plan, _ = planned
    shown = []
    monkeypatch.setattr(plan_view.time, "sleep", lambda s: None)
    real = plan_view.run_view_plan

    def spy(args):
        from hexapod_model.viz import plan_scene

        original = plan_scene.PlanScene.show
        monkeypatch.setattr(plan_scene.PlanScene, "show", lambda self, k: (shown.append(k), original(self, k)))
        return real(args)

    monkeypatch.setattr(plan_view, "run_view_plan", spy)
    assert main(["view", "--plan", str(tmp / "plan.json"), "--once", "--rate", "20"]) == 0
    assert shown[-1] == len(plan.t) - 1 and 20 < len(shown) < len(plan.t)
    assert "meshcat: http" in capsys.readouterr().out


def test_a_stored_target_in_collision_is_refused_before_planning(tmp_path, capsys):
    """A target stored for thin legs, planned with thick ones (the geometry changed): one line naming the pair."""
    thick = ROOT / "docs" / "geometries" / "thick_legs.toml"
    config = tmp_path / "fixture.toml"
    text = CONFIG.read_text()
    assert text.count('hexapod = "reference"') == 2
    config.write_text(text.replace('hexapod = "reference"', f'hexapod = "{thick}"'))
    twist = {"x": 0.0, "y": 0.0, "z": 0.4, "roll": 0.0, "pitch": 0.0, "yaw": 75.0}  # thick legs overlap
    target = target_from_json({"pose": twist, "tolerance": TOL}, "right", hexapod("reference"), "test", 1.0)
    with Store(tmp_path / "fixture.sqlite") as store:
        row = store.targets.add_target(target)
    truth = hm.Hexapod.load(thick).clearance(target.pose)
    assert truth.collision
    capsys.readouterr()
    out = tmp_path / "plan.json"
    assert main(["changeover", "plan", str(config), "--from-home", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"stored target {row} of right" in err and "in collision" in err
    assert f"{truth.pair[0]} - {truth.pair[1]} at {truth.distance * 1e3:.3f} mm" in err and not out.exists()
