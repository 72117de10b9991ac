"""The README's commands work as written: the set-up's main job and every `hexapod ...` example.

Its Python blocks run in tests/test_docs.py.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

from .conftest import HAVE_CELL, HAVE_CHROMIUM

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
PYTHON_PAGE = (ROOT / "docs" / "python.md").read_text()  # the view and snapshot commands

#: the service's commands: they run until stopped, or read the store a running service wrote;
#: tests/cli/test_service_cli.py runs them in that order
SERVICE_COMMANDS = ("serve", "simulate-encoders", "fixture")


def code_blocks(lang: str, text: str = README) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, re.S)


def readme_commands() -> list[str]:
    """Every `hexapod ...` command of the README (table cells, code-block lines), then docs/python.md's."""
    found = re.findall(r"`(hexapod [^`]+)`", README)
    for block in code_blocks("text") + code_blocks("bash") + code_blocks("text", PYTHON_PAGE):
        found += [ln.split("#")[0].strip() for ln in block.splitlines() if ln.startswith("hexapod ")]
    return [c for c in found if len(shlex.split(c)) > 2 and shlex.split(c)[1] != "COMMAND"]  # not a bare name


def quick(args: list[str]) -> list[str] | None:
    """``args`` with smaller sizes where the command is slow; None for a command not run here."""
    if args[0] in SERVICE_COMMANDS:
        return None
    shrink = {"--poses": "40", "--samples": "20"}
    args = [shrink.get(args[k - 1], a) if k else a for k, a in enumerate(args)]
    if args[0] == "evaluate":
        args += ["--grid", "6", "--workers", "1"]
    if "--png" in args and not HAVE_CHROMIUM:  # the HTML part still runs
        k = args.index("--png")
        del args[k : k + 2]
    if "--cell" in args and not HAVE_CELL:  # the UR10's data (cell extra) absent: the hexapod alone
        args.remove("--cell")
    if args[0] == "view":
        args += ["--once", "--rate", "1000"]  # show, then exit instead of serving until Ctrl-C
    if args[0] == "calibrate":  # 2 folds, fixed axis directions: 54 unknowns, 3 fits of 20-40 poses
        args += ["--folds", "2", "--hold", "*_axis.*", "--candidates", "150"]
    if "--scenario" in args:
        args += ["--calibration-poses", "40"]
    return args


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


def test_every_readme_command_runs(tmp_path, monkeypatch):
    """Each `hexapod ...` of the README, in order, with smaller sizes where it is slow."""
    from hexapod_model.cli.main import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "docs").symlink_to(ROOT / "docs")
    commands = readme_commands()
    names = {shlex.split(c)[1] for c in commands}
    assert {"urdf", "fk", "ik", "mjcf", "reproduce", "calibrate", "evaluate", "track", "snapshot"} <= names
    for line in commands:
        args = quick(shlex.split(line)[1:])
        if args is not None:
            assert main(args) == 0, line
    assert (tmp_path / "poses.csv").exists() and (tmp_path / "calibration").is_dir()
