"""One clearance query against one warm forward solve on the reference preset.

    python benchmarks/clearance.py [--poses N] [--seed S]

Random poses of the +-50 mm / +-25 deg box; for each, its readings (inverse kinematics) are
solved warm from the previous solution, and its configuration's clearance is measured three
ways: the fast kernel (numba; what ``Hexapod.clearance`` runs), the same kernel with coal for
the plates it cannot rule out, and coal's distance on every pair (Pinocchio's
``computeDistances``). Prints the median and p99 wall time of each (us).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hexapod_model import Hexapod
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics.clearance import query_of


def _timed(fn, *args) -> float:
    t0 = time.perf_counter()
    fn(*args)
    return time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    hexa = Hexapod.from_preset("reference")
    query = query_of(hexa)
    poses = list(box_poses(hexa.home_pose, args.poses, args.seed, translation=0.05, angle_deg=25))
    rows = [(T, hexa.inverse(T, check=False)) for T in poses]
    rows = [(T, s) for T, s in rows if s.converged]
    warm = hexa.forward(rows[0][1].lengths)
    query(warm.q)  # compiles the kernel (cached after the first run)
    forward, fast, coal = [], [], []
    for _, sol in rows:
        forward.append(_timed(hexa.forward, sol.lengths, warm))
        warm = hexa.forward(sol.lengths, warm)
        fast.append(_timed(hexa.clearance, warm.q))
        coal.append(_timed(query.all_pairs, warm.q))
    print(f"reference preset, {len(rows)} poses of the +-50 mm / +-25 deg box, {len(query.pairs)} pairs checked")
    for name, times in (("warm forward solve", forward), ("clearance (kernel)", fast), ("coal, every pair", coal)):
        t = np.array(times) * 1e6
        print(f"{name:22s} median {np.median(t):8.1f} us   p99 {np.percentile(t, 99):8.1f} us")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
