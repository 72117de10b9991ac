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
