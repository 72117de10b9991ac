"""Calibrate a fixture's joint geometry from measured poses; keep it only if it predicts better.

    python examples/calibrate_fixture.py [MEASURED.csv] [-o calibrated.toml] [--force]

MEASURED.csv holds one measured pose per row: the six leg readings ``l1..l6`` (m, zero at home)
and the pose a measuring device saw, ``x,y,z`` (m) and ``qx,qy,qz,qw`` (the format of
``hexapod reproduce --data``). Without it, the script simulates 60 such measurements of a
``reference`` fixture built with joint errors (±0.5 mm, ±0.3°, ±1 mm on the encoders).

The joint geometry is identified together with the measuring device's frame and the marker's
frame on the platform. A 5-fold validation then predicts each pose with a geometry calibrated
on the other poses: the calibrated geometry is written only when its held-out error is lower
than the nominal one's by more than twice the standard error. ``hexapod calibrate`` does the
same with a report (docs/calibration.md).

Each stage says what it does on stderr (the whole takes one to two minutes, the first run after
installation a minute more for the solver's compilation).
"""

import argparse
import sys

import numpy as np
from tqdm import tqdm

import hexapod_model as hm
from hexapod_model.calibration.identify import identify
from hexapod_model.calibration.validation import cross_validate
from hexapod_model.description.geometry_toml import save_geometry
from hexapod_model.studies.calibrate import load_poses, simulate

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("measured", nargs="?", help="measured poses (default: a simulated fixture)")
ap.add_argument("-o", "--output", default="calibrated.toml")
ap.add_argument("--force", action="store_true", help="write the calibrated geometry in any case")
args = ap.parse_args()


def say(text: str) -> None:
    """A stage, on stderr (the results go to stdout)."""
    print(text, file=sys.stderr, flush=True)


def progress(iterable, total: int, desc: str):
    """A tqdm bar on stderr for the library's long loops."""
    return tqdm(iterable, total=total, desc=desc, file=sys.stderr)


nominal = hm.get_preset("reference")
say(f"reading {args.measured}" if args.measured else "simulating 60 measured poses of a fixture with joint errors")
data = load_poses(args.measured) if args.measured else simulate(nominal, 60, seed=3).data
hold = ("*_axis.*",)  # the Cardan axes' directions as drawn: fewer unknowns for a few dozen poses

say(f"identifying the geometry from {len(data.readings)} poses")
result = identify(nominal, data, hold=hold)
print(
    f"{data.source}: {len(data.readings)} poses, {int(result.identifiable.sum())} parameters identified, "
    f"{len(result.combinations)} combinations the poses cannot tell apart held at nominal"
)

say("5-fold validation: each pose predicted by the geometry fitted to the other folds")
check = cross_validate(
    nominal, data, folds=5, hold=hold, progress=progress
)  # each pose predicted by the other folds' fit
before, after = check.before[0], check.after[0]  # held-out position errors (mm)
gain = before - after
margin = 2 * gain.std(ddof=1) / np.sqrt(len(gain))
print(
    f"held-out position error: nominal {before.mean():.3f} mm, calibrated {after.mean():.3f} mm "
    f"(difference {gain.mean():.3f} ± {margin:.3f} mm)"
)

if gain.mean() > margin or args.force:
    save_geometry(result.geometry, args.output, comment=f"calibrated from {data.source}")
    hexa = hm.Hexapod.load(args.output, compiled=False)  # the calibrated fixture, as any geometry file
    print(f"wrote {args.output}; row 1 solved with it: {hexa.forward(data.readings[0]).status}")
else:
    print(f"{args.output} not written: the calibration does not predict held-out poses better; keep the nominal")
