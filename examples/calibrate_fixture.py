"""Calibrate a fixture's joint geometry from measured poses, then solve with the calibrated model.

    python examples/calibrate_fixture.py [MEASURED.csv] [-o calibrated.toml]

MEASURED.csv holds one measured pose per row: the six leg readings ``l1..l6`` (m, zero at home)
and the pose a measuring device saw, ``x,y,z`` (m) and ``qx,qy,qz,qw`` (the format of
``hexapod reproduce --data``). The measuring device's frame and the marker's frame on the
platform are identified with the joint geometry. ``hexapod calibrate`` does the same with a
k-fold validation and a report (docs/calibration.md).
"""

import argparse
from pathlib import Path

import numpy as np

import hexapod_model as hm
from hexapod_model.calibration.identify import identify
from hexapod_model.description.geometry_toml import save_geometry
from hexapod_model.kinematics.rotations import pose_distance
from hexapod_model.studies.calibrate import load_poses

HERE = Path(__file__).resolve().parent

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("measured", nargs="?", default=HERE.parent / "docs" / "examples" / "measured.csv")
ap.add_argument("-o", "--output", default="calibrated.toml")
args = ap.parse_args()

data = load_poses(str(args.measured))
# The Cardan axes' directions held at their drawing values: fewer unknowns for 40 poses.
result = identify(hm.get_preset("reference"), data, hold=("*_axis.*",))
predicted, ok = result.predict(data.readings)
errors_mm = 1e3 * np.linalg.norm(predicted[ok, :3, 3] - data.measured[ok, :3, 3], axis=1)  # device frame
print(f"{len(data.readings)} measured poses, {int(result.identifiable.sum())} parameters identified")
print(f"position error after calibration: mean {np.mean(errors_mm):.3f} mm, max {np.max(errors_mm):.3f} mm")
print(f"{len(result.combinations)} combinations these poses cannot tell apart, held at nominal; the first:")
print("  ", result.combinations[0].describe())

save_geometry(result.geometry, args.output, comment=f"calibrated from {args.measured}")
calibrated = hm.Hexapod.load(args.output, compiled=False)  # the calibrated fixture, as any geometry file
nominal = hm.Hexapod.from_preset("reference", compiled=False)
a, b = calibrated.forward(data.readings[0]), nominal.forward(data.readings[0])
print(f"wrote {args.output}; row 1 solved with it lies {1e3 * pose_distance(a.pose, b.pose, 0.0):.3f} mm from nominal")
