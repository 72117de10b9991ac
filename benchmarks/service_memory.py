"""Peak memory (max RSS) of the fixture pose service with 1 and with N fixtures, and per extra fixture.

python benchmarks/service_memory.py [--fixtures 1,20,50] [--sets 300]

Each figure is a fresh process: it builds a configuration of N fixtures, each naming the
``reference`` hexapod as ``hexapod serve`` reads it (the service loads the hexapods itself),
starts the service (cycle thread, store writer, HTTP on 127.0.0.1:0), plays ``--sets`` reading
sets per fixture (trajectory A, frames put straight into the virtual bus's receiving queue),
stops it and reports its max RSS (``getrusage``) and its RSS before the service was built (the
imports and the kernels). The cost per extra fixture is the slope between the smallest and the
largest N. Warm numba caches assumed (run the service once first).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def rss_mb() -> float:
    """Resident set size now (MB), from /proc."""
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def child(fixtures: int, sets: int) -> dict:
    """Run the service with ``fixtures`` fixtures in this process; its memory figures."""
    import can

    from hexapod_model import Hexapod
    from hexapod_model.service import FixtureService

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from service import make_config, readings_sequence  # this folder's throughput benchmark

    hexa = Hexapod.from_preset("reference")
    readings = readings_sequence(hexa)[:sets]
    hexa.forward(readings[0])  # kernels loaded: not a fixture's cost
    before = rss_mb()
    with tempfile.TemporaryDirectory() as tmp:
        channel, config = make_config(fixtures, Path(tmp))
        bus = can.Bus(interface="virtual", channel=channel)
        service = FixtureService(config, bus=bus)
        count = [0]
        service.subscribe(lambda rec: count.__setitem__(0, count[0] + 1))
        service.start()
        try:
            wall = time.time()
            for k, row in enumerate(readings):
                for f in config.fixtures:
                    for j, leg in enumerate(f.legs):
                        m = leg.message(float(row[j]))
                        m.timestamp = wall + k / 100.0 + j * 130e-6
                        bus.queue.put(m)
            end = time.monotonic() + 120.0
            while count[0] < 0.99 * sets * fixtures and time.monotonic() < end:
                time.sleep(0.05)
            running = rss_mb()
        finally:
            service.stop()
            bus.shutdown()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return {
        "fixtures": fixtures,
        "records": count[0],
        "rss_before_mb": before,
        "rss_running_mb": running,
        "peak_mb": peak,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fixtures", default="1,20", help="fixture counts, one process each")
    ap.add_argument("--sets", type=int, default=300, help="reading sets per fixture")
    ap.add_argument("--json", help="also write the figures as JSON")
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(args.child, args.sets)))
        return 0
    runs = []
    for n in (int(v) for v in args.fixtures.split(",") if v):
        out = subprocess.run(
            [sys.executable, __file__, "--child", str(n), "--sets", str(args.sets)],
            capture_output=True,
            text=True,
            check=True,
        )
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
        r = runs[-1]
        print(
            f"{n:3d} fixture(s)  peak RSS {r['peak_mb']:6.1f} MB  running {r['rss_running_mb']:6.1f} MB  "
            f"before the service {r['rss_before_mb']:6.1f} MB  records {r['records']}",
            flush=True,
        )
    if len(runs) > 1:
        lo, hi = runs[0], runs[-1]
        per = (hi["peak_mb"] - lo["peak_mb"]) / (hi["fixtures"] - lo["fixtures"])
        print(f"peak RSS per extra fixture: {per:.2f} MB ({lo['fixtures']} -> {hi['fixtures']} fixtures)")
    if args.json:
        Path(args.json).write_text(json.dumps(runs, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
