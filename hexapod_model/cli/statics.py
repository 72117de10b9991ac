"""``hexapod statics``: leg (brake) forces and Cardan reaction moments of the locked fixture under a wrench."""

from __future__ import annotations

import argparse
import json

import numpy as np

from ..analysis.statics import FRAMES, LegLoads, loads_at, stiffness_of
from ..description.plausibility import check_pose_position
from ..exceptions import InputError
from ..files import atomic_write_text, check_output_path
from ..kinematics.input_checks import check_vector
from ..lie import xyz_rpy_to_pose
from ._common import add_hexapod_argument, add_pose_argument, hexapod_of

DESCRIPTION = """\
Axial force in each leg of the locked fixture (what its brake holds) and the moments its offset
Cardan joints carry, for a wrench on the platform at a pose (docs/statics.md). With a brake
capacity (geometry field brake_capacity, or --brake-capacity) the load margin; with
--leg-stiffness the stiffness of the locked fixture at the pose."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``statics``."""
    p = sub.add_parser(
        "statics", help="leg (brake) forces and Cardan moments under a platform wrench", description=DESCRIPTION
    )
    add_hexapod_argument(p)
    add_pose_argument(p, "platform pose: position (m, base frame) and roll, pitch, yaw (deg) (default: home)")
    p.add_argument(
        "--wrench",
        nargs=6,
        type=float,
        required=True,
        metavar=("FX", "FY", "FZ", "MX", "MY", "MZ"),
        help="force (N) and moment (N m) applied to the platform at --point",
    )
    p.add_argument("--frame", choices=FRAMES, default="platform", help="coordinates of --wrench and --point")
    p.add_argument("--point", nargs=3, type=float, metavar=("PX", "PY", "PZ"), help="where the force acts (m)")
    p.add_argument(
        "--brake-capacity", type=float, metavar="N", help="axial force a brake holds (N); default: the geometry's"
    )
    p.add_argument(
        "--leg-stiffness",
        type=float,
        nargs="+",
        metavar="K",
        help="axial stiffness of the locked legs (N/m): one or six",
    )
    p.add_argument("--json", help="also write the figures as JSON")
    p.set_defaults(func=run)


def format_loads(loads: LegLoads, capacity: float | None) -> str:
    """The table ``hexapod statics`` prints: one line per leg, then the largest force and the margin."""
    F, M = (np.array2string(v, precision=4) for v in (loads.wrench[:3], loads.wrench[3:]))
    lines = [
        f"wrench about the platform origin (base frame): F = {F} N, M = {M} N m",
        f"{'leg':>4s}{'axial N':>13s}{'transverse N':>14s}{'|M platform| N m':>18s}{'|M base| N m':>15s}",
    ]
    for i in range(6):
        lines.append(
            f"{i + 1:4d}{loads.axial_force[i]:13.6g}{loads.transverse_force[i]:14.4g}"
            f"{np.linalg.norm(loads.platform_moment[i]):18.4g}{np.linalg.norm(loads.base_moment[i]):15.4g}"
        )
    lines.append(f"largest |axial force| {loads.largest_axial_force:.6g} N (positive = tension)")
    if capacity is not None:
        m = loads.margin(capacity)
        lines.append(
            f"brake capacity {capacity:.6g} N: load margin {m:.6g} N ({m / capacity:.1%}), "
            + ("the brakes hold" if m >= 0 else "a brake SLIPS")
        )
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """``hexapod statics``."""
    if args.json:
        check_output_path(args.json, args.hexapod)
    capacity = args.brake_capacity
    if capacity is not None and not (np.isfinite(capacity) and capacity > 0):
        raise InputError("--brake-capacity", capacity, "expected a positive force in N")
    k = args.leg_stiffness
    if k is not None and (len(k) not in (1, 6) or not all(np.isfinite(v) and v > 0 for v in k)):
        raise InputError("--leg-stiffness", k, "expected one or six positive stiffnesses in N/m")
    hexa = hexapod_of(args, compiled=False)  # one solve: no numba start-up
    if capacity is None and hexa.geometry is not None:
        capacity = hexa.geometry.brake_capacity
    pose = hexa.home_pose if args.pose is None else xyz_rpy_to_pose(check_vector("--pose", args.pose, 6))
    check_pose_position("--pose", pose, hexa.base_radius)
    sol = hexa.inverse(pose)
    loads = loads_at(hexa, sol.q, args.wrench, args.frame, args.point)
    print(format_loads(loads, capacity))
    report = {
        "hexapod": str(args.hexapod),
        "pose": pose.tolist(),
        "wrench_at_origin_base": loads.wrench.tolist(),
        "axial_force_N": loads.axial_force.tolist(),
        "leg_force_N": loads.leg_force.tolist(),
        "transverse_force_N": loads.transverse_force.tolist(),
        "platform_moment_Nm": loads.platform_moment.tolist(),
        "base_moment_Nm": loads.base_moment.tolist(),
        "largest_axial_force_N": loads.largest_axial_force,
        "brake_capacity_N": capacity,
        "margin_N": loads.margin(capacity) if capacity is not None else None,
    }
    if k is not None:
        stiff = stiffness_of(loads.jacobian, k[0] if len(k) == 1 else k)
        legs = f"{k[0]:.6g} N/m" if len(k) == 1 else "the given stiffnesses"
        print(
            f"locked stiffness with legs of {legs}: "
            f"translational >= {stiff.translational:.6g} N/m, rotational >= {stiff.rotational:.6g} N m/rad"
        )
        report |= {"stiffness": stiff.matrix.tolist(), "translational_N_per_m": stiff.translational}
        report |= {"rotational_Nm_per_rad": stiff.rotational}
    if args.json:
        atomic_write_text(args.json, json.dumps(report, indent=2) + "\n")
    return 0
