"""The compiled Newton path against the general one and the straightforward Pinocchio Newton.

In one process, alternating (the machine is shared: the load affects every variant alike),
CPU time per solve (``time.thread_time_ns``, so preemption by other processes is not counted):

* warm FK along trajectory A at 1 kHz (each solve from the previous one, tol 1e-10), cold FK
  from home over box poses, IK: ``Hexapod.forward`` / ``inverse`` with the compiled solver,
  with the general solver (Pinocchio's ``computeJointJacobians`` per iteration), and the
  straightforward Newton of ``benchmarks/baseline_newton.py`` for warm FK;
* batches: ``forward_batch`` of the box poses from home and of the trajectory (warm), and
  ``inverse_batch``, in solves per second of CPU time.

    python benchmarks/compiled_newton.py [PRESET] [--rounds 3] [--samples 1000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from baseline_newton import baseline_forward

from hexapod_model import Hexapod
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics.newton.solver import NewtonSolver
from hexapod_model.studies.bench import BENCH_TOL, trajectory_readings


def use(hexa: Hexapod, general: bool) -> None:
    """Give the calling thread the general solvers (``general``) or the default ones."""
    held = (hexa.engine.held_forward, hexa.engine.held_inverse)
    hexa.engine.local.solvers = {h: NewtonSolver(hexa.closed_loop, h) for h in held} if general else {}


def per_solve(solve, inputs) -> np.ndarray:
    """CPU microseconds of each ``solve(x, previous)``."""
    out, prev = np.empty(len(inputs)), None
    for k, x in enumerate(inputs):
        t0 = time.thread_time_ns()
        prev = solve(x, prev)
        out[k] = (time.thread_time_ns() - t0) / 1e3
    return out


def rate(call, n: int) -> float:
    """Solves per CPU second of one ``call()`` solving ``n`` rows."""
    t0 = time.thread_time_ns()
    call()
    return n / ((time.thread_time_ns() - t0) / 1e9)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("preset", nargs="?", default="reference")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--samples", type=int, default=1000)
    args = ap.parse_args(argv)
    hexa = Hexapod.from_preset(args.preset)
    _, warm = trajectory_readings(hexa)
    box = hexa.inverse_batch(box_poses(hexa.home_pose, args.samples, seed=0))
    cold, poses = box.lengths[box.converged], box.poses[box.converged]
    first = hexa.forward(warm[0])
    cases = {
        "warm FK": lambda: per_solve(lambda x, p: hexa.forward(x, guess=p or first, tol=BENCH_TOL), warm[1:]),
        "cold FK": lambda: per_solve(lambda x, _: hexa.forward(x, tol=BENCH_TOL), cold),
        "IK": lambda: per_solve(lambda T, _: hexa.inverse(T, tol=BENCH_TOL), poses),
    }
    times: dict[tuple[str, str], list[np.ndarray]] = {}
    for _ in range(args.rounds):
        for variant in ("compiled", "general"):
            use(hexa, variant == "general")
            for name, run in cases.items():
                times.setdefault((name, variant), []).append(run())
        use(hexa, False)
        q = first.q

        def baseline(x, _):
            nonlocal q
            q = baseline_forward(hexa, x, q)[0]

        times.setdefault(("warm FK", "Pinocchio Newton"), []).append(per_solve(baseline, warm[1:]))
    print(f"{args.preset}: CPU microseconds per solve, best median of {args.rounds} alternating rounds")
    print(f"{'case':10s}{'variant':>18s}{'median':>9s}{'p95':>9s}{'p99':>9s}")
    for (name, variant), runs in times.items():
        best = min(runs, key=np.median)
        print(f"{name:10s}{variant:>18s}" + "".join(f"{np.percentile(best, p):9.1f}" for p in (50, 95, 99)))
    use(hexa, False)
    batches = {
        "forward_batch, box poses from home": (lambda: hexa.forward_batch(cold, tol=BENCH_TOL), len(cold)),
        "forward_batch, trajectory A warm": (lambda: hexa.forward_batch(warm, warm=True, tol=BENCH_TOL), len(warm)),
        "inverse_batch, box poses from home": (lambda: hexa.inverse_batch(poses, tol=BENCH_TOL), len(poses)),
    }
    for label, (call, n) in batches.items():
        print(f"{label:38s}{max(rate(call, n) for _ in range(args.rounds)):9.0f} solves/s (best of {args.rounds})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
