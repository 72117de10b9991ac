"""Solver timing figures (``hexapod bench``, ``benchmarks/run_benchmarks.py``).

* warm FK: Jakobović and Jelenković's trajectory A, scaled to the hexapod (paper unit = base radius / 50),
  sampled at 1 kHz; each solve starts from the previous solution, tolerance 1e-10;
* cold FK: random poses of the +-50 mm / +-25 deg box, each solved from home;
* IK: the same poses, each from home.

Times are wall-clock per solve (``time.perf_counter``), in microseconds.
"""

from __future__ import annotations

import time

import numpy as np

from ..analysis.trajectories import box_poses, trajectory_poses
from ..kinematics.hexapod import Hexapod
from ..tracking.tracker import characteristic_length

BENCH_TOL = 1e-10  # closure residual of every timed solve (the figure)
TARGETS_US = {"warm_fk": 50.0, "cold_fk": 1000.0, "ik": 100.0}


def _stats(times_s: list[float], iterations: list[int]) -> dict:
    t = np.asarray(times_s) * 1e6
    return {
        "n": int(t.size),
        "median_us": float(np.median(t)),
        "p95_us": float(np.percentile(t, 95)),
        "p99_us": float(np.percentile(t, 99)),
        "iterations_mean": float(np.mean(iterations)),
        "iterations_max": int(np.max(iterations)),
    }


def trajectory_readings(hexa: Hexapod, name: str = "A") -> tuple[np.ndarray, np.ndarray]:
    """Trajectory readings at 1 kHz.

    Jakobović and Jelenković's trajectory ``name`` at 1 kHz scaled to the hexapod (paper unit = base
    radius / 50): the (n, 4, 4) true poses and the (n, 6) leg readings (m) that produce them.
    """
    _, poses = trajectory_poses(name, hexa.home_pose, characteristic_length(hexa) / 50.0)
    readings, sol = [], None
    for T in poses:
        sol = hexa.inverse(T, guess=sol)
        readings.append(sol.lengths)
    return poses, np.array(readings)


def run_benchmarks(hexa: Hexapod, samples: int = 1000, seed: int = 0) -> dict:
    """Time warm FK, cold FK and IK on ``hexa``; returns the figures (microseconds)."""
    _, readings = trajectory_readings(hexa)
    poses = box_poses(hexa.home_pose, samples, seed)
    box = [hexa.inverse(T, check=False) for T in poses]
    box = [s for s in box if s.converged]
    for _ in range(2):  # warm-up: JIT, caches
        hexa.forward(readings[1], guess=hexa.forward(readings[0]))
    report: dict = {"nq": hexa.nq}

    def timed(solve, inputs) -> dict:
        times, its, sol = [], [], None
        for x in inputs:
            t0 = time.perf_counter()
            sol = solve(x, sol)
            times.append(time.perf_counter() - t0)
            its.append(sol.iterations)
        return _stats(times, its)

    first = hexa.forward(readings[0])
    report["warm_fk"] = timed(lambda x, prev: hexa.forward(x, guess=prev or first, tol=BENCH_TOL), readings[1:])
    report["cold_fk"] = timed(lambda x, _: hexa.forward(x, tol=BENCH_TOL), [s.lengths for s in box])
    report["ik"] = timed(lambda x, _: hexa.inverse(x, tol=BENCH_TOL), [s.pose for s in box])
    report["targets_median_us"] = TARGETS_US
    return report
