"""What the assembly check of direct kinematics costs and how often it refuses, per preset.

    python benchmarks/certificate.py [PRESET ...] [--poses N] [--seed S] [--warm-offset M]

For ``N`` random poses per preset (home +- 50 mm, roll/pitch/yaw +- 25 deg, within the limits),
the readings are solved cold (from home) and warm (from the pose moved by ``warm-offset`` m) by

* the plain Newton iteration (``NewtonSolver.iterate`` without the check), and
* the checked first attempt (``certified_forward``: the same iteration with the contraction
  and determinant-sign checks), then ``Hexapod.forward`` as a whole.

It prints per preset and mode the median time of each, and the *refusals*: solves whose
checked first attempt fails (the readings path is then followed in substeps), and those whose
final status is not ``converged``. The check is a heuristic (docs/solver.md): these figures
measure its cost and how often it declines, not what it proves.
"""

from __future__ import annotations

import argparse
import time
from collections import Counter

import numpy as np

from hexapod_model import Hexapod
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.presets import PRESETS, get_preset


def run(name: str, n: int, seed: int, offset: float) -> dict:
    """Median times (us) and refusal counts of cold and warm solves of preset ``name``."""
    hexa = Hexapod.load(name)
    solver = hexa.engine.solver(hexa.engine.held_forward)
    rng = np.random.default_rng(seed + 1)
    hexa.forward(np.zeros(6))  # compile / warm up
    out: dict = {"preset": name}
    times: dict[str, dict[str, list[float]]] = {
        m: {"plain": [], "checked": [], "forward": []} for m in ("cold", "warm")
    }
    counts = {"cold": Counter(), "warm": Counter()}
    for T in box_poses(hexa.home_pose, n, seed, 0.05, 25.0):
        truth = hexa.inverse(T, check=False)
        if not truth.converged:
            continue
        d = rng.normal(size=3)
        moved = T.copy()
        moved[:3, 3] += offset * d / np.linalg.norm(d)
        near = hexa.inverse(moved, check=False)
        starts = {"cold": None}
        if near.converged:
            starts["warm"] = near
        for mode, guess in starts.items():
            joints = hexa.joints_of(truth.lengths)
            start = hexa.engine.start(guess)
            sign = solver.home_sign if guess is None else guess.det_sign
            q0 = start.copy()
            q0[hexa.closed_loop.prismatic_q] = joints
            t0 = time.perf_counter()
            solver.iterate(q0, 1e-12, 20)
            t1 = time.perf_counter()
            attempt = solver.certified_forward(start, joints, 1e-12, 20, sign)
            t2 = time.perf_counter()
            sol = hexa.forward(truth.lengths, guess, check=False)
            t3 = time.perf_counter()
            times[mode]["plain"].append(t1 - t0)
            times[mode]["checked"].append(t2 - t1)
            times[mode]["forward"].append(t3 - t2)
            counts[mode]["solves"] += 1
            counts[mode]["first_attempt_refused"] += len(attempt) != 6
            counts[mode]["not_converged"] += sol.status != "converged"
    for mode in ("cold", "warm"):
        out[mode] = dict(counts[mode])
        for key, values in times[mode].items():
            out[mode][f"{key}_median_us"] = float(np.median(values) * 1e6) if values else float("nan")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=[n for n in PRESETS if not get_preset(n).redundant])  # six readings
    ap.add_argument("--poses", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--warm-offset", type=float, default=1e-4, help="m (default 1e-4: a 1 kHz sample at 0.1 m/s)")
    args = ap.parse_args(argv)
    for name in args.presets:
        r = run(name, args.poses, args.seed, args.warm_offset)
        for mode in ("cold", "warm"):
            c = r[mode]
            print(
                f"{name:12s} {mode}: {c.get('solves', 0)} solves; plain Newton {c['plain_median_us']:.1f} us, "
                f"checked first attempt {c['checked_median_us']:.1f} us, forward {c['forward_median_us']:.1f} us "
                f"(medians); first attempt refused {c.get('first_attempt_refused', 0)}, "
                f"not converged {c.get('not_converged', 0)}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
