"""CSV tables of leg readings and poses (``hexapod fk`` / ``ik`` / ``reproduce --data`` files).

* Readings: header ``l1,...,l6`` (metres, zero at home).
* Poses: ``x,y,z`` (metres, base frame), ``qx,qy,qz,qw`` and/or ``roll,pitch,yaw`` (degrees,
  ``R = Rz(yaw) Ry(pitch) Rx(roll)``); see :func:`poses_from_table`.
* Solver columns: ``status`` (``ok`` or the failure name), ``iterations``, ``residual``.

Reading follows the line rules of :mod:`hexapod_model.io.csv_rows` (UTF-8, optional BOM,
blank lines counted, a row with the wrong cell count invalid, never re-flowed); the cells of
the columns above must be finite numbers of magnitude at most :data:`MAX_MAGNITUDE`.
"""

from __future__ import annotations

import csv
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np

from ..exceptions import InputError
from ..files import atomic_writer
from ..lie import (
    matrix_to_quaternion,
    matrix_to_rpy,
    quaternion_to_matrix,
    rotation_angle,
    rpy_to_matrix,
)
from .csv_rows import Rows, TableReader

__all__ = [
    "LENGTH_COLUMNS",
    "POSE_COLUMNS",
    "SOLVER_COLUMNS",
    "MAX_MAGNITUDE",
    "QUATERNION_TOLERANCE",
    "ROTATION_AGREEMENT",
    "Rows",
    "TableReader",
    "TableWriter",
    "column",
    "open_table",
    "pose_columns",
    "pose_input_columns",
    "pose_row",
    "poses_from_table",
    "read_table",
    "write_table",
]

LENGTH_COLUMNS = [f"l{i}" for i in range(1, 7)]
POSE_COLUMNS = ["x", "y", "z", "qx", "qy", "qz", "qw", "roll", "pitch", "yaw"]
#: the solver's columns of fk / ik output; ``message`` is empty on an ``ok`` row, else why it is not
SOLVER_COLUMNS = ["status", "iterations", "residual", "message"]
QUATERNION_COLUMNS = ["qx", "qy", "qz", "qw"]
RPY_COLUMNS = ["roll", "pitch", "yaw"]
#: largest |value| of a cell in l1..l6 or a pose column (m, deg or quaternion component):
#: no hexapod pose is that far out, and bounded inputs keep every derived number finite
MAX_MAGNITUDE = 1e6
#: largest | |q| - 1 | of a quaternion: a unit quaternion written with 6 or more decimals
#: passes (it is then divided by its norm, which undoes the rounding); anything else is invalid
QUATERNION_TOLERANCE = 1e-5
#: largest angle (rad) between qx..qw and roll,pitch,yaw when a row gives both
ROTATION_AGREEMENT = 1e-4
LIMITS = dict.fromkeys(LENGTH_COLUMNS + POSE_COLUMNS, MAX_MAGNITUDE)


def open_table(source: str | Path | IO[Any], required: Sequence[str] = (), name: str | None = None) -> TableReader:
    """A :class:`TableReader` on ``source`` (path or stream) with this module's value limits."""
    return TableReader(source, required, name, LIMITS)


def read_table(path: str | Path | IO[Any], required: list[str] | None = None) -> tuple[list[str], np.ndarray]:
    """Header and (n, k) float array of a whole CSV file (blank lines skipped).

    A cell that is not a finite number (or, in this module's columns, exceeds
    :data:`MAX_MAGNITUDE`) becomes NaN; rows are never re-flowed.

    Raises:
        InputError: unreadable file, missing required columns, a row whose cell count differs
            from the header's (naming its line).
    """
    with open_table(path, required or []) as table:
        rows = table.read(table.header)
        name = table.name
    bad = np.flatnonzero(rows.malformed)
    if bad.size:
        raise InputError("CSV row", name, f"line {rows.lines[bad[0]]}: {rows.errors[bad[0]]}")
    return table.header, rows.values


def column(header: list[str], data: np.ndarray, names: list[str]) -> np.ndarray:
    """Columns ``names`` of a table, as an (n, len(names)) array."""
    return data[:, [header.index(n) for n in names]]


def pose_input_columns(header: Sequence[str]) -> list[str]:
    """The columns a pose is read from: ``x,y,z`` and ``qx..qw`` and/or ``roll,pitch,yaw``."""
    missing = [c for c in ("x", "y", "z") if c not in header]
    if missing:
        raise InputError("CSV header", list(header), f"pose tables need x,y,z columns (missing {missing})")
    cols = ["x", "y", "z"]
    for group in (QUATERNION_COLUMNS, RPY_COLUMNS):
        have = [c for c in group if c in header]
        if have and len(have) < len(group):
            raise InputError("CSV header", list(header), f"has {have} but not all of {group}")
        cols += have
    if len(cols) == 3:
        raise InputError("CSV header", list(header), "pose tables need qx,qy,qz,qw or roll,pitch,yaw (deg) columns")
    return cols


def poses_from_table(columns: Sequence[str], values: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """(n, 4, 4) poses from pose-table values, and per row ``""`` or why the row is invalid.

    The quaternion is used when present: it must have unit norm within
    :data:`QUATERNION_TOLERANCE`. When ``roll,pitch,yaw`` are given too, both must describe
    the same rotation within :data:`ROTATION_AGREEMENT`. Invalid rows hold NaN.
    """
    columns = list(columns)
    n = len(values)
    poses = np.tile(np.eye(4), (n, 1, 1))
    errors = [""] * n
    poses[:, :3, 3] = column(columns, values, ["x", "y", "z"])
    rpy = None
    if RPY_COLUMNS[0] in columns:
        rpy = rpy_to_matrix(*np.radians(column(columns, values, RPY_COLUMNS)).T)
    if QUATERNION_COLUMNS[0] in columns:
        q = column(columns, values, QUATERNION_COLUMNS)
        norm = np.sqrt(np.sum(q * q, axis=1))  # |q| <= 2e6 by MAX_MAGNITUDE: no overflow
        off = np.abs(norm - 1.0)
        for k in np.flatnonzero(off > QUATERNION_TOLERANCE):
            errors[k] = (
                f"qx,qy,qz,qw is not a unit quaternion: norm {norm[k]:.9g} differs from 1 by more than "
                f"{QUATERNION_TOLERANCE:g}"
            )
        with np.errstate(invalid="ignore", divide="ignore"):
            poses[:, :3, :3] = quaternion_to_matrix(q)
        if rpy is not None:
            with np.errstate(invalid="ignore"):
                angle = rotation_angle(poses[:, :3, :3], rpy)
            for k in np.flatnonzero(angle > ROTATION_AGREEMENT):
                errors[k] = errors[k] or (
                    f"qx,qy,qz,qw and roll,pitch,yaw differ by {np.degrees(angle[k]):.6g} deg "
                    f"(more than {ROTATION_AGREEMENT:g} rad)"
                )
    elif rpy is not None:
        poses[:, :3, :3] = rpy
    bad = [k for k, e in enumerate(errors) if e]
    poses[bad] = np.nan
    return poses, errors


def pose_row(pose: np.ndarray) -> list[float]:
    """``x,y,z,qx,qy,qz,qw,roll,pitch,yaw`` (m, unit quaternion, degrees) of a 4x4 pose."""
    return pose_columns(np.asarray(pose)[None])[0].tolist()


def pose_columns(poses: np.ndarray) -> np.ndarray:
    """(n, 10) ``x,y,z,qx,qy,qz,qw,roll,pitch,yaw`` (m, unit quaternion, degrees) of (n, 4, 4) poses.

    Converts all rows in one call: per-row conversions cost ~100x more per pose.
    """
    poses = np.asarray(poses, dtype=float)
    R = poses[:, :3, :3]
    return np.hstack([poses[:, :3, 3], matrix_to_quaternion(R), np.degrees(matrix_to_rpy(R))])


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return "" if v != v else f"{v:.12g}"  # v != v: NaN, without a numpy call per cell
    return str(v)


class TableWriter:
    """Rows to a text stream, through the ``csv`` module; the header goes first.

    Floats are written with 12 significant digits (sub-nanometre for metre-scale values), NaN
    as an empty cell; lines end with a line feed.
    """

    def __init__(self, stream: IO[str], header: Sequence[str]):
        self._writer = csv.writer(stream, lineterminator="\n")
        self._writer.writerow(header)

    def write(self, row: Iterable[Any]) -> None:
        """Write one row."""
        self._writer.writerow([_cell(v) for v in row])


def write_table(path: str | Path | None, header: list[str], rows: Iterable[Iterable[Any]], out: Any = None) -> None:
    """Write rows as CSV to ``path`` atomically (or to the text stream ``out`` when ``path`` is None)."""
    if path is None:
        writer = TableWriter(out, header)
        for r in rows:
            writer.write(r)
        return
    with atomic_writer(path) as fh:
        writer = TableWriter(fh, header)
        for r in rows:
            writer.write(r)
