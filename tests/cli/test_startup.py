"""What a ``hexapod`` process loads: only the sub-command's module, nothing heavy for fk/ik."""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
from pathlib import Path

from hexapod_model.cli.main import MODULES, OWNER, build_parser

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("scipy", "numba", "llvmlite", "matplotlib", "meshcat", "yourdfpy", "trimesh", "mujoco")


def test_owner_table_names_every_command_of_every_module():
    owners = {}
    for name in MODULES:
        sub = argparse.ArgumentParser().add_subparsers()
        importlib.import_module(f"hexapod_model.cli.{name}").register(sub)
        owners |= {command: name for command in sub.choices}
    assert owners == OWNER
    assert set(build_parser().parse_args(["fk", "reference", "x.csv"]).__dict__) >= {"hexapod", "input"}


def test_fk_and_ik_import_nothing_heavy(tmp_path):
    """A short input (one chunk of rows) is solved with the NumPy kernels: no numba, no scipy."""
    poses = tmp_path / "poses.csv"
    code = (
        "import sys\nfrom hexapod_model.cli.main import main\n"
        f"assert main(['fk', 'reference', {str(ROOT / 'docs/examples/lengths.csv')!r}, '-o', {str(poses)!r}]) == 0\n"
        f"assert main(['ik', 'reference', {str(poses)!r}, '-o', {str(tmp_path / 'back.csv')!r}]) == 0\n"
        f"print(sorted(k for k in sys.modules if k.startswith({HEAVY!r})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    assert out.stdout.strip() == "[]", out.stdout[:500]


def test_urdf_imports_nothing_heavy(tmp_path):
    """Writing a URDF loads and assembles it in Pinocchio: no numba, no yourdfpy (trimesh, SciPy) unless asked."""
    code = (
        "import sys\nfrom hexapod_model.cli.main import main\n"
        f"assert main(['urdf', '-o', {str(tmp_path / 'my.urdf')!r}]) == 0\n"
        "assert main(['urdf', '--preset', '3-6']) == 0\n"
        f"print(sorted(k for k in sys.modules if k.startswith({HEAVY!r})), file=sys.stderr)\n"
        f"assert main(['urdf', '--yourdfpy', '-o', {str(tmp_path / 'checked.urdf')!r}]) == 0\n"
        "print('yourdfpy' in sys.modules, file=sys.stderr)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    lines = out.stderr.strip().splitlines()
    assert lines[-3] == "[]" and lines[-1] == "True", out.stderr[-500:]
    assert (tmp_path / "my.urdf").read_text() == (ROOT / "urdf" / "reference.urdf").read_text()
    assert (tmp_path / "checked.urdf").read_text() == (ROOT / "urdf" / "reference.urdf").read_text()


def test_a_long_input_is_solved_compiled(tmp_path):
    """More rows than one chunk: the compiled kernels (numba imported), the same answers as the NumPy ones."""
    import numpy as np

    from hexapod_model.io.csv_rows import CHUNK_ROWS

    rows = np.loadtxt(ROOT / "docs/examples/lengths.csv", delimiter=",", skiprows=1)
    long = tmp_path / "long.csv"
    reps = CHUNK_ROWS // len(rows) + 1
    long.write_text(
        "l1,l2,l3,l4,l5,l6\n" + "".join(",".join(f"{v:.9f}" for v in r) + "\n" for r in np.tile(rows, (reps, 1)))
    )
    short = ROOT / "docs/examples/lengths.csv"
    code = (
        "import sys\nfrom hexapod_model.cli.main import main\n"
        f"assert main(['fk', 'reference', {str(long)!r}, '-o', {str(tmp_path / 'a.csv')!r}]) == 0\n"
        f"assert main(['fk', 'reference', {str(short)!r}, '-o', {str(tmp_path / 'b.csv')!r}]) == 0\n"
        "print('numba' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    assert out.stdout.strip() == "True"
    a = np.genfromtxt(tmp_path / "a.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    b = np.genfromtxt(tmp_path / "b.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert len(a) == reps * len(rows)
    for name in ("x", "y", "z", "qx", "qy", "qz", "qw"):
        np.testing.assert_allclose(a[name][: len(b)], b[name], rtol=0, atol=1e-11)
    assert list(a["status"][: len(b)]) == list(b["status"]) and list(a["iterations"][: len(b)]) == list(b["iterations"])
