"""Peak memory (max RSS) and wall time of ``hexapod fk`` and ``hexapod ik`` against input length.

Each run is a fresh ``python -m hexapod_model`` process on a generated file of leg readings
(a smooth path inside the stroke, so every row converges from the previous one) or of the
poses fk wrote for it; its max RSS comes from ``os.wait4``. Streaming means the figure does
not grow with the number of rows.

    python benchmarks/stream_memory.py [--rows 20000 200000] [--hexapod reference]
        [--pythonpath DIR]   # e.g. an export of another commit, to compare
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def write_readings(path: Path, n: int) -> None:
    """``n`` rows of l1..l6 (m): slow sinusoids of 20 mm amplitude, one period per 20,000 rows."""
    t = np.arange(n)[:, None] * (2 * np.pi / 20000)
    lengths = 0.02 * np.sin(t * np.array([1.0, 1.3, 0.7, 1.1, 0.9, 1.7]) + np.arange(6))
    with path.open("w") as fh:
        fh.write("l1,l2,l3,l4,l5,l6\n")
        for start in range(0, n, 10000):
            np.savetxt(fh, lengths[start : start + 10000], fmt="%.12g", delimiter=",")


def measure(argv: list[str], env: dict, cwd: str) -> tuple[float, float, int]:
    """(seconds, max RSS in MB, exit code) of ``python -m hexapod_model *argv`` run in ``cwd``.

    ``cwd`` must not be a checkout: ``python -m`` imports from the working folder first.
    """
    t0 = time.perf_counter()
    cmd = [sys.executable, "-m", "hexapod_model", *argv]
    proc = subprocess.Popen(cmd, env=env, cwd=cwd, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    return time.perf_counter() - t0, usage.ru_maxrss / 1024.0, proc.returncode


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, nargs="+", default=[20000, 200000])
    parser.add_argument("--hexapod", default="reference")
    parser.add_argument("--pythonpath", help="import hexapod_model from here (default: this checkout)")
    args = parser.parse_args()
    root = Path(args.pythonpath or Path(__file__).resolve().parents[1]).resolve()
    env = dict(os.environ, PYTHONPATH=str(root))
    print(f"hexapod_model from {root}, hexapod {args.hexapod}")
    print(f"{'command':8s}{'rows':>9s}{'seconds':>10s}{'max RSS MB':>12s}{'exit':>6s}")
    with tempfile.TemporaryDirectory(prefix="hexapod_stream_") as tmp:
        for n in args.rows:
            lengths, poses, back = (Path(tmp) / f"{name}_{n}.csv" for name in ("lengths", "poses", "back"))
            write_readings(lengths, n)
            for cmd, src, dst in (("fk", lengths, poses), ("ik", poses, back)):
                seconds, rss, code = measure([cmd, args.hexapod, str(src), "-o", str(dst)], env, tmp)
                print(f"{cmd:8s}{n:9d}{seconds:10.1f}{rss:12.1f}{code:6d}", flush=True)


if __name__ == "__main__":
    main()
