"""CSV tables of leg readings and poses (the ``hexapod fk`` / ``hexapod ik`` file formats).

* Readings: header ``l1,...,l6`` (metres, zero at home).
* Poses: ``x,y,z`` (metres, base frame), ``qx,qy,qz,qw`` and ``roll,pitch,yaw`` (degrees,
  ``R = Rz(yaw) Ry(pitch) Rx(roll)``). When reading, the quaternion wins if present,
  otherwise the angles are used.
* Solver columns: ``status`` (``ok`` or the failure name), ``iterations``, ``residual``.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import TextIO

import numpy as np

from ..exceptions import InputError
from ..kinematics.rotations import matrix_to_quaternion, matrix_to_rpy, quaternion_to_matrix, rpy_to_matrix

LENGTH_COLUMNS = [f"l{i}" for i in range(1, 7)]
POSE_COLUMNS = ["x", "y", "z", "qx", "qy", "qz", "qw", "roll", "pitch", "yaw"]
SOLVER_COLUMNS = ["status", "iterations", "residual"]


def read_table(path: str | Path | TextIO, required: list[str] | None = None) -> tuple[list[str], np.ndarray]:
    """Header and (n, k) float array of a CSV file or text stream; unparsable cells become NaN.

    Raises:
        InputError: missing file or missing required columns.
    """
    if not isinstance(path, (str, Path)):
        rows = list(csv.reader(path))
        path = getattr(path, "name", "<stream>")
    else:
        path = Path(path)
        try:
            with path.open(newline="") as fh:
                rows = list(csv.reader(fh))
        except OSError as exc:
            raise InputError("CSV file", str(path), exc.strerror or "cannot read") from None
    if not rows:
        raise InputError("CSV file", str(path), "empty file (expected a header line)")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in (required or []) if c not in header]
    if missing:
        raise InputError("CSV header", header, f"{path}: missing columns {missing}")

    def num(cell: str) -> float:
        try:
            return float(cell)
        except ValueError:
            return float("nan")

    data = np.array([[num(c) for c in r] + [np.nan] * (len(header) - len(r)) for r in rows[1:] if r], dtype=float)
    return header, data.reshape(-1, len(header))


def column(header: list[str], data: np.ndarray, names: list[str]) -> np.ndarray:
    """Columns ``names`` of a table, as an (n, len(names)) array."""
    return data[:, [header.index(n) for n in names]]


def poses_from_table(header: list[str], data: np.ndarray) -> np.ndarray:
    """(n, 4, 4) poses from a pose table (NaN rows stay NaN and are rejected by the solver)."""
    if not all(c in header for c in ("x", "y", "z")):
        raise InputError("CSV header", header, "pose tables need x,y,z columns")
    poses = np.tile(np.eye(4), (len(data), 1, 1))
    poses[:, :3, 3] = column(header, data, ["x", "y", "z"])
    if all(c in header for c in ("qx", "qy", "qz", "qw")):
        q = column(header, data, ["qx", "qy", "qz", "qw"])
        with np.errstate(invalid="ignore", divide="ignore"):
            poses[:, :3, :3] = quaternion_to_matrix(q)
    elif all(c in header for c in ("roll", "pitch", "yaw")):
        poses[:, :3, :3] = rpy_to_matrix(*np.radians(column(header, data, ["roll", "pitch", "yaw"])).T)
    else:
        raise InputError("CSV header", header, "pose tables need qx,qy,qz,qw or roll,pitch,yaw (deg) columns")
    return poses


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


def write_table(path: str | Path | None, header: list[str], rows: list[list], out=None) -> None:
    """Write rows as CSV to ``path`` (or to the stream ``out`` when ``path`` is None).

    Floats are written with 12 significant digits (sub-nanometre for metre-scale values).
    """

    def fmt(v):
        if isinstance(v, float):
            return "" if np.isnan(v) else f"{v:.12g}"
        return str(v)

    lines = [",".join(header)] + [",".join(fmt(v) for v in r) for r in rows]
    text = "\n".join(lines) + "\n"
    if path is None:
        out.write(text)
    else:
        Path(path).write_text(text)
