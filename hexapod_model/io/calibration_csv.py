"""The measured-poses CSV of ``hexapod calibrate``: readings and the measured pose of each row.

Columns (the ``hexapod reproduce --data`` format, extended for extra sensors):

* ``l1..l6``: the six legs' readings (m, zero at home);
* for a geometry with extra sensors, optionally their readings in the geometry's reading order
  (``HexapodGeometry.reading_names``): ``l7``, ``l8``, ... for measuring legs (m), then
  ``tilt_x``, ``tilt_y`` for an inclinometer (rad). Either all of them or none: a file with
  the six legs' readings only is calibrated from the six legs;
* ``x,y,z`` (m), ``qx,qy,qz,qw``: the measured pose of a marker or tool frame in the measuring
  device's frame.

Every row must be valid under the line rules of :mod:`hexapod_model.io.tables` (the cell
count of the header, finite numbers within its magnitude limit, a unit quaternion within its
tolerance): the first row that is not raises :class:`~hexapod_model.exceptions.InputError`
naming its line. Columns the geometry does not read (``l7`` for a six-leg hexapod) are ignored.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..calibration.problem import MeasuredPoses
from ..description.geometry import HexapodGeometry
from ..exceptions import InputError
from ..lie import matrix_to_quaternion
from .tables import LENGTH_COLUMNS, LIMITS, MAX_MAGNITUDE, TableReader, poses_from_table, write_table

MEASURED_POSE_COLUMNS = ["x", "y", "z", "qx", "qy", "qz", "qw"]


def reading_columns(names: Sequence[str]) -> list[str]:
    """The CSV column of each reading name: ``legK`` is ``lK`` (m); ``tilt_x``, ``tilt_y`` (rad) as named."""
    return [f"l{n[3:]}" if n.startswith("leg") else n for n in names]


def load_poses(path: str | Path, nominal: HexapodGeometry | None = None) -> MeasuredPoses:
    """A measured-poses CSV (module doc) as :class:`~hexapod_model.calibration.problem.MeasuredPoses`.

    Args:
        path: the CSV file.
        nominal: the geometry to calibrate; its extra sensors' columns are read when the file
            has them (``None``: the six legs' only).

    Raises:
        InputError: a missing column, some but not all of the extra sensors' columns, fewer
            than 2 rows, or a bad row (named by its line).
    """
    extra = reading_columns(nominal.reading_names[6:]) if nominal is not None else []
    limits = LIMITS | dict.fromkeys(extra, MAX_MAGNITUDE)
    with TableReader(path, LENGTH_COLUMNS + MEASURED_POSE_COLUMNS, None, limits) as table:
        present = [c for c in extra if c in table.header]
        if present and present != extra:
            missing = [c for c in extra if c not in present]
            raise InputError(
                "CSV header",
                f"{path}: {', '.join(present)}",
                f"give all of the extra readings' columns {', '.join(extra)} or none (missing {', '.join(missing)})",
            )
        rows = table.read(LENGTH_COLUMNS + present + MEASURED_POSE_COLUMNS)
    if len(rows) < 2:
        raise InputError("data rows", len(rows), f"{path}: need at least 2 measured poses")
    n = 6 + len(present)
    measured, pose_errors = poses_from_table(MEASURED_POSE_COLUMNS, rows.values[:, n:])
    for k in range(len(rows)):
        why = rows.errors[k] or pose_errors[k]
        if why:
            raise InputError("data row", k + 1, f"{path}: line {rows.lines[k]}: {why}")
    lines = tuple(int(line) for line in rows.lines)
    return MeasuredPoses(rows.values[:, :n], measured, str(path), lines)


def save_poses(path: str | Path, data: MeasuredPoses, names: Sequence[str] | None = None) -> Path:
    """Write ``data`` as a measured-poses CSV (the inverse of :func:`load_poses`).

    ``names``: the reading names of the data's columns (default ``leg1..leg6`` and, for more
    columns, ``leg7``, ...).
    """
    width = data.readings.shape[1]
    names = list(names) if names is not None else [f"leg{i + 1}" for i in range(width)]
    if len(names) != width:
        raise InputError("reading names", len(names), f"need one per reading column ({width})")
    q = matrix_to_quaternion(data.measured[:, :3, :3])
    rows = np.hstack([data.readings, data.measured[:, :3, 3], q]).tolist()
    write_table(path, reading_columns(names) + MEASURED_POSE_COLUMNS, rows)
    return Path(path)
