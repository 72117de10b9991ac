"""What planning a changeover costs (not a test: figures are printed).

python benchmarks/changeover_plan.py [--repeat N]

The changeover of docs/examples/fixture.toml's two fixtures (both on the reference hexapod,
placed by their ``[fixtures.cell]``) from home to docs/examples/recipe.toml's targets: the
planning CPU time (``time.process_time``, this process's threads) of the first call (which
loads the UR10 of example-robot-data and its collision meshes) and the best of ``--repeat``
later calls; the target is under 10 s of CPU.
"""

from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path

from hexapod_model import Hexapod
from hexapod_model.lie import rpy_to_matrix, xyz_rpy_to_pose
from hexapod_model.planning import FixtureCell, Move, plan_changeover

ROOT = Path(__file__).resolve().parents[1]


def moves() -> list[Move]:
    """The example cell's two fixtures, from home to the example recipe's targets."""
    import numpy as np

    config = tomllib.loads((ROOT / "docs/examples/fixture.toml").read_text())
    recipe = tomllib.loads((ROOT / "docs/examples/recipe.toml").read_text())["targets"]
    out = []
    for f in config["fixtures"]:
        hexa = Hexapod.load(f["hexapod"])
        p = recipe[f["name"]]["pose"]
        target = np.eye(4)
        target[:3, 3] = p["x"], p["y"], p["z"]
        target[:3, :3] = rpy_to_matrix(*np.radians([p["roll"], p["pitch"], p["yaw"]]))
        cell = FixtureCell(
            f["name"],
            f["hexapod"],
            xyz_rpy_to_pose(f["cell"]["base_in_robot"]),
            xyz_rpy_to_pose(f["cell"]["coupling"]),
            hexa.home_pose,
            target,
        )
        out.append(Move(cell, hexa))
    return out


def main() -> None:
    """Print the planning CPU time."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    work = moves()
    t0 = time.process_time()
    plan = plan_changeover(work)
    first = time.process_time() - t0
    best = float("inf")
    for _ in range(args.repeat):
        t0 = time.process_time()
        plan_changeover(work)
        best = min(best, time.process_time() - t0)
    order = " -> ".join(plan.order)
    print(f"changeover of {len(work)} fixtures ({order}, {plan.total_time:.2f} s, {len(plan.t)} points)")
    print(f"planning CPU: first call {first:.2f} s (loads the UR10), then best of {args.repeat}: {best:.2f} s")
    print("target: under 10 s")


if __name__ == "__main__":
    main()
