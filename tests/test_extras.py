"""The optional parts: a missing extra stops a command with one line naming its ``pip install``."""

from __future__ import annotations

import subprocess
import sys

import pytest

from hexapod_model.extras import EXTRAS, MODULES, MissingExtraError, require


def test_require_names_the_extra_to_install():
    with pytest.raises(MissingExtraError) as info:
        require("hexapod_model_no_such_module", "plots")
    message = str(info.value)
    assert "\n" not in message and message.endswith("pip install 'hexapod_model[plots]'")
    assert message.startswith("hexapod_model_no_such_module is not installed (the figures)")
    assert set(MODULES) == set(EXTRAS)


@pytest.mark.parametrize(
    "blocked, argv, extra",
    [
        ("meshcat", ["snapshot", "reference", "-o", "x.png"], "view"),
        ("can", ["serve", "fixture.toml"], "service"),
    ],
)
def test_a_command_without_its_extra_says_which_pip_install_brings_it(blocked, argv, extra, tmp_path):
    code = (
        f"import sys\nsys.modules[{blocked!r}] = None  # as if not installed\n"
        "from hexapod_model.cli.main import main\n"
        f"sys.exit(main({argv!r}))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert out.returncode == 2, out.stderr[-500:]
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].endswith(f"pip install 'hexapod_model[{extra}]'"), out.stderr[-500:]
    assert "Traceback" not in out.stderr


_HIDE_CELL = """
import importlib.metadata

_distribution = importlib.metadata.distribution


def distribution(name):
    if name.replace("_", "-") == "example-robot-data":
        raise importlib.metadata.PackageNotFoundError(name)
    return _distribution(name)


importlib.metadata.distribution = distribution
"""


def test_without_example_robot_data_the_cell_tests_skip_with_the_hint(tmp_path):
    """``pip install -e .`` without the cell extra: the tests that need the UR10 skip, naming the install."""
    import os
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    (tmp_path / "hide_cell.py").write_text(_HIDE_CELL)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(root), os.environ.get("PYTHONPATH", "")])}
    env.pop("PYTEST_ADDOPTS", None)  # a session of its own: not the outer run's options (its coverage floor)
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "hide_cell", "-p", "no:cacheprovider", "-rs",
         "tests/viz/test_view.py", "-k", "cell_ik or unreachable"],
        cwd=root, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert out.returncode == 0 and "2 skipped" in out.stdout, out.stdout[-2000:]
    assert "pip install -e '.[cell]'" in out.stdout
