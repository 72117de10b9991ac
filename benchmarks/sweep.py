"""Candidates per second of ``hexapod sweep`` on a Dask LocalCluster of 1 and 2 worker processes.

Each run evaluates the same random sample of candidates around the reference fixture (platform and
base radius, home height) into a fresh folder, on a cluster that has already loaded the package and
run one candidate (the numba kernels compiled or read from their cache). It prints the wall time,
candidates per second and the mean time a task reported, with the load average before and after:
on a shared machine the other processes decide what a second worker gains.

    python benchmarks/sweep.py [--candidates 12] [--grid 7] [--workers 1 2]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from distributed import Client, LocalCluster  # noqa: E402

from hexapod_model.description.presets import get_preset  # noqa: E402
from hexapod_model.studies.evaluate import Settings  # noqa: E402
from hexapod_model.studies.sweep import run_sweep  # noqa: E402
from hexapod_model.studies.sweep_spec import SweepSpec  # noqa: E402


def spec_of(candidates: int, grid: int, seed: int) -> SweepSpec:
    params = {"platform_radius": (0.12, 0.18), "base_radius": (0.22, 0.28), "home_height": (0.36, 0.44)}
    return SweepSpec(
        get_preset("reference"),
        "reference",
        params,
        frozenset(params),
        mode="random",
        count=candidates,
        seed=seed,
        settings=replace(Settings(), grid=grid, cone_deg=15.0, cone_samples=4),
        leg_stiffness=2.0e7,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=12)
    ap.add_argument("--grid", type=int, default=7)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    print(f"sweep benchmark: {args.candidates} candidates, grid {args.grid}, 5 orientations, {os.cpu_count()} cores")
    print(f"  load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"  {'workers':>8s}{'wall s':>9s}{'cand/s':>9s}{'task s':>9s}")
    for n in args.workers:
        with (
            LocalCluster(
                n_workers=n, threads_per_worker=1, host="127.0.0.1", dashboard_address=None, silence_logs=40
            ) as cluster,
            Client(cluster) as client,
        ):
            client.wait_for_workers(n)
            with tempfile.TemporaryDirectory() as tmp:  # warm-up: every worker loads and compiles once
                run_sweep(spec_of(n, 5, seed=99), tmp, scheduler=cluster.scheduler_address)
            with tempfile.TemporaryDirectory() as tmp:
                start = time.perf_counter()
                result = run_sweep(
                    spec_of(args.candidates, args.grid, seed=0), tmp, scheduler=cluster.scheduler_address
                )
                wall = time.perf_counter() - start
            tasks = [float(r["seconds"]) for r in result["rows"] if r["status"] == "ok"]
            mean = sum(tasks) / len(tasks) if tasks else float("nan")
            print(f"  {n:8d}{wall:9.2f}{args.candidates / wall:9.2f}{mean:9.2f}")
    print(f"  load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
