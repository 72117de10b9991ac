"""Print the solver timing figures for every preset (or the ones named).

    python benchmarks/run_benchmarks.py [PRESET ...] [--samples N] [--json FILE]
"""

from __future__ import annotations

import argparse
import json

from hexapod_model.bench import print_report, run_benchmarks
from hexapod_model.presets import PRESETS


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=list(PRESETS))
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    reports = []
    for name in args.presets:
        reports.append(run_benchmarks(name, samples=args.samples))
        print_report(reports[-1])
        print()
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(reports, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
