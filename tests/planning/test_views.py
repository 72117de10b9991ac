"""The plan's views: the snapshot's key frames (HTML), the figure, and the benchmark script."""

from __future__ import annotations

import subprocess
import sys

import pytest

from hexapod_model.cli.main import main
from hexapod_model.planning.writers import read_plan

from .test_plan import ROOT, planned  # noqa: F401  (the module's plan)


def test_snapshot_writes_the_key_frames(planned, tmp_path):  # noqa: F811
    pytest.importorskip("meshcat", reason="meshcat is not installed: pip install 'hexapod_model[view]'")
    from hexapod_model.viz.plan_scene import key_frames

    tmp, _, _ = planned
    plan = read_plan(tmp / "plan.json")
    assert main(["snapshot", "--plan", str(tmp / "plan.json"), "-o", str(tmp_path / "key.html")]) == 0
    frames = key_frames(plan)
    assert len(frames) == 2 + 2 * len(plan.order)
    written = sorted(p.name for p in tmp_path.glob("key_*.html"))
    assert written == sorted(f"key_{n:02d}_{label}.html" for n, (_, label) in enumerate(frames))
    assert all((tmp_path / name).stat().st_size > 10_000 for name in written)  # the meshes are in the file


def test_the_figure_has_the_joints_and_the_legs(planned, tmp_path):  # noqa: F811
    pytest.importorskip("matplotlib", reason="matplotlib is not installed: pip install 'hexapod_model[plots]'")
    from hexapod_model.plots.changeover_plan import plan_figure, plot_plan

    tmp, _, _ = planned
    plan = read_plan(tmp / "plan.json")
    fig = plan_figure(plan)
    q_axes, _, leg_axes = fig.axes[:3]
    assert len(q_axes.lines) == 6 and len(leg_axes.lines) == 6 * len(plan.order)
    assert plot_plan(plan, tmp_path / "plan.png").stat().st_size > 0


@pytest.mark.slow
def test_the_benchmark_runs():
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "changeover_plan.py"), "--repeat", "1"],
        capture_output=True, text=True, timeout=600, check=True,
    )  # fmt: skip
    assert "planning CPU" in out.stdout
