"""fk / ik / reproduce --data on malformed input files: each bad row named, nothing re-flowed or changed."""

from __future__ import annotations

import csv
import io
import sys

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.cli.main import main
from hexapod_model.io.tables import pose_columns

from ..conftest import hexapod

HEADER = "l1,l2,l3,l4,l5,l6"
DATA_HEADER = "l1,l2,l3,l4,l5,l6,x,y,z,qx,qy,qz,qw"
HOME_DATA_ROW = "0,0,0,0,0,0,0,0,0.4,0,0,0,1"


def read_rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("rows", [3, 6])
def test_fk_rows_with_an_extra_cell_are_invalid_not_reshaped(tmp_path, capsys, rows):
    (tmp_path / "l.csv").write_text(HEADER + "\n" + "0.01,0,-0.02,0,0.015,0,0.001\n" * rows)
    code, _, err = run(capsys, "fk", "reference", str(tmp_path / "l.csv"), "-o", str(tmp_path / "p.csv"))
    out = read_rows(tmp_path / "p.csv")
    assert code == 1 and len(out) == rows and {r["status"] for r in out} == {"invalid_input"}
    assert {r["x"] for r in out} == {""}  # no pose for a row that was not read as it was written
    assert f"{rows} of {rows} rows failed; first: row 1 (line 2): invalid_input: 7 cells, the header has 6" in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_fk_trailing_comma_gives_one_output_row_per_input_row(tmp_path, capsys):
    (tmp_path / "l.csv").write_text(HEADER + "\n" + "0.01,0,-0.02,0,0.015,0,\n" * 6)
    code, _, err = run(capsys, "fk", "reference", str(tmp_path / "l.csv"), "-o", str(tmp_path / "p.csv"))
    assert code == 1 and len(read_rows(tmp_path / "p.csv")) == 6


def test_fk_good_rows_between_bad_ones_and_blank_lines_keep_file_line_numbers(tmp_path, capsys):
    hexa = hexapod("reference")
    good = [hexa.inverse(T).lengths for T in box_poses(hexa.home_pose, 2, seed=4)]
    text = (
        "\n".join(
            [
                HEADER,
                ",".join(str(float(v)) for v in good[0]),
                "",
                "",
                "0.01,0,0",
                ",".join(str(float(v)) for v in good[1]),
            ]
        )
        + "\n"
    )
    (tmp_path / "l.csv").write_text(text)
    code, _, err = run(capsys, "fk", "reference", str(tmp_path / "l.csv"), "-o", str(tmp_path / "p.csv"))
    out = read_rows(tmp_path / "p.csv")
    assert code == 1 and [r["status"] for r in out] == ["ok", "invalid_input", "ok"]
    assert "1 of 3 rows failed; first: row 2 (line 5): invalid_input: 3 cells, the header has 6" in err
    assert abs(float(out[2]["z"]) - box_poses(hexa.home_pose, 2, seed=4)[1][2, 3]) < 1e-9
    assert [r["message"] for r in out] == ["", "3 cells, the header has 6", ""]  # each bad row says why


def test_every_failed_row_carries_its_reason_and_ik_reads_fk_output_back(tmp_path, capsys):
    (tmp_path / "l.csv").write_text(HEADER + "\n0,0,0,0,0,0\n0,0,nan,0,0,0\n5,0,0,0,0,0\n")
    code, _, _ = run(capsys, "fk", "reference", str(tmp_path / "l.csv"), "-o", str(tmp_path / "p.csv"))
    out = read_rows(tmp_path / "p.csv")
    assert code == 1 and [r["status"] for r in out] == ["ok", "invalid_input", "invalid_input"]
    assert out[0]["message"] == "" and out[1]["message"] == "l3 = 'nan' is not a finite number"
    assert "stroke limit" in out[2]["message"] and "leg1_prismatic" in out[2]["message"]
    code, _, _ = run(capsys, "ik", "reference", str(tmp_path / "p.csv"), "-o", str(tmp_path / "back.csv"))
    assert code == 1 and [r["status"] for r in read_rows(tmp_path / "back.csv")][0] == "ok"


def test_ik_and_reproduce_refuse_rows_with_the_wrong_cell_count(tmp_path, capsys):
    (tmp_path / "p.csv").write_text("x,y,z,roll,pitch,yaw\n0,0,0.4,0,0,0\n0,0,0.4,0,0,0,5\n0.01,0,0.41,5,0,0\n")
    code, _, err = run(capsys, "ik", "reference", str(tmp_path / "p.csv"), "-o", str(tmp_path / "l.csv"))
    assert code == 1 and [r["status"] for r in read_rows(tmp_path / "l.csv")] == ["ok", "invalid_input", "ok"]
    assert "line 3): invalid_input: 7 cells, the header has 6" in err
    (tmp_path / "d.csv").write_text("\n".join([DATA_HEADER, HOME_DATA_ROW, HOME_DATA_ROW + ",0", HOME_DATA_ROW]))
    code, _, err = run(capsys, "reproduce", "--data", str(tmp_path / "d.csv"), "--convergence-poses", "0")
    assert code == 2 and "line 3: 14 cells, the header has 13" in err and len(err.strip().splitlines()) == 1


def test_bom_is_accepted_and_a_non_utf8_file_is_one_line(tmp_path, capsys):
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + HEADER.encode() + b"\n0,0,0,0,0,0\n")
    code, out, _ = run(capsys, "fk", "reference", str(tmp_path / "bom.csv"))
    # the residual of the zero configuration, as solved (a one-row input: the NumPy kernels)
    home = hm.Hexapod.from_preset("reference", compiled=False).forward(np.zeros(6))
    assert code == 0 and out.splitlines()[1].endswith(f",ok,0,{home.residual:.12g},") and home.residual < 1e-12
    (tmp_path / "latin.csv").write_bytes(HEADER.encode() + b"\n0,0,0,0,0,0\n\n0,0,0,0,0,0 \xb5m\n")
    code, _, err = run(capsys, "fk", "reference", str(tmp_path / "latin.csv"), "-o", str(tmp_path / "p.csv"))
    assert code == 2 and err.strip() == (
        f"hexapod fk: error: invalid CSV file '{tmp_path / 'latin.csv'}': line 4: not UTF-8 text "
        "(byte 0xb5 at column 13); save the file as UTF-8"
    )
    assert not (tmp_path / "p.csv").exists()  # the rows solved before line 4 are not left half-written
    (tmp_path / "d.csv").write_bytes(DATA_HEADER.encode() + b"\n" + HOME_DATA_ROW.encode() + b"\n\xff\n")
    code, _, err = run(capsys, "reproduce", "--data", str(tmp_path / "d.csv"))
    assert code == 2 and "line 3: not UTF-8" in err and "Traceback" not in err


@pytest.mark.parametrize(
    "row, words",
    [
        ("0,0,0.4,0,0,0,2", "not a unit quaternion: norm 2 differs from 1 by more than 1e-05"),
        ("0,0,0.4,0,0,0,1.0005", "norm 1.0005"),  # reproduce --data accepted this (1e-3) and ik normalised it
        ("0,0,0.4,1e308,0,0,1e308", "qx = '1e308' exceeds 1e+06 in magnitude"),
        ("1e308,0,0.4,0,0,0,1", "x = '1e308' exceeds 1e+06 in magnitude"),
        ("1e999,0,0.4,0,0,0,1", "x = '1e999' is not a finite number"),
    ],
)
def test_ik_never_changes_a_pose_and_reproduce_follows_the_same_rule(tmp_path, capsys, row, words):
    (tmp_path / "p.csv").write_text("x,y,z,qx,qy,qz,qw\n0,0,0.4,0,0,0,1\n" + row + "\n")
    code, _, err = run(capsys, "ik", "reference", str(tmp_path / "p.csv"), "-o", str(tmp_path / "l.csv"))
    out = read_rows(tmp_path / "l.csv")
    assert code == 1 and [r["status"] for r in out] == ["ok", "invalid_input"] and out[1]["l1"] == ""
    assert words in err and len(err.strip().splitlines()) == 1
    data = "\n".join([DATA_HEADER, HOME_DATA_ROW, "0,0,0,0,0,0," + row, HOME_DATA_ROW]) + "\n"
    (tmp_path / "d.csv").write_text(data)
    code, out_text, err = run(capsys, "reproduce", "--data", str(tmp_path / "d.csv"), "--convergence-poses", "0")
    assert code == 2 and "line 3: " in err and words in err and "inf" not in out_text and "nan" not in out_text


def test_ik_failure_summary_is_one_line(tmp_path, capsys):
    (tmp_path / "p.csv").write_text("x,y,z,qx,qy,qz,qw\n0,0,0.4,,0,0,1\n")
    code, _, err = run(capsys, "ik", "reference", str(tmp_path / "p.csv"))
    assert code == 1 and len(err.strip().splitlines()) == 1 and "qx is empty" in err


def test_fk_streams_its_rows(monkeypatch, capsys):
    """Rows come out while the input is still being read: memory does not grow with the input.

    Two chunks are read before the first row is written (an input longer than one chunk is
    solved with the compiled kernels).
    """
    n = 6000

    class Stdin(io.BytesIO):
        lines_read = 0

        def readline(self, size=-1):
            Stdin.lines_read += 1
            return super().readline(size)

    class Stdout(io.StringIO):
        read_at_first_row = None

        def write(self, text):
            if Stdout.read_at_first_row is None and ",ok," in text:
                Stdout.read_at_first_row = Stdin.lines_read
            return super().write(text)

    readings = np.zeros((n, 6))
    readings[:, 0] = np.linspace(0.0, 0.02, n)
    monkeypatch.setattr(
        sys, "stdin", Stdin((HEADER + "\n" + "".join(f"{v},0,0,0,0,0\n" for v in readings[:, 0])).encode())
    )
    out = Stdout()
    monkeypatch.setattr(sys, "stdout", out)
    assert main(["fk", "reference", "-"]) == 0
    lines = out.getvalue().splitlines()
    assert len(lines) == n + 1 and all(line.count(",ok,") == 1 for line in lines[1:])
    assert Stdout.read_at_first_row is not None and Stdout.read_at_first_row < n / 2
    hexa = hexapod("reference")
    last = hexa.forward(readings[-1])
    np.testing.assert_allclose(
        [float(v) for v in lines[-1].split(",")[:10]], pose_columns(last.pose[None])[0], atol=1e-9
    )


def test_reproduce_data_with_a_huge_position_is_rejected_not_averaged(tmp_path, capsys):
    rows = [DATA_HEADER, HOME_DATA_ROW, "0,0,0,0,0,0,1e308,0,0.4,0,0,0,1", HOME_DATA_ROW]
    (tmp_path / "d.csv").write_text("\n".join(rows) + "\n")
    code = main(["reproduce", "--data", str(tmp_path / "d.csv"), "--json", str(tmp_path / "r.json")])
    assert code == 2 and not (tmp_path / "r.json").exists()
    assert "line 3: x = '1e308' exceeds 1e+06" in capsys.readouterr().err
