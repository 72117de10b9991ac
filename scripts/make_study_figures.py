"""Regenerate the `hexapod reproduce` figures of docs/reproduce.md and the example data file.

    python scripts/make_study_figures.py [--poses 3000]

Writes ``docs/img/reproduce_*.png`` (Bem et al. (2026) Figs. 4-7 re-run on the ``reference`` preset:
3000 poses, seed 0, 10 um encoder noise, exact reference poses) and
``docs/examples/measured.csv`` (40 simulated "measurements": 10 um encoder noise, 0.3 mm / r
reference-pose noise, seed 7) that ``docs/reproduce.md`` uses as the ``--data`` example.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from hexapod_model.cli.main import main as hexapod
from hexapod_model.kinematics.hexapod import Hexapod
from hexapod_model.studies.reproduce import save_measured, simulate

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=3000)
    ap.add_argument("--img", type=Path, default=ROOT / "docs" / "img", help="figure directory")
    ap.add_argument("--examples", type=Path, default=ROOT / "docs" / "examples", help="measured.csv directory")
    args = ap.parse_args(argv)
    data = simulate(Hexapod.from_preset("reference"), 40, seed=7, encoder_noise=10e-6, reference_noise=0.3e-3)
    args.examples.mkdir(parents=True, exist_ok=True)
    print("wrote", save_measured(args.examples / "measured.csv", data))
    return hexapod(
        ["reproduce", "--preset", "reference", "--poses", str(args.poses), "--seed", "0", "--out", str(args.img)]
    )


if __name__ == "__main__":
    raise SystemExit(main())
