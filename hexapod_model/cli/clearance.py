"""``hexapod clearance``: the smallest distance between two bodies of a hexapod at a pose, and its joint cones."""

from __future__ import annotations

import argparse
import json

import numpy as np

from ..files import atomic_write_text, check_output_path
from ..kinematics.cones import check_cones
from ..kinematics.input_checks import check_vector
from ..lie import xyz_rpy_to_pose
from ._common import add_hexapod_argument, add_pose_argument, hexapod_of

DESCRIPTION = """\
The clearance of a pose: the smallest distance between two collision bodies of the hexapod's
URDF (legs as capsules, joint housings, plates), the pair and the nearest points, and each
joint's deflection against its cone (docs/solver.md). Exit code 1 when the pose is in
collision (clearance below the geometry's min_clearance) or a joint lies beyond its cone."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``clearance``."""
    p = sub.add_parser(
        "clearance", help="smallest distance between two bodies at a pose, joint cones", description=DESCRIPTION
    )
    add_hexapod_argument(p)
    add_pose_argument(p, "platform pose: position (m, base frame) and roll, pitch, yaw (deg) (default: home)")
    p.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``hexapod clearance``."""
    if args.json:
        check_output_path(args.json, args.hexapod)
    hexa = hexapod_of(args, compiled=False)  # one solve: no numba start-up
    pose = hexa.home_pose if args.pose is None else xyz_rpy_to_pose(check_vector("--pose", args.pose, 6))
    sol = hexa.inverse(pose, check=False)
    result = hexa.clearance(pose)
    cones = check_cones(hexa.closed_loop, hexa.geometry, sol.q)
    a, b = result.points
    print(result.message())
    print(f"nearest points (base frame, m): {np.array2string(a, precision=6)} {np.array2string(b, precision=6)}")
    print(cones.message())
    if sol.status != "converged":
        print(f"inverse solve: {sol.status}" + (f" ({sol.message})" if sol.message else ""))
    if args.json:
        report = {"hexapod": str(args.hexapod), "pose": pose.tolist(), "inverse_status": sol.status}
        report |= result.to_dict()
        limits = [[float(v) if np.isfinite(v) else None for v in row] for row in cones.limits]  # None: no cone
        report |= {"cone_angles_rad": cones.angles.tolist(), "cone_limits_rad": limits, "cones_within": cones.within}
        atomic_write_text(args.json, json.dumps(report, indent=2) + "\n")
    return 1 if result.collision or not cones.within else 0
