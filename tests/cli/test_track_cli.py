"""``hexapod track --readings``: a recorded stream in, one row per sample out."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from hexapod_model.analysis.trajectories import trajectory_poses
from hexapod_model.cli.main import main
from hexapod_model.lie import quaternion_to_matrix
from hexapod_model.studies.track import TRACK_LOG_COLUMNS, true_readings

from ..conftest import hexapod


def write_stream(path, t, readings, header="t,l1,l2,l3,l4,l5,l6"):
    lines = [header] + [",".join([f"{ti:.6f}"] + [f"{v:.12g}" for v in row]) for ti, row in zip(t, readings)]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def stream():
    hexa = hexapod("reference")
    t, poses = trajectory_poses("A", hexa.home_pose, 0.005, 1000.0, 8.0)
    t, poses = t[:80], poses[:80]
    return t, poses, true_readings(hexa, poses)[0]


def test_track_readings_writes_one_row_per_sample(tmp_path, stream, capsys):
    t, poses, readings = stream
    readings = readings + np.random.default_rng(0).normal(0.0, 10e-6, readings.shape)
    readings[40, 3] += 5e-3  # one spike
    readings[60, :] = np.nan  # an unreadable row
    inp, out = tmp_path / "stream.csv", tmp_path / "poses.csv"
    write_stream(inp, t, readings)
    assert main(["track", "reference", "--readings", str(inp), "-o", str(out)]) == 1
    with open(out, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == TRACK_LOG_COLUMNS and len(rows) == len(t)
    assert [float(r["t"]) for r in rows] == pytest.approx(t)
    assert rows[40]["flags"] == "jump" and rows[40]["status"] == "ok"
    assert rows[60]["status"] == "invalid_input" and rows[60]["x"] == ""
    assert [r["flags"] for r in rows[:3]] == ["settling"] * 3
    clean = [k for k, r in enumerate(rows) if r["status"] == "ok" and not r["flags"]]
    assert len(clean) >= len(rows) - 8 and int(rows[10]["iterations"]) >= 1
    for k in clean:
        r = rows[k]
        R = quaternion_to_matrix(np.array([float(r[c]) for c in ("qx", "qy", "qz", "qw")]))
        assert np.linalg.norm([float(r[c]) for c in "xyz"] - poses[k][:3, 3]) < 1e-3
        assert np.abs(R - poses[k][:3, :3]).max() < 1e-2
    err = capsys.readouterr().err
    jumps = sum("jump" in r["flags"].split(";") for r in rows)  # the spike, and the rows its step check took
    assert 1 <= jumps <= 4 and all(r["flags"] == "jump" for r in rows[40 : 40 + jumps])
    assert "failed or flagged" in err and f"jump {jumps}" in err and "invalid_input 1" in err
    assert "discontinuity" not in err  # a spike is not a step


def test_track_readings_clean_stream_exits_0_to_stdout(tmp_path, stream, capsys):
    t, _, readings = stream
    inp = tmp_path / "s.csv"
    write_stream(inp, t, readings)
    assert main(["track", "reference", "--readings", str(inp), "--noise", "20e-6"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == ",".join(TRACK_LOG_COLUMNS) and len(lines) == len(t) + 1


def test_track_readings_bad_input_is_one_line(tmp_path, stream, capsys):
    t, _, readings = stream
    inp = tmp_path / "s.csv"
    write_stream(inp, t, readings, header="time,l1,l2,l3,l4,l5,l6")
    assert main(["track", "reference", "--readings", str(inp)]) == 2
    assert "missing columns ['t']" in capsys.readouterr().err
    write_stream(inp, t[::-1], readings)
    assert main(["track", "reference", "--readings", str(inp)]) == 2
    assert "increase strictly" in capsys.readouterr().err
    write_stream(inp, t, readings)
    assert main(["track", "reference", "--readings", str(inp), "-o", str(tmp_path / "nope" / "o.csv")]) == 2
    assert main(["track", "reference", "--readings", str(inp), "-o", str(inp)]) == 2
    assert main(["track", "reference", "--readings", str(inp), "--noise", "-1"]) == 2
    assert inp.read_text().startswith("t,l1")


@pytest.mark.parametrize("fault", ["swap", "step"])
def test_track_readings_flags_every_row_after_a_swap_or_a_step_like_the_service(tmp_path, fault):
    hexa = hexapod("reference")
    t, poses = trajectory_poses("A", hexa.home_pose, 0.005, 1000.0, 8.0)
    t, poses = t[:400], poses[:400]
    readings = true_readings(hexa, poses)[0] + np.random.default_rng(1).normal(0.0, 10e-6, (400, 6))
    if fault == "swap":
        readings[150:, [1, 2]] = readings[150:, [2, 1]]
    else:
        readings[150:, 2] += 3e-4
    inp, out = tmp_path / "stream.csv", tmp_path / "poses.csv"
    write_stream(inp, t, readings)
    assert main(["track", "reference", "--readings", str(inp), "-o", str(out)]) == 1
    with open(out, newline="") as fh:
        rows = list(csv.DictReader(fh))
    after = rows[150:]
    assert not any(r["status"] == "ok" and not r["flags"] for r in after), [
        k + 150 for k, r in enumerate(after) if r["status"] == "ok" and not r["flags"]
    ][:5]
    legs = {"swap": {"discontinuity:leg2", "discontinuity:leg3"}, "step": {"discontinuity:leg3"}}[fault]
    assert legs <= set(rows[-1]["flags"].split(";"))
