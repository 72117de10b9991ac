"""Start-up cost of a ``hexapod`` process against ``python -c "import pinocchio, numpy"``.

Runs the two commands alternately in fresh processes and prints, per command, the median wall
time, CPU time (user + sys, from ``os.wait4``) and the largest peak RSS; ``--cold`` also runs
the command once with an empty numba cache (a temporary ``NUMBA_CACHE_DIR``: the first run after
installation, compiling every kernel it calls).

    python benchmarks/startup.py [--runs 7] [--cold] [-- hexapod fk reference docs/examples/lengths.csv]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASELINE = [sys.executable, "-c", "import pinocchio, numpy"]
COMMAND = [sys.executable, "-m", "hexapod_model", "fk", "reference", str(ROOT / "docs/examples/lengths.csv")]


def run(cmd: list[str], env: dict | None = None) -> tuple[float, float, float]:
    """Wall time (s), CPU time (s) and peak RSS (MB) of one run of ``cmd``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {proc.stderr.read().decode()[-500:] if proc.stderr else ''}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def median(values: list[float]) -> float:
    s = sorted(values)
    return s[len(s) // 2]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--cold", action="store_true", help="also time a first run with an empty numba cache")
    ap.add_argument("command", nargs="*", help="the command to time (default: hexapod fk reference lengths.csv)")
    args = ap.parse_args(argv)
    command = args.command or COMMAND
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    run(command, env)  # the numba cache is warm from here on
    results: dict[str, list[tuple[float, float, float]]] = {"baseline": [], "command": []}
    for _ in range(args.runs):  # alternate: the machine's load affects both alike
        results["baseline"].append(run(BASELINE, env))
        results["command"].append(run(command, env))
    base = [median([r[i] for r in results["baseline"]]) for i in range(2)]
    print(f"{'':34s}{'wall s':>9s}{'CPU s':>9s}{'peak MB':>9s}   (median of {args.runs}, alternating)")
    for name, label in (("baseline", "python -c 'import pinocchio, numpy'"), ("command", " ".join(command[2:]))):
        wall, cpu = (median([r[i] for r in results[name]]) for i in range(2))
        rss = max(r[2] for r in results[name])
        print(f"{label[:33]:34s}{wall:9.3f}{cpu:9.3f}{rss:9.0f}   x{wall / base[0]:.2f} wall, x{cpu / base[1]:.2f} CPU")
    if args.cold:
        cache = tempfile.mkdtemp(prefix="numba-cold-")
        try:
            wall, cpu, rss = run(command, dict(env, NUMBA_CACHE_DIR=cache))
        finally:
            shutil.rmtree(cache, ignore_errors=True)
        print(f"{'first run, empty numba cache':34s}{wall:9.3f}{cpu:9.3f}{rss:9.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
