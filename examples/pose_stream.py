"""Reconstruct a pose stream from a CSV of leg readings, each sample warm from the one before.

    python examples/pose_stream.py [READINGS.csv] [-o poses.csv]

READINGS.csv: a header with ``l1..l6`` (m, zero at home; other columns such as ``t`` are
carried over) and one sample per row. The rows are solved as one batch in order, each from
the previous good pose; a row that cannot be read or solved keeps its place with its status,
and nothing is guessed for it. ``hexapod fk`` does the same for files of any length.
"""

import argparse
from pathlib import Path

import numpy as np

import hexapod_model as hm
from hexapod_model.io.tables import LENGTH_COLUMNS, column, pose_columns, read_table, write_table

HERE = Path(__file__).resolve().parent

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("readings", nargs="?", default=HERE.parent / "docs" / "examples" / "stream.csv")
ap.add_argument("-o", "--output", default="poses.csv")
args = ap.parse_args()

header, table = read_table(args.readings, LENGTH_COLUMNS)  # a bad cell is NaN, a bad row an error
readings = column(header, table, LENGTH_COLUMNS)
hexa = hm.Hexapod.from_preset("reference", compiled=len(readings) > 1000)  # NumPy kernels for short inputs
result = hexa.forward_batch(readings, warm=True)

values = np.full((len(readings), 10), np.nan)  # x, y, z (m), qx..qw, roll, pitch, yaw (deg)
values[result.converged] = pose_columns(result.poses[result.converged])
extra = [name for name in header if name not in LENGTH_COLUMNS]
rows = [
    [*column(header, table, extra)[k], *values[k], ";".join(result.flags[k]) or result.status[k]]  # near_singular
    for k in range(len(readings))
]
write_table(args.output, [*extra, "x", "y", "z", "qx", "qy", "qz", "qw", "roll", "pitch", "yaw", "status"], rows)

z = values[result.converged, 2]
solved = int(result.converged.sum())
print(f"{solved} of {len(readings)} samples solved; platform height {z.min():.4f}..{z.max():.4f} m")
for k in np.flatnonzero(~result.converged):
    print(f"sample {k + 1}: {result.status[k]}: {result.messages[k]}")
print(f"wrote {args.output}")
