"""Where ``hexapod reproduce`` spends its time, and ``hexapod evaluate`` with 1 and 2 workers.

``reproduce`` (default): one process runs the command's steps in order and prints, per step,
wall and CPU time (imports, loading the hexapod, drawing the poses, both models' solves, the
convergence traces of Figs. 6-7 with their cost per Newton step, the conditioning table, each
figure). ``evaluate``: ``hexapod evaluate --workers 1`` and ``--workers 2`` alternately in fresh
processes, wall time and CPU time of the process and its workers (``os.wait4``). Both print the
load average before and after: on a shared machine the other processes' load decides what a
second worker can gain.

    python benchmarks/study_commands.py [reproduce] [--poses 3000]
    python benchmarks/study_commands.py evaluate [--runs 3] [--grid 21]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


class Clock:
    """Wall and CPU time since the previous :meth:`mark`, printed with a label."""

    def __init__(self) -> None:
        self.wall, self.cpu = time.perf_counter(), time.process_time()

    def mark(self, label: str) -> None:
        """Print the interval since the last mark under ``label`` and start the next."""
        wall, cpu = time.perf_counter(), time.process_time()
        print(f"  {label:46s}{wall - self.wall:8.2f}{cpu - self.cpu:8.2f}")
        self.wall, self.cpu = wall, cpu


def load() -> str:
    return "load average " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def reproduce(poses: int) -> None:
    """The steps of ``hexapod reproduce --poses N --out DIR`` (reference preset), timed one by one."""
    print(load())
    print(f"  {'step':46s}{'wall s':>8s}{'CPU s':>8s}")
    clock = Clock()
    import numpy as np

    from hexapod_model.cli import reproduce as _cli  # noqa: F401  (the command's imports)

    clock.mark("imports (hexapod_model, numba, scipy)")
    from hexapod_model.analysis.conditioning import condition_numbers
    from hexapod_model.kinematics.hexapod import load_hexapod
    from hexapod_model.studies.reproduce import DEFAULT_ENCODER_NOISE, run_study, simulate

    hexa = load_hexapod("reference")
    clock.mark("load the hexapod (numba cache)")
    data = simulate(hexa, poses, 0, DEFAULT_ENCODER_NOISE)
    clock.mark(f"draw {poses} poses (inverse_batch)")
    run_study(hexa, data, 0)
    clock.mark("both models' solves, statistics")
    cpu0 = time.process_time()
    result = run_study(hexa, data, None)
    tr = result.traces
    assert tr is not None
    steps = sum(t.iterations for name in ("full", "reduced") for t in tr[name])
    per_step = (time.process_time() - cpu0) / steps
    clock.mark(f"the same + traces: {steps} steps, {1e6 * per_step:.0f} us CPU")
    condition_numbers(hexa, data.readings[:200])
    clock.mark("conditioning table (200 poses)")
    from hexapod_model.plots import reproduce as plots

    clock.mark("import matplotlib (plots.reproduce)")
    pos = np.asarray(result.positions_m) * 1e3
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        plots.error_clouds(out / "a.png", pos, result.errors_cardan, "Cardan-aware")
        clock.mark("figure: error clouds (one of two)")
        plots.histograms(out / "h.png", result.errors_cardan, result.errors_standard)
        clock.mark("figure: histograms")
        plots.convergence(out / "c.png", tr)
        clock.mark("figure: convergence")
        plots.conditioning(out / "k.png", tr["full"], tr["reduced"], tr["rows"])
        clock.mark("figure: conditioning")
    print(load())


def run(cmd: list[str], env: dict) -> tuple[float, float]:
    """Wall time and CPU time (user + sys, the process and its reaped workers) of ``cmd``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {proc.stderr.read().decode()[-500:] if proc.stderr else ''}")
    return time.perf_counter() - t0, usage.ru_utime + usage.ru_stime


def evaluate(runs: int, grid: int) -> None:
    """``hexapod evaluate --workers 1`` and ``--workers 2`` alternately, ``runs`` times each."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    cmd = [sys.executable, "-m", "hexapod_model", "evaluate", "reference", "--grid", str(grid), "--workers"]
    run([*cmd, "1"], env)  # warm the numba cache
    print(load())
    times: dict[str, list[tuple[float, float]]] = {"1": [], "2": []}
    for _ in range(runs):
        for w in times:
            times[w].append(run([*cmd, w], env))
    print(f"  {'workers':10s}{'wall s':>8s}{'CPU s':>8s}   (each run, alternating)")
    for w, rows in times.items():
        for wall, cpu in rows:
            print(f"  {w:10s}{wall:8.2f}{cpu:8.2f}")
    print(load())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("command", nargs="?", choices=("reproduce", "evaluate"), default="reproduce")
    ap.add_argument("--poses", type=int, default=3000, help="reproduce: poses (default 3000)")
    ap.add_argument("--runs", type=int, default=3, help="evaluate: runs per worker count (default 3)")
    ap.add_argument("--grid", type=int, default=21, help="evaluate: --grid (default 21)")
    args = ap.parse_args(argv)
    if args.command == "reproduce":
        reproduce(args.poses)
    else:
        evaluate(args.runs, args.grid)
    return 0


if __name__ == "__main__":
    sys.exit(main())
