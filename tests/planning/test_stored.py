"""`hexapod changeover plan` from the store: the stored lock poses and a stored recipe; `hexapod view --plan`."""

from __future__ import annotations

import tomllib

import numpy as np
import pinocchio as pin

from hexapod_model.cli import plan_view
from hexapod_model.cli.main import main
from hexapod_model.lie import matrix_to_quaternion, xyz_rpy_to_pose
from hexapod_model.planning.writers import read_plan
from hexapod_model.service.store import LockEvent, Store
from hexapod_model.service.targets import recipe_from_json

from ..conftest import hexapod
from .test_plan import CONFIG, RECIPE, planned  # noqa: F401  (the module's plan)

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
