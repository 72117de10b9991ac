"""The CSV module: line rules, per-row errors, encodings, streams, pose columns and the writer."""

from __future__ import annotations

import io

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.io.tables import (
    LENGTH_COLUMNS,
    MAX_MAGNITUDE,
    QUATERNION_TOLERANCE,
    TableWriter,
    open_table,
    pose_input_columns,
    poses_from_table,
    read_table,
    write_table,
)
from hexapod_model.lie import rotation_angle, rpy_to_matrix

HEADER = "l1,l2,l3,l4,l5,l6\n"


def rows_of(tmp_path, text: str | bytes, columns=LENGTH_COLUMNS, **kw):
    path = tmp_path / "t.csv"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with open_table(path, **kw) as table:
        return table.read(columns)


def test_rows_with_more_or_fewer_cells_are_invalid_and_never_reflowed(tmp_path):
    text = HEADER + "0.01,0,-0.02,0,0.015,0,0.001\n" * 6 + "1,2,3,4,5,6\n" + "1,2,3\n" + "1,2,3,4,5,6,\n"
    rows = rows_of(tmp_path, text)
    assert len(rows) == 9  # one row per data line, whatever its cell count
    assert rows.errors[:6] == ["7 cells, the header has 6"] * 6
    assert rows.errors[6] == "" and rows.values[6].tolist() == [1, 2, 3, 4, 5, 6]
    assert rows.errors[7] == "3 cells, the header has 6" and rows.errors[8] == "7 cells, the header has 6"
    assert rows.lines.tolist() == list(range(2, 11))
    assert rows.malformed.tolist() == [True] * 6 + [False, True, True]
    assert np.isnan(rows.values[[0, 7, 8]]).all()


def test_line_numbers_are_the_files_own_lines(tmp_path):
    text = HEADER + "\n1,2,3,4,5,6\n   \n\r\n" + '1,2,3,4,5,"6"\n' + "1,2\n"
    rows = rows_of(tmp_path, text)
    assert rows.lines.tolist() == [3, 6, 7] and rows.errors == ["", "", "2 cells, the header has 6"]


def test_lines_ended_by_cr_alone_are_read_or_refused_in_one_line(tmp_path, capsys):
    """A CSV whose lines end in CR only gave a 20-line traceback (_csv.Error)."""
    from hexapod_model.cli.main import main

    rows = rows_of(tmp_path, "l1,l2,l3,l4,l5,l6\r0,0,0,0,0,0\r1,2,3,4,5,6\r")
    assert rows.values.tolist() == [[0] * 6, [1, 2, 3, 4, 5, 6]] and rows.lines.tolist() == [2, 3]
    mixed = tmp_path / "m.csv"  # CR alone inside a file of LF lines: refused, named
    mixed.write_bytes(b"l1,l2,l3,l4,l5,l6\r0,0,0,0,0,0\n0,0,0,0,0,0\n")
    with pytest.raises(hm.InputError, match="line 1: a line ends in CR .* save the file with LF or CRLF"):
        with open_table(mixed) as table:
            table.read(LENGTH_COLUMNS)
    assert main(["fk", "reference", str(mixed), "-o", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a line ends in CR" in err[0] and "Traceback" not in err[0]
    cr = tmp_path / "cr.csv"
    cr.write_bytes(b"l1,l2,l3,l4,l5,l6\r0,0,0,0,0,0\r")
    assert main(["fk", "reference", str(cr), "-o", str(tmp_path / "o.csv")]) == 0


def test_quoted_cell_over_two_lines_counts_from_its_first(tmp_path):
    text = 'a,l1\n"x\ny",1\n2\n'
    rows = rows_of(tmp_path, text, columns=["l1"])
    assert rows.lines.tolist() == [2, 4] and rows.values[0, 0] == 1 and rows.errors[1].startswith("1 cells")


def test_cells_must_be_finite_bounded_numbers(tmp_path):
    text = (
        "t,l1,note\n"
        "1e9,0.5,x\n"  # t is not one of the module's columns: no magnitude limit; 'note' is not read
        "0,,y\n"
        "0,abc,z\n"
        "0,nan,z\n"
        "0,1e400,z\n"  # overflows to inf
        "0,1e308,z\n"
        "0,1_5,z\n"
        f"0,{-MAX_MAGNITUDE},z\n"
    )
    rows = rows_of(tmp_path, text, columns=["t", "l1"])
    assert rows.values[0].tolist() == [1e9, 0.5] and rows.errors[0] == ""
    assert rows.errors[1:7] == [
        "l1 is empty",
        "l1 = 'abc' is not a number",
        "l1 = 'nan' is not a finite number",
        "l1 = '1e400' is not a finite number",
        "l1 = '1e308' exceeds 1e+06 in magnitude",
        "l1 = '1_5' is not a number",
    ]
    assert np.isnan(rows.values[1:7, 1]).all() and rows.errors[7] == ""


def test_utf8_bom_is_skipped_and_other_encodings_name_the_line(tmp_path):
    rows = rows_of(tmp_path, b"\xef\xbb\xbf" + HEADER.encode() + b"0,0,0,0,0,0\n")
    assert rows.errors == [""]
    with pytest.raises(hm.InputError) as exc:
        rows_of(tmp_path, HEADER.encode() + b"0,0,0,0,0,0\n\n\xe9,0,0,0,0,0\n")
    assert "line 4: not UTF-8 text (byte 0xe9 at column 1)" in str(exc.value)
    assert "\n" not in str(exc.value)


def test_header_rules(tmp_path):
    for text, words in (
        ("", "line 1: expected a header line"),
        ("\n1,2\n", "line 1: expected a header line"),
        ("l1,l2,l1\n", "column 'l1' appears twice"),
        ("l1,l2\n", "missing columns ['l3', 'l4', 'l5', 'l6']"),
    ):
        with pytest.raises(hm.InputError) as exc:
            rows_of(tmp_path, text, required=LENGTH_COLUMNS)
        assert words in str(exc.value)
    with pytest.raises(hm.InputError, match="No such file"):
        open_table(tmp_path / "missing.csv")


def test_text_and_binary_streams(tmp_path):
    text = "\ufeff" + HEADER + "1,2,3,4,5,6\n"
    for stream in (io.StringIO(text), io.BytesIO(text.encode())):
        with open_table(stream, LENGTH_COLUMNS, name="<stdin>") as table:
            assert table.header == LENGTH_COLUMNS and table.read(LENGTH_COLUMNS).values.tolist() == [[1, 2, 3, 4, 5, 6]]
        assert not stream.closed  # a stream belongs to the caller


def test_chunks_are_bounded(tmp_path):
    path = tmp_path / "big.csv"
    path.write_text(HEADER + "0,0,0,0,0,0\n" * 2500)
    with open_table(path) as table:
        sizes = [len(c) for c in table.chunks(LENGTH_COLUMNS, size=1000)]
    assert sizes == [1000, 1000, 500]


def test_overlong_line_is_refused(tmp_path):
    from hexapod_model.io.csv_rows import MAX_LINE_BYTES

    with pytest.raises(hm.InputError, match="line 2 is longer than"):
        rows_of(tmp_path, HEADER + "1" * (MAX_LINE_BYTES + 10) + "\n")


def test_read_table_refuses_malformed_rows_and_keeps_bad_cells_as_nan(tmp_path):
    (tmp_path / "a.csv").write_text(HEADER + "1,2,x,4,5,6\n\n1,2,3,4,5,6\n")
    header, data = read_table(tmp_path / "a.csv")
    assert header == LENGTH_COLUMNS and data.shape == (2, 6) and np.isnan(data[0, 2])
    (tmp_path / "b.csv").write_text(HEADER + "1,2,3,4,5,6\n1,2,3,4,5,6,7\n")
    with pytest.raises(hm.InputError, match="line 3: 7 cells, the header has 6"):
        read_table(tmp_path / "b.csv")


def test_pose_columns_and_quaternion_rule():
    assert pose_input_columns(["x", "y", "z", "roll", "pitch", "yaw", "status"]) == [
        "x",
        "y",
        "z",
        "roll",
        "pitch",
        "yaw",
    ]
    for header, words in (
        (["x", "y", "qx", "qy", "qz", "qw"], "need x,y,z"),
        (["x", "y", "z"], "qx,qy,qz,qw or roll,pitch,yaw"),
        (["x", "y", "z", "qx", "qy", "qz"], "not all of"),
    ):
        with pytest.raises(hm.InputError, match=words):
            pose_input_columns(header)
    cols = ["x", "y", "z", "qx", "qy", "qz", "qw"]
    s = np.sqrt(0.5)
    values = np.array(
        [
            [0, 0, 0.4, 0, 0, s, s],
            [0, 0, 0.4, 0, 0, 0, 2],  # norm 2: not a unit quaternion, never normalised and solved
            [0, 0, 0.4, 0, 0, 0, 1 + 0.9 * QUATERNION_TOLERANCE],  # rounding: accepted
            [0, 0, 0.4, 0, 0, 0, 1 + 2 * QUATERNION_TOLERANCE],
            [0, 0, 0.4, 0, 0, 0, 0],
        ]
    )
    poses, errors = poses_from_table(cols, values)
    assert errors[0] == "" and errors[2] == ""
    assert "not a unit quaternion: norm 2 differs from 1 by more than 1e-05" in errors[1]
    assert "not a unit quaternion" in errors[3] and "norm 0 " in errors[4]
    assert np.isnan(poses[[1, 3, 4]]).all()
    np.testing.assert_allclose(poses[0, :3, :3], rpy_to_matrix(0, 0, np.pi / 2), atol=1e-15)
    np.testing.assert_allclose(poses[2, :3, :3], np.eye(3), atol=1e-15)


def test_quaternion_and_angles_must_agree_when_both_are_given():
    cols = ["x", "y", "z", "qx", "qy", "qz", "qw", "roll", "pitch", "yaw"]
    s = np.sqrt(0.5)
    values = np.array([[0, 0, 0.4, 0, 0, s, s, 0, 0, 90.0], [0, 0, 0.4, 0, 0, s, s, 0, 0, 91.0]])
    poses, errors = poses_from_table(cols, values)
    assert errors[0] == "" and "differ by 1 deg" in errors[1]
    assert rotation_angle(poses[0, :3, :3], rpy_to_matrix(0, 0, np.pi / 2)) < 1e-12


def test_writer_and_atomic_write_table(tmp_path):
    buf = io.StringIO()
    w = TableWriter(buf, ["x", "status"])
    w.write([0.1 + 0.2, "ok"])
    w.write([float("nan"), "a, b"])
    assert buf.getvalue() == 'x,status\n0.3,ok\n,"a, b"\n'
    path = tmp_path / "out.csv"
    path.write_text("old\n")

    def rows():
        yield [1.0, "ok"]
        raise RuntimeError("solver crashed half-way")

    with pytest.raises(RuntimeError):
        write_table(path, ["x", "status"], rows())
    assert path.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["out.csv"]
    write_table(path, ["x", "status"], [[1.0, "ok"]])
    assert path.read_text() == "x,status\n1,ok\n"
