"""``hexapod fk`` / ``ik`` solve their rows through the batch API: the same file as row by row."""

from __future__ import annotations

import csv
import io

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.cli.main import main
from hexapod_model.io.tables import (
    LENGTH_COLUMNS,
    POSE_COLUMNS,
    SOLVER_COLUMNS,
    TableWriter,
    open_table,
    pose_columns,
    pose_input_columns,
    poses_from_table,
)
from hexapod_model.kinematics.body_check import BODY_STATUSES
from hexapod_model.studies.bench import trajectory_readings

from ..conftest import PATH_TOL, batch_rule_forward, hexapod

BAD_LINES = ("0.01,abc,0,0,0,0", "0.01,0,0", "", "nan,0,0,0,0,0", "1e7,0,0,0,0,0", "0.01,0,0,0,0,0.9")


def per_row(hexa: hm.Hexapod, path, kind: str, prove: bool = False) -> tuple[str, int, str]:
    """The output, failure count and first failure of the row-by-row loop the CLI ran before (``prove``: fk --prove)."""
    out = io.StringIO()
    with open_table(path, LENGTH_COLUMNS if kind == "fk" else ()) as table:
        columns = LENGTH_COLUMNS if kind == "fk" else pose_input_columns(table.header)
        header = (POSE_COLUMNS if kind == "fk" else LENGTH_COLUMNS) + SOLVER_COLUMNS
        writer, solve = TableWriter(out, header), batch_rule_forward(hexa, prove) if kind == "fk" else hexa.inverse
        total, failed, first, guess = 0, 0, "", None
        for rows in table.chunks(columns):
            inputs, errors = rows.values, list(rows.errors)
            if kind == "ik":
                inputs, pose_errors = poses_from_table(columns, rows.values)
                errors = [a or b for a, b in zip(errors, pose_errors)]
            for k in range(len(rows)):
                sol, why = None, errors[k]
                if not why:
                    try:
                        sol = solve(inputs[k], guess=guess, check=False)
                        why = sol.message
                    except hm.HexapodError as exc:
                        why = str(exc)
                status = "invalid_input" if sol is None else sol.status
                values = np.full(len(header) - 4, np.nan)
                tail = [status, 0, float("nan")] if sol is None else [status, sol.iterations, float(sol.residual)]
                if sol is not None and sol.status in BODY_STATUSES:
                    guess = sol  # the batch's warm start: a closed configuration within the limits
                if sol is not None and sol.converged:
                    guess = sol
                    values = pose_columns(sol.pose[None])[0] if kind == "fk" else sol.lengths
                    tail[0] = ";".join(sol.flags) or "ok"
                if tail[0] != "ok":
                    failed += 1
                    first = first or f"row {total + k + 1} (line {rows.lines[k]}): {tail[0]}: {why}"
                writer.write([*map(float, values), *tail, why if tail[0] != "ok" else ""])
            total += len(rows)
    return out.getvalue(), failed, first


def assert_same_table(got: str, expected: str) -> None:
    """Same header, rows and words (statuses, flags, empty cells); numbers to ``PATH_TOL`` (m, rad).

    The batch loop and the row-by-row solve are two compiled units: the same answer to rounding,
    written with 12 digits (a residual of 1e-14 shows its last bits). A ``max_iterations`` row's
    residual (a diverging Newton's last iterate) is not compared.
    """
    a, b = (list(csv.reader(io.StringIO(text))) for text in (got, expected))
    assert len(a) == len(b) and a[0] == b[0]
    status = a[0].index("status")
    for line, (x, y) in enumerate(zip(a[1:], b[1:]), start=2):
        assert len(x) == len(y) and x[status] == y[status], line
        for u, v in zip(x[: status + 2], y[: status + 2]):  # the values, the status, the iterations
            if u == v:
                continue
            assert abs(float(u) - float(v)) <= PATH_TOL, (line, u, v)
        if x[status] != "max_iterations":
            for u, v in zip(x[status + 2 :], y[status + 2 :]):
                assert u == v or abs(float(u) - float(v)) <= PATH_TOL, (line, u, v)


def fk_file(hexa: hm.Hexapod, path) -> None:
    """~3000 rows: a trajectory, its jumps back to the start, box and far poses, bad rows."""
    _, warm = trajectory_readings(hexa)
    box = hexa.inverse_batch(box_poses(hexa.home_pose, 500, seed=81, translation=0.06, angle_deg=30))
    far = hexa.inverse_batch(box_poses(hexa.home_pose, 500, seed=83, translation=0.14, angle_deg=50))
    far_rows = far.q[np.isfinite(far.q).all(axis=1)][:, hexa.closed_loop.prismatic_q]  # some beyond the limits
    rows = np.concatenate([warm[::3], box.lengths[box.converged], far_rows, warm[::4]])
    lines = [",".join(f"{v:.12g}" for v in r) for r in rows]
    for k, bad in enumerate(BAD_LINES):
        lines.insert(300 * k + 7, bad)
    path.write_text(",".join(LENGTH_COLUMNS) + "\n" + "\n".join(lines) + "\n")


def ik_file(hexa: hm.Hexapod, path) -> None:
    """~3000 poses (x, y, z, qx..qw), some out of reach or limits, bad rows."""
    poses = box_poses(hexa.home_pose, 3000, seed=82, translation=0.1, angle_deg=40)
    lines = [",".join(f"{v:.12g}" for v in pin.SE3ToXYZQUAT(pin.SE3(T))) for T in poses]
    for k, bad in enumerate(("0,0,0.4,0,0,0,1.1", "0,0,x,0,0,0,1", "0,0", "nan,0,0.4,0,0,0,1")):
        lines.insert(500 * k + 11, bad)
    path.write_text("x,y,z,qx,qy,qz,qw\n" + "\n".join(lines) + "\n")


@pytest.mark.parametrize(("kind", "prove"), [("fk", False), ("fk", True), ("ik", False)])
def test_cli_output_is_the_row_by_row_output(kind, prove, tmp_path, capsys):
    hexa = hexapod("reference")
    inp, out = tmp_path / f"{kind}.csv", tmp_path / "out.csv"
    (fk_file if kind == "fk" else ik_file)(hexa, inp)
    expected, failed, first = per_row(hexa, inp, kind, prove)
    code = main([kind, "reference", str(inp), "-o", str(out), *(["--prove"] if prove else [])])
    err = capsys.readouterr().err
    assert_same_table(out.read_text(), expected)
    assert expected.count("\n") > 3000 and "invalid_input" in expected
    assert code == (1 if failed else 0) and failed
    assert f"{failed} of " in err and first in err
