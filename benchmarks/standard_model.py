"""Throughput of the standard (spherical-joint) Stewart-Gough model, batch over many poses.

    python benchmarks/standard_model.py [PRESET] [--poses N] [--repeat R]

Prints poses/s for batch inverse kinematics (``StandardModel.inverse``) and batch Newton
direct kinematics from the home pose (``StandardModel.forward``) on random poses of Bem et al.'s
test box (+-50 mm, +-25 deg). Targets on the development machine: IK >= 1e6 poses/s, FK >= 2e5
poses/s. The best of ``--repeat`` runs is reported (after one warm-up that loads numba).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hexapod_model.analysis.standard import StandardModel
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.presets import get_preset


def best_rate(func, n: int, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - t0)
    return n / best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("preset", nargs="?", default="reference")
    ap.add_argument("--poses", type=int, default=200_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    sm = StandardModel.from_geometry(get_preset(args.preset))
    poses = box_poses(sm.home_pose, args.poses, seed=0)
    readings = sm.inverse(poses)
    sm.forward(readings[:10])  # warm-up: load the numba kernel
    ik = best_rate(lambda: sm.inverse(poses), args.poses, args.repeat)
    fk = best_rate(lambda: sm.forward(readings), args.poses, args.repeat)
    res = sm.forward(readings)
    err = np.abs(res.poses - poses).max()
    print(f"standard model, preset {args.preset}, {args.poses} poses (Bem et al. (2026) box)")
    print(f"  batch IK : {ik:12,.0f} poses/s   (target >= 1,000,000)")
    print(f"  batch FK : {fk:12,.0f} poses/s   (target >=   200,000; from home, tol 1e-12 m)")
    print(
        f"  FK: {res.converged.mean():.1%} converged, mean {res.iterations.mean():.2f} / max {res.iterations.max()} "
        f"iterations, max |pose - truth| {err:.2g}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
