"""The README's commands work as written (the set-up's main job, the CLI block, the Python block)."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np

import hexapod_model as hm

from .conftest import HAVE_CHROMIUM

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()


def code_blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README, re.S)


def test_main_job_of_the_setup_command(tmp_path):
    install = code_blocks("bash")[0].strip()
    job = install.split("&&")[1].strip()  # hexapod fk reference docs/examples/lengths.csv -o poses.csv
    args = shlex.split(job)
    assert args[0] == "hexapod"
    args = [str(ROOT / a) if a.startswith("docs/") else a for a in args]
    args[args.index("-o") + 1] = str(tmp_path / "poses.csv")
    out = subprocess.run([sys.executable, "-m", "hexapod_model", *args[1:]], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    rows = (tmp_path / "poses.csv").read_text().strip().splitlines()
    assert len(rows) == 9 and all(r.split(",")[10] == "ok" for r in rows[1:])


def test_python_block_runs(monkeypatch):
    monkeypatch.chdir(ROOT)
    block = code_blocks("python")[0]
    env = {"next_lengths": np.array([0.011, 0.0, -0.019, 0.001, 0.015, 0.0])}
    exec(compile(block, "README", "exec"), env)
    assert env["sol"].converged and np.allclose(env["back"].lengths, env["next_lengths"], atol=1e-9)
    hybrid = code_blocks("python")[1]
    exec(compile(hybrid, "README", "exec"), env)
    assert env["sol"].converged


def test_cli_block_commands_run(tmp_path, monkeypatch):
    from hexapod_model.cli.main import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "lengths.csv").write_text((ROOT / "docs/examples/lengths.csv").read_text())
    (tmp_path / "my_hexapod.toml").write_text(
        'name = "mine"\njoint_type = "spherical"\nhome_height = 0.4\n'
        + "".join(
            f"[[legs]]\nbase_anchor = {list(leg.base_anchor)}\nplatform_anchor = {list(leg.platform_anchor)}\n"
            f"stroke = [-0.1, 0.1]\n"
            for leg in hm.get_preset("spherical").legs
        )
    )
    block = next(b for b in code_blocks("text") if b.startswith("hexapod urdf"))
    for line in block.strip().splitlines():
        cmd = shlex.split(line.split("#")[0])
        if cmd[1] == "bench":
            continue  # the same benchmark runs in tests/cli/test_cli.py
        assert main(cmd[1:]) == 0, line
    assert (tmp_path / "lengths.csv").exists() and (tmp_path / "mine.urdf").exists()


def test_study_and_evaluation_commands_run(tmp_path, monkeypatch):
    """Every other `hexapod ...` line of the README runs, with smaller sizes where it is slow."""
    from hexapod_model.cli.main import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "docs").symlink_to(ROOT / "docs")
    assert main(["fk", "reference", str(ROOT / "docs/examples/lengths.csv"), "-o", "poses.csv"]) == 0
    lines = [ln for b in code_blocks("text") if not b.startswith("hexapod urdf") for ln in b.strip().splitlines()]
    assert any("reproduce" in ln for ln in lines) and any("evaluate" in ln for ln in lines)
    shrink = {"--poses": ["--poses", "40"]}
    for line in lines:
        cmd = shlex.split(line.split("#")[0])
        if "--table" in cmd:
            continue  # 32 tracking runs: covered by tests/analysis/test_tracking.py
        args = []
        skip = False
        for a in cmd[1:]:
            if skip:
                skip = False
                continue
            if a in shrink:
                args += shrink[a]
                skip = True
            else:
                args.append(a)
        if args[0] == "evaluate":
            args += ["--grid", "6", "--workers", "1"]
        if "--png" in args and not HAVE_CHROMIUM:  # the HTML part still runs
            k = args.index("--png")
            del args[k : k + 2]
        if args[0] == "view":
            args += ["--once", "--rate", "1000"]  # show, then exit instead of serving until Ctrl-C
        if args[0] == "calibrate":  # 2 folds, fixed axis directions: 54 unknowns, 3 fits of 20-40 poses
            args += ["--folds", "2", "--hold", "*_axis.*", "--candidates", "150"]
        if "--scenario" in args:
            args += ["--calibration-poses", "40"]
        if args[0] == "calibrate" and "examples/measured.csv" in line and "--force" not in args:
            # the bundled example is the nominal model plus noise: no better than nominal, not written
            assert main(args) == 1 and not Path(args[args.index("-o") + 1]).exists(), line
            continue
        assert main(args) == 0, line
