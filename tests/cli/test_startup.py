"""What a ``hexapod`` process loads: only the sub-command's module, nothing heavy for fk/ik."""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
from pathlib import Path

from hexapod_model.cli.main import MODULES, OWNER, build_parser

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("scipy.spatial", "scipy.optimize", "scipy.stats", "matplotlib", "meshcat", "yourdfpy", "trimesh", "mujoco")


def test_owner_table_names_every_command_of_every_module():
    owners = {}
    for name in MODULES:
        sub = argparse.ArgumentParser().add_subparsers()
        importlib.import_module(f"hexapod_model.cli.{name}").register(sub)
        owners |= {command: name for command in sub.choices}
    assert owners == OWNER
    assert set(build_parser().parse_args(["fk", "reference", "x.csv"]).__dict__) >= {"hexapod", "input"}


def test_fk_and_ik_import_nothing_heavy(tmp_path):
    poses = tmp_path / "poses.csv"
    code = (
        "import sys\nfrom hexapod_model.cli.main import main\n"
        f"assert main(['fk', 'reference', {str(ROOT / 'docs/examples/lengths.csv')!r}, '-o', {str(poses)!r}]) == 0\n"
        f"assert main(['ik', 'reference', {str(poses)!r}, '-o', {str(tmp_path / 'back.csv')!r}]) == 0\n"
        f"print(sorted(k for k in sys.modules if k.startswith({HEAVY!r})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    assert out.stdout.strip() == "[]", out.stdout[:500]
