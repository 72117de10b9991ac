"""The simulated calibration study of ``hexapod calibrate --simulate``, timed.

    python benchmarks/calibration_study.py [--preset reference] [--poses 100] [--seed 0]
                                           [--folds 5] [--json FILE] [--img DIR]

Prints the held-out errors before / after calibration and of the true geometry (and the
nominal geometry's errors if the frames were known exactly), the check of
the identified parameters against the truth, and the wall time of identification plus k-fold
validation (the study's target: under 60 s for 100 poses). ``--img`` writes the figures
(``docs/img/calibration_*.png`` for docs/calibration.md). docs/calibration.md quotes its output.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from hexapod_model.calibration.frames import error_stats, pose_errors, predict
from hexapod_model.description.presets import get_preset
from hexapod_model.kinematics.hexapod import Hexapod
from hexapod_model.studies.calibrate import run_calibration, simulate
from hexapod_model.studies.calibrate_report import truth_check


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="reference")
    ap.add_argument("--poses", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--folds", type=int, default=5)
    ap.add_argument("--hold", action="append", default=[], help="parameters to keep nominal (quick runs)")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--img", type=Path, help="write the figures into this folder")
    args = ap.parse_args(argv)
    Hexapod.from_preset(args.preset).forward([0.001] * 6)  # compile / load the numba kernels first
    start = time.perf_counter()
    sim = simulate(get_preset(args.preset), args.poses, args.seed)
    result = run_calibration(
        sim.nominal, sim.data, folds=args.folds, seed=args.seed, simulation=sim, hold=tuple(args.hold)
    )
    total = time.perf_counter() - start
    nominal = Hexapod.from_geometry(sim.nominal)
    P = np.array([nominal.forward(r).pose for r in sim.data.readings])
    rows = {
        "before (nominal, true frames)": error_stats(
            pose_errors(predict(sim.measuring_frame, P, sim.marker_frame), sim.data.measured)
        ),
        "before (nominal, frames fitted)": error_stats(result.validation.before),
        "after (calibrated)": error_stats(result.validation.after),
        "true geometry": error_stats(result.true_errors),
    }
    print(f"{args.preset}, {args.poses} poses, seed {args.seed}, {args.folds}-fold held-out errors:")
    for label, s in rows.items():
        print(
            f"  {label:32s} translation {s['translation_mean_mm']:.4f} mm mean, {s['translation_max_mm']:.4f} max; "
            f"rotation {s['rotation_mean_deg']:.4f} deg mean, {s['rotation_max_deg']:.4f} max"
        )
    check = truth_check(result)
    ident = result.identification
    print(
        f"  identified {check['identifiable']} of {ident.parameters.size} parameters, "
        f"{check['within_3_sigma']} within 3 sigma of the truth "
        f"(worst {check['worst']['name']} {check['worst']['error_over_sigma']:+.2f} sigma)"
    )
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "default")
    print(f"  identification + validation {result.seconds:.1f} s, with the simulation {total:.1f} s "
          f"(BLAS threads: {threads}, {os.cpu_count()} cores)")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps({**rows, "truth": check, "seconds": result.seconds, "total": total}, indent=2))
    if args.img:
        from hexapod_model.plots.calibrate import write_figures

        for path in write_figures(args.img, result):
            print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
