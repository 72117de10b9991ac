"""The changeover through the real process: `hexapod serve` of docs/examples/fixture.toml with --simulate sim.toml.

With a token file: a target for ``right`` at its simulated hold pose is in tolerance within 10 s,
one 2 mm away reports ~2 mm and per-leg changes equal to the inverse kinematics' differences
(1 um), the target survives a restart, writes without the token are 401; the same through
``hexapod fixture target | recipe | locate``.
"""

from __future__ import annotations

import json
import signal
import socket
import time
import urllib.error
import urllib.request

import numpy as np
import pytest

from hexapod_model.cli.main import main
from hexapod_model.lie import xyz_rpy_to_pose as placement

from ..conftest import hexapod
from ..service.helpers import record_pose
from .test_service_cli import ROOT, Served

TOKEN = "example-token-0123456789abcdef"
HOLD = {"x": 0.01, "y": -0.02, "z": 0.41, "roll": 5.0, "pitch": -3.0, "yaw": 10.0}
TOL = {"translation_mm": 0.1, "rotation_deg": 0.05}


def example(tmp_path):
    """docs/examples/fixture.toml and sim.toml in ``tmp_path``, on a free port, with a token file."""
    text = (ROOT / "docs/examples/fixture.toml").read_text()
    assert "port = 8765\n" in text
    text = text.replace("port = 8765\n", 'port = 0\ntoken_file = "fixture.token"\n')
    (tmp_path / "fixture.toml").write_text(text)
    (tmp_path / "sim.toml").write_text((ROOT / "docs/examples/sim.toml").read_text())
    token = tmp_path / "fixture.token"
    token.write_text(TOKEN + "\n")
    token.chmod(0o600)
    return tmp_path / "fixture.toml", tmp_path / "sim.toml"


def call(port, method, path, body=None, token=TOKEN):
    headers = {"Content-Type": "application/json", "X-Operator": "anna"}
    if token:
        headers["Authorization"] = f"Bearer {token}"
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(f"http://127.0.0.1:{port}{path}", data=data, method=method, headers=headers)
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, json.load(r)
    except urllib.error.HTTPError as e:
        return e.code, json.load(e)


def poll(port, fixture, check, seconds):
    end = time.monotonic() + seconds
    while True:
        g = call(port, "GET", f"/fixtures/{fixture}/guidance")[1]
        if check(g) or time.monotonic() > end:
            return g
        time.sleep(0.1)


@pytest.mark.slow
def test_done_when_from_the_example_served_by_its_cli(tmp_path, capsys):
    cfg, sim = example(tmp_path)
    hexa = hexapod("reference")
    served = Served(str(cfg), "--simulate", str(sim))
    try:
        port = served.wait_port()
        assert call(port, "PUT", "/fixtures/right/target", {"pose": HOLD, "tolerance": TOL}, token=None)[0] == 401
        assert call(port, "PUT", "/recipes/r", {"targets": {}}, token=None)[0] == 401
        t0 = time.monotonic()
        code, body = call(port, "PUT", "/fixtures/right/target", {"pose": HOLD, "tolerance": TOL})
        assert code == 200, body
        g = poll(port, "right", lambda g: g["in_tolerance"], 10.0)
        assert g["in_tolerance"] and time.monotonic() - t0 < 10.0
        away = {**HOLD, "x": HOLD["x"] + 0.002}
        code, body = call(port, "PUT", "/fixtures/right/target", {"pose": away, "tolerance": TOL})
        kept = body["target"]
        g = poll(port, "right", lambda g: g["target"]["id"] == kept["id"] and g["status"] == "ok", 10.0)
        assert g["deviation"]["translation_mm"] == pytest.approx(2.0, abs=0.1)
        expected = (hexa.inverse(placement([*away.values()][:3] + [*away.values()][3:])).lengths) * 1e3
        expected -= hexa.inverse(record_pose(g)).lengths * 1e3
        assert np.abs(np.array([leg["change_mm"] for leg in g["legs"]]) - expected).max() < 1e-3  # 1 um
        # the command line: the guidance printed, a recipe stored and activated (left follows it)
        url = ["--url", f"http://127.0.0.1:{port}"]
        assert main(["fixture", "target", str(cfg), "right", *url]) == 0
        out = capsys.readouterr().out
        assert "deviation 2.0" in out or "deviation 1.9" in out
        assert "in tolerance: no" in out and out.count(" mm\n") >= 6
        recipe = tmp_path / "bracket.toml"
        recipe.write_text(
            "[targets.left]\npose = { x = 0.0, y = 0.003, z = 0.405, roll = 1.0, pitch = 0.0, yaw = -2.0 }\n"
            "tolerance = { translation_mm = 0.1, rotation_deg = 0.05 }\n"
        )
        assert main(["fixture", "recipe", str(cfg), "bracket", "--set", str(recipe), "--activate", *url]) == 0
        assert "recipe bracket active" in capsys.readouterr().out
        g = poll(port, "left", lambda g: g["in_tolerance"] and g["stored"], 20.0)
        assert g["in_tolerance"] and g["target"]["recipe"] == "bracket", (g["status"], g["flags"], g["state"])
        assert main(["fixture", "history", str(cfg), "--fixture", "left"]) == 0  # the lock names what it met
        rows = capsys.readouterr().out.splitlines()
        assert rows[0].endswith(",target_id,recipe") and rows[-1].endswith(f",{g['target']['id']},bracket")
    finally:
        assert served.finish(signal.SIGINT) == 0, "".join(served.err)
    served = Served(str(cfg), "--simulate", str(sim))  # the target survives a restart
    try:
        port = served.wait_port()
        again = call(port, "GET", "/fixtures/right/target")[1]["target"]
        assert again["id"] == kept["id"] and again["set_by"] == kept["set_by"]
        assert again["pose"] == pytest.approx(kept["pose"], abs=1e-12)
        assert main(["fixture", "target", str(cfg), "right", "--clear", "--url", f"http://127.0.0.1:{port}"]) == 0
        assert "target cleared" in capsys.readouterr().out
        code, body = call(port, "PUT", "/fixtures/left/target", {"pose": HOLD, "tolerance": TOL, "by": "bo"})
        assert code == 200 and body["target"]["set_by"].startswith("bo (")
    finally:
        served.finish(signal.SIGKILL)  # and a kill -9 right after the answer
    served = Served(str(cfg), "--simulate", str(sim))
    try:
        port = served.wait_port()
        assert call(port, "GET", "/fixtures/right/target")[1]["target"] is None
        assert call(port, "GET", "/fixtures/left/target")[1]["target"]["id"] == body["target"]["id"]
    finally:
        assert served.finish(signal.SIGINT) == 0, "".join(served.err)


def test_fixture_locate_prints_base_in_robot_and_residuals(tmp_path, capsys):
    T = placement([0.85, -0.3, 0.02, 0.0, 0.0, 90.0])
    base = np.array([[0.2, 0.0, 0.0], [-0.1, 0.17, 0.0], [-0.1, -0.17, 0.0]])
    robot = base @ T[:3, :3].T + T[:3, 3]
    rows = ["base_x,base_y,base_z,robot_x,robot_y,robot_z"] + [
        ",".join(repr(float(v)) for v in [*a, *b]) for a, b in zip(base, robot)
    ]
    (tmp_path / "points.csv").write_text("\n".join(rows) + "\n")
    assert main(["fixture", "locate", str(tmp_path / "points.csv")]) == 0
    out = capsys.readouterr().out.splitlines()
    values = [float(v) for v in out[0].split("[")[1].split("]")[0].split(",")]
    assert np.allclose(values, [0.85, -0.3, 0.02, 0.0, 0.0, 90.0], atol=1e-6) and "RMS residual 0.000 mm" in out[-1]
    (tmp_path / "bad.csv").write_text("base_x,base_y\n1,2\n")
    assert main(["fixture", "locate", str(tmp_path / "bad.csv")]) == 2
    assert "missing column(s) base_z" in capsys.readouterr().err


def test_fixture_target_without_a_service_is_one_line(tmp_path, capsys):
    cfg, _ = example(tmp_path)
    text = cfg.read_text().replace("port = 0\n", "port = 9\n")  # nothing listens on the discard port
    cfg.write_text(text)
    assert main(["fixture", "target", str(cfg), "right"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is hexapod serve running?" in err


@pytest.mark.cell
def test_view_live_cell_places_the_ur10_by_the_served_pose_in_robot(tmp_path, capsys):
    from hexapod_model.viz.robot_cell import robot_base_pose, tool_changer_pose

    from .test_service_cli import HOLD_SIM, write_config, write_sim

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    cell = "[fixtures.cell]\nbase_in_robot = [0.8, 0.0, 0.0, 0.0, 0.0, 180.0]\n"
    cell += "coupling = [0.0, 0.0, 0.07, 180.0, 0.0, 0.0]\n"
    cfg = write_config(tmp_path, port=port, fixtures=[("left", "reference", [0x181 + k for k in range(6)], cell)])
    served = Served(str(cfg), "--simulate", str(write_sim(tmp_path, HOLD_SIM)))
    try:
        served.wait_port()
        served.wait_for(lambda: served.get("/fixtures/left/pose")["status"] == "ok")
        rec = served.get("/fixtures/left/pose")
        assert main(["view", str(cfg), "--live", "--cell", "--once"]) == 0
    finally:
        assert served.finish(signal.SIGINT) == 0, "".join(served.err)
    captured = capsys.readouterr()
    assert "showed 1 poses of left" in captured.err and "UR10 flange at pose_in_robot" in captured.err
    # the same cell as `hexapod view --cell`: the robot's base at (0.8, 0, 0) facing the hexapod
    expected = np.linalg.inv(robot_base_pose()) @ tool_changer_pose(record_pose(rec))
    assert np.allclose(record_pose(rec["pose_in_robot"]), expected, atol=1e-9)
    plain = write_config(tmp_path, port=port)
    assert main(["view", str(plain), "--live", "--cell", "--once"]) == 2
    assert "no [fixtures.cell]" in capsys.readouterr().err


def test_one_flag_names_the_operator_in_every_fixture_command(capsys):
    from hexapod_model.cli.main import build_parser

    parser = build_parser("fixture")
    for words in (["acknowledge", "left"], ["target", "left"], ["recipe"]):
        args = parser.parse_args(["fixture", words[0], "f.toml", *words[1:], "--by", "anna"])
        assert args.by == "anna", words
    old = parser.parse_args(["fixture", "target", "f.toml", "left", "--operator", "anna"])  # the earlier name
    assert old.by == "anna"
    for name in ("target", "recipe"):
        with pytest.raises(SystemExit):
            parser.parse_args(["fixture", name, "-h"])
        shown = capsys.readouterr().out
        assert "--by" in shown and "--operator" not in shown
