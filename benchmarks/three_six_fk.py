"""Timing and assembly counts of Shi, She and Duan's geometric direct kinematics (``ThreeSixFK``).

    python benchmarks/three_six_fk.py [--poses N] [--seed S]

Random poses of the +-100 mm / +-40 deg box on the ``3-6`` preset; for each, the readings of
the pose (inverse kinematics) are solved for every assembly. Prints the median / p99 wall time
of ``solve_all`` and of ``solve`` (nearest to home), the count of assemblies found, and whether
the pose that produced the readings was always among them (within 1e-6 m, rotations times the
base radius: next to a fold, where two assemblies nearly coincide, the readings fix the pose
only to about 1e-9 m).
"""

from __future__ import annotations

import argparse
import time
from collections import Counter

import numpy as np

from hexapod_model import Hexapod
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics.three_six import MAX_ASSEMBLIES, ThreeSixFK
from hexapod_model.tracking.tracker import pose_distance


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    hexa = Hexapod.from_preset("3-6")
    fk = ThreeSixFK(hexa.geometry)
    fk.solve_all(np.zeros(6))  # warm-up
    t_all, t_one, counts, missed = [], [], Counter(), 0
    for T in box_poses(hexa.home_pose, args.poses, args.seed, translation=0.1, angle_deg=40):
        ik = hexa.inverse(T, check=False)
        if not ik.converged:
            continue
        t0 = time.perf_counter()
        sols = fk.solve_all(ik.lengths)
        t1 = time.perf_counter()
        fk.solve(ik.lengths)
        t_all.append(t1 - t0)
        t_one.append(time.perf_counter() - t1)
        counts[len(sols)] += 1
        missed += min(pose_distance(s.pose, T, fk.length) for s in sols) > 1e-6
    for name, t in (("solve_all", t_all), ("solve", t_one)):
        us = np.array(t) * 1e6
        print(f"{name:10s} median {np.median(us):7.0f} us   p99 {np.percentile(us, 99):7.0f} us")
    found = ", ".join(f"{k}: {v}" for k, v in sorted(counts.items()))
    print(f"{len(t_all)} readings; assemblies found (count: readings) {found}; at most {MAX_ASSEMBLIES}")
    print(f"the pose that produced the readings was missed {missed} times")
    return 1 if missed else 0


if __name__ == "__main__":
    raise SystemExit(main())
