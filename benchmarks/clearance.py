"""The clearance query and the body check against a warm forward solve, beside the plain ones, on the reference preset.

    python benchmarks/clearance.py [--poses N] [--seed S] [--rounds R] [--json FILE]

Random poses of the +-50 mm / +-25 deg box; their readings (inverse kinematics) are solved
warm, each from the previous solution, without the body check (``check_body=False``) and with
it (the default), and so are the readings of trajectory A at 1 kHz (``floor_compare.py``'s warm
FK, the solver's default tolerance); each box configuration's clearance and body check are measured in the same
rounds, alternating (the machine is shared: the load affects every variant alike), in CPU time
(``time.thread_time_ns``):

* the clearance query: ``Hexapod.clearance``, its kernel call alone
  (:meth:`~hexapod_model.kinematics.clearance.ClearanceQuery.check` with an infinite bound is
  the same call), the plain query of ``benchmarks/clearance_plain.py`` (a 4x4 product per joint,
  coal on the plate pairs a bound cannot rule out, arrays allocated per call), and coal's
  distance on every pair (Pinocchio's ``computeDistances``);
* the body check of one answer: ``ClearanceQuery.check`` (the placements, the cone angles and
  the pairs closer than ``min_clearance`` in one call) and the plain check (NumPy cones, then the
  plain query).

Prints the median and p99 of the best round (us) and the answers' agreement; ``--json`` also
writes them (``benchmarks/performance_table.py`` reads it).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from clearance_plain import PlainCheck, PlainQuery

from hexapod_model import Hexapod
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics.clearance import query_of
from hexapod_model.studies.bench import trajectory_readings


def _times(fn, inputs) -> np.ndarray:
    """CPU microseconds of ``fn(x)`` for each input."""
    out = np.empty(len(inputs))
    for k, x in enumerate(inputs):
        t0 = time.thread_time_ns()
        fn(x)
        out[k] = (time.thread_time_ns() - t0) / 1e3
    return out


def _warm(hexa: Hexapod, lengths: list[np.ndarray]) -> np.ndarray:
    """CPU microseconds of each warm forward solve along ``lengths`` (from the previous solution).

    The solve without the Krawczyk proof of its step (``prove=False``): the body check's share of
    the solve is what these figures compare (the proof's cost: ``certificate.py``).
    """
    out, prev = np.empty(len(lengths)), hexa.forward(lengths[0])
    for k, x in enumerate(lengths):
        t0 = time.thread_time_ns()
        prev = hexa.forward(x, prev, prove=False)
        out[k] = (time.thread_time_ns() - t0) / 1e3
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--json", type=Path, help="also write the figures as JSON")
    args = ap.parse_args(argv)
    bare = Hexapod.from_preset("reference", check_body=False)
    checked = Hexapod.from_preset("reference")
    query, body = query_of(bare), checked.engine.body
    poses = box_poses(bare.home_pose, args.poses, args.seed, translation=0.05, angle_deg=25)
    sols = [s for s in (bare.inverse(T, check=False) for T in poses) if s.converged]
    lengths, qs = [s.lengths for s in sols], [s.q for s in sols]
    plain_query, plain_check = PlainQuery(query), PlainCheck(bare)
    work, out = query._work()
    ints, floats, frames = query.tables

    def kernel(q):
        return query._kernel(q, ints, floats, frames, work, out, np.inf, False)

    trajectory = list(trajectory_readings(bare)[1][: args.poses])
    variants = {
        "warm forward, check_body=False": lambda: _warm(bare, lengths),
        "warm forward, check_body=True": lambda: _warm(checked, lengths),
        "trajectory A, check_body=False": lambda: _warm(bare, trajectory),
        "trajectory A, check_body=True": lambda: _warm(checked, trajectory),
        "clearance: Hexapod.clearance": lambda: _times(bare.clearance, qs),
        "clearance: kernel call": lambda: _times(kernel, qs),
        "clearance: plain query": lambda: _times(plain_query, qs),
        "clearance: coal, every pair": lambda: _times(query.all_pairs, qs),
        "body check: one call": lambda: _times(body.violations, qs),
        "body check: plain": lambda: _times(plain_check, qs),
    }
    for run in variants.values():  # compile (or load) everything before timing
        run()
    rounds: dict[str, list[np.ndarray]] = {name: [] for name in variants}
    for _ in range(args.rounds):
        for name, run in variants.items():
            rounds[name].append(run())
    print(f"reference preset, {len(qs)} poses of the +-50 mm / +-25 deg box, {len(query.pairs)} pairs checked,")
    print(f"CPU time per call (best of {args.rounds} alternating rounds)")
    print(f"{'':34s}{'median':>9s}{'p99':>9s}")
    best = {name: min(r, key=np.median) for name, r in rounds.items()}
    for name, t in best.items():
        print(f"  {name:32s}{np.median(t):9.1f}{np.percentile(t, 99):9.1f}")
    report: dict = {
        "poses": len(qs),
        "pairs": len(query.pairs),
        "rounds": args.rounds,
        "us": {name: {"median": float(np.median(t)), "p99": float(np.percentile(t, 99))} for name, t in best.items()},
        "check_ratio": {},
        "query_ratio": {},
    }
    for label, kind in (("box poses", "warm forward"), ("trajectory A", "trajectory A")):
        ratio = np.median(best[f"{kind}, check_body=True"]) / np.median(best[f"{kind}, check_body=False"])
        print(f"  warm forward with / without the check, {label}: {ratio:.2f}x")
        report["check_ratio"][label] = float(ratio)
    query_us = np.median(best["clearance: Hexapod.clearance"])
    for label, kind in (("box poses", "warm forward"), ("trajectory A", "trajectory A")):
        ratio = query_us / np.median(best[f"{kind}, check_body=False"])
        print(f"  Hexapod.clearance / warm forward without the check, {label}: {ratio:.2f}x")
        report["query_ratio"][label] = float(ratio)
    worst = max(abs(bare.clearance(q).distance - plain_query(q).distance) for q in qs)
    coal = max(abs(bare.clearance(q).distance - query.all_pairs(q).min()) for q in qs)
    flags = sum([k for k, _ in body.violations(q)] == plain_check(q) for q in qs)
    print(f"answers: the query against the plain one {worst:.1e} m, against coal on every pair {coal:.1e} m;")
    print(f"the body check's verdicts equal the plain check's on {flags} of {len(qs)} poses")
    if args.json:
        report["agreement"] = {"plain_query_m": float(worst), "coal_m": float(coal), "verdicts_equal": int(flags)}
        args.json.write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
