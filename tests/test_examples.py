"""Every script in examples/ runs as a user would run it, and does what its docstring says."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import hexapod_model as hm

from .conftest import HAVE_CHROMIUM

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


def env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}


def run(script: str, *args: str, cwd: Path, timeout: float = 300, stderr: list[str] | None = None) -> str:
    """The script's stdout (its stderr appended to ``stderr`` when given); it must exit 0."""
    out = subprocess.run(
        [sys.executable, str(EXAMPLES / script), *args], cwd=cwd, env=env(), capture_output=True, text=True,
        timeout=timeout,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    if stderr is not None:
        stderr.append(out.stderr)
    return out.stdout


def test_every_example_is_tested_and_listed_in_the_readme():
    scripts = sorted(p.name for p in EXAMPLES.glob("*.py"))
    tested = set(re.findall(r'run\(\s*"(\w+\.py)"', Path(__file__).read_text()))
    readme = (ROOT / "README.md").read_text()
    assert 4 <= len(scripts) <= 6 and set(scripts) <= tested
    assert all(f"examples/{s}" in readme for s in scripts)


def test_pose_stream(tmp_path):
    text = (ROOT / "docs/examples/stream.csv").read_text().splitlines()
    text.insert(3, "0.002,0.01,0.0,nan,0,0,0")  # a bad row keeps its place, named
    (tmp_path / "in.csv").write_text("\n".join(text) + "\n")
    out = run("pose_stream.py", "in.csv", "-o", "poses.csv", cwd=tmp_path)
    assert "250 of 251 samples solved" in out and "sample 3: invalid_input" in out
    rows = (tmp_path / "poses.csv").read_text().splitlines()
    assert rows[0].startswith("t,x,y,z,") and len(rows) == 252
    assert rows[3].endswith(",,,,,,,,,,invalid_input") and rows[4].endswith(",converged")
    # the poses are those of hexapod fk (the same readings through the CLI)
    hexa = hm.Hexapod.from_preset("reference", compiled=False)
    first = [float(v) for v in rows[1].split(",")[1:4]]
    readings = [float(v) for v in text[1].split(",")[1:]]
    np.testing.assert_allclose(first, hexa.forward(readings).pose[:3, 3], atol=1e-9)


def test_urdf_variant(tmp_path):
    out = run("urdf_variant.py", "--raise", "0.02", "--out", "v", cwd=tmp_path)
    assert "home height 0.420 m (was 0.400)" in out
    hexa = hm.Hexapod.from_urdf(tmp_path / "v" / "reference_raised.urdf", compiled=False)
    again = hm.Hexapod.load(str(tmp_path / "v" / "reference_raised.toml"), compiled=False)
    assert abs(hexa.home_pose[2, 3] - 0.42) < 1e-12 and abs(again.home_pose[2, 3] - 0.42) < 1e-12
    assert "meshcat" in (tmp_path / "v" / "reference_raised.html").read_text()[:200000].lower()
    assert (tmp_path / "v" / "reference_raised.png").exists() == HAVE_CHROMIUM


def test_calibrate_fixture(tmp_path):
    err: list[str] = []
    out = run("calibrate_fixture.py", "-o", "cal.toml", cwd=tmp_path, stderr=err)  # a simulated fixture, joint errors
    # it says what it does while it works: a line per stage, the validation's folds
    assert "identifying" in err[0] and "5-fold validation" in err[0] and "5/5" in err[0], err[0]
    nominal, calibrated = map(float, re.search(r"nominal ([\d.]+) mm, calibrated ([\d.]+) mm", out).groups())
    assert calibrated < 0.6 * nominal and "wrote cal.toml" in out
    hexa = hm.Hexapod.load(str(tmp_path / "cal.toml"), compiled=False)
    assert hexa.geometry is not None and hexa.geometry.name == "reference_calibrated"
    # the bundled measurements are the nominal model plus noise: nothing to gain, nothing written
    out = run("calibrate_fixture.py", str(ROOT / "docs/examples/measured.csv"), "-o", "nominal.toml", cwd=tmp_path)
    assert "nominal.toml not written" in out and not (tmp_path / "nominal.toml").exists()


def test_mujoco_mjcf(tmp_path):
    out = run("mujoco_mjcf.py", "-o", "h.xml", cwd=tmp_path)
    gap_mm = float(re.search(r"mm from the target, ([\de.+-]+) mm from forward", out).group(1))
    violation = float(re.search(r"closure violation at rest: ([\de.+-]+)", out).group(1))
    assert gap_mm < 1e-6 and violation < 1e-9
    assert hm.Hexapod.from_mjcf(tmp_path / "h.xml", compiled=False).nq == hm.Hexapod.from_preset("reference").nq


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_robot_cell_client(tmp_path):
    """With the token set-up of docs/changeover.md: a missing token is said at once, with the fix."""
    port = free_port()
    config = (ROOT / "docs/examples/fixture.toml").read_text()
    config = config.replace("port = 8765", f"port = {port}").replace('channel = "fixtures"', 'channel = "cell-test"')
    config = config.replace('# token_file = "fixture.token"', 'token_file = "fixture.token"')
    (tmp_path / "fixture.toml").write_text(config)
    (tmp_path / "fixture.token").write_text("robot-cell-client-token-0123456789\n")
    (tmp_path / "fixture.token").chmod(0o600)
    sim = str(ROOT / "docs/examples/sim.toml")
    log = (tmp_path / "serve.log").open("w")
    serve = subprocess.Popen(
        [sys.executable, "-m", "hexapod_model", "serve", "fixture.toml", "--simulate", sim],
        cwd=tmp_path, env=env(), stdout=subprocess.DEVNULL, stderr=log,
    )  # fmt: skip
    url = ["--url", f"http://127.0.0.1:{port}", "--timeout", "240"]
    try:
        t0 = time.monotonic()
        refused = subprocess.run(
            [sys.executable, str(EXAMPLES / "robot_cell_client.py"), *url], cwd=tmp_path, env=env(),
            capture_output=True, text=True, timeout=300,
        )  # fmt: skip
        said_in = time.monotonic() - t0
        out = run("robot_cell_client.py", *url, "--token-file", "fixture.token", cwd=tmp_path)
    finally:
        serve.send_signal(signal.SIGINT)
        try:
            serve.wait(timeout=60)
        except subprocess.TimeoutExpired:
            serve.kill()
            serve.wait()
        log.close()
    assert refused.returncode != 0 and "401" in refused.stderr and "--token-file" in refused.stderr, refused.stderr
    assert said_in < 120.0, said_in  # at the first answer (the service starts), not after --timeout
    assert "fixtures left, right" in out
    found = re.search(r"right: locked at x (\S+) y (\S+) z (\S+) m, roll (\S+) pitch (\S+) yaw (\S+) deg", out)
    sigma = re.search(r"1-sigma ([\d.]+) mm, ([\d.]+) deg", out)
    pose, (sigma_mm, sigma_deg) = np.array([float(v) for v in found.groups()]), map(float, sigma.groups())
    held = np.array([0.01, -0.02, 0.41, 5.0, -3.0, 10.0])  # the simulated fixture's pose (docs/examples/sim.toml)
    # within 5 sigma (sigma: the RMS length of the error), plus the printed digits
    assert np.linalg.norm(pose[:3] - held[:3]) < 5e-3 * sigma_mm + 1e-6
    assert np.abs(pose[3:] - held[3:]).max() < 5 * sigma_deg + 1e-4
