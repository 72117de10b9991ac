"""Print the solver timing figures for every preset (or the ones named).

python benchmarks/run_benchmarks.py [PRESET ...] [--samples N] [--json FILE]
"""

from __future__ import annotations

import argparse
import json

from hexapod_model import Hexapod
from hexapod_model.cli.core import format_bench
from hexapod_model.description.presets import PRESETS, get_preset
from hexapod_model.studies.bench import run_benchmarks


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=[n for n in PRESETS if not get_preset(n).redundant])  # six readings
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    reports = []
    for name in args.presets:
        reports.append({"hexapod": name, **run_benchmarks(Hexapod.load(name), samples=args.samples)})
        print(format_bench(reports[-1]))
        print()
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(reports, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
