"""What the changeover costs (not a test: figures are printed).

python benchmarks/changeover.py [--repeat N]

Per call, best of 5 runs of ``--repeat`` calls (reference hexapod, the docs' hold pose):

* setting a target: JSON validation and the target's inverse kinematics;
* the guidance of one fixture from its latest record (deviation, six leg changes, in_tolerance);
* a record's ``pose_in_robot`` (the cycle's extra work per reading set with ``[fixtures.cell]``),
  with the coupling at the platform origin and 70 mm above it (its own sigma, reused within
  0.5 mm and 0.05 deg), and the recomputation of that sigma when the plate has moved;
* the dashboard's event for two fixtures (what ``GET /events`` serialises four times a second).
"""

from __future__ import annotations

import argparse
import json
import time

from hexapod_model import Hexapod
from hexapod_model.service.config.cell import Cell, InRobot, placement
from hexapod_model.service.cycle.solver import PoseSolver
from hexapod_model.service.record.pose import pose_record
from hexapod_model.service.record.pose_record import PoseRecord
from hexapod_model.service.targets.guidance import guidance
from hexapod_model.service.targets.target import target_from_json

HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]
BODY = {
    "pose": dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), [HOLD[0], HOLD[1], HOLD[2] + 0.002, *HOLD[3:]])),
    "tolerance": {"translation_mm": 0.1, "rotation_deg": 0.05},
}


def per_call(fn, repeat: int) -> float:
    """Best of 5 runs: microseconds per call of ``fn()``."""
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(repeat):
            fn()
        best = min(best, (time.perf_counter() - t0) / repeat)
    return best * 1e6


def main() -> None:
    """Print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2000, help="calls per run (default 2000)")
    args = parser.parse_args()
    hexa = Hexapod.from_preset("reference")
    pose = placement(HOLD)
    sol = hexa.inverse(pose)
    solver = PoseSolver(hexa, 10e-6)
    u = solver.uncertainty(sol.q)
    sigma = {"translation_mm": u.translation * 1e3, "rotation_deg": u.rotation * 57.29577951308232}
    values = pose_record(pose)
    record = PoseRecord(
        "right", 1.0, sol.lengths.tolist(), values, "ok", [], 0, "locked", True, sigma, 1.0, None, None, pose
    )
    target = target_from_json(BODY, "right", hexa, "bench", 0.0)
    base = placement([0.8, 0.0, 0.0, 0.0, 0.0, 180.0])
    plain = InRobot(Cell(base, placement([0.0] * 6)), 10e-6, solver.propagation)
    coupled = InRobot(Cell(base, placement([0.0, 0.0, 0.07, 180.0, 0.0, 0.0])), 10e-6, solver.propagation)
    coupled.record(pose, sol.q, sigma)
    n = args.repeat
    rows = [
        (
            "set a target (validation + inverse kinematics)",
            per_call(lambda: target_from_json(BODY, "right", hexa, "b", 0.0), n // 10),
        ),
        ("guidance of one fixture", per_call(lambda: guidance(record, target), n)),
        ("pose_in_robot, coupling at the platform origin", per_call(lambda: plain.record(pose, sol.q, sigma), n)),
        ("pose_in_robot, coupling 70 mm above (sigma reused)", per_call(lambda: coupled.record(pose, sol.q, sigma), n)),
        ("  its sigma recomputed (the plate moved > 0.5 mm)", per_call(lambda: solver.propagation(sol.q), n // 10)),
        (
            "dashboard event, two fixtures (guidance + JSON)",
            per_call(lambda: json.dumps({"fixtures": [guidance(record, target), guidance(record, target)]}), n),
        ),
    ]
    for label, us in rows:
        print(f"{label:55s} {us:8.1f} us")


if __name__ == "__main__":
    main()
