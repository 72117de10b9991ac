"""A plan's files: ``plan.json`` (:meth:`Plan.to_json`) and a CSV of its points, written atomically.

The CSV has one row per point: ``t`` (s), ``phase``, ``fixture``, then per joint ``q_NAME``
(rad), ``qd_NAME`` (rad/s), ``qdd_NAME`` (rad/s^2), the flange's ``flange_x .. flange_qw`` (m,
robot base frame), the carried platform's ``platform_x .. platform_qw`` (m, its base frame) and
the legs' ``reading1 .. reading6`` (m); the last two groups are empty outside ``carry``.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

from ..exceptions import InputError
from ..files import atomic_write_text
from .model import Plan

POSE_KEYS = ("x", "y", "z", "qx", "qy", "qz", "qw")


def csv_header(plan: Plan) -> list[str]:
    """The CSV's column names."""
    names = plan.joint_names
    return [
        "t",
        "phase",
        "fixture",
        *(f"q_{n}" for n in names),
        *(f"qd_{n}" for n in names),
        *(f"qdd_{n}" for n in names),
        *(f"flange_{k}" for k in POSE_KEYS),
        *(f"platform_{k}" for k in POSE_KEYS),
        *(f"reading{i}" for i in range(1, 7)),
    ]


def plan_csv(plan: Plan) -> str:
    """The plan's points as CSV text (``repr`` of each float: read back bit for bit)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(csv_header(plan))

    def cells(row) -> list[str]:
        return ["" if math.isnan(v) else repr(float(v)) for v in row]

    for k in range(len(plan.t)):
        w.writerow(
            [
                repr(float(plan.t[k])),
                plan.phase[k],
                plan.fixture[k],
                *cells(plan.q[k]),
                *cells(plan.qd[k]),
                *cells(plan.qdd[k]),
                *cells(plan.flange_in_robot[k]),
                *cells(plan.platform_pose[k]),
                *cells(plan.readings[k]),
            ]
        )
    return out.getvalue()


def write_plan_json(plan: Plan, path: str | Path) -> Path:
    """Write ``plan.json`` (atomically)."""
    return atomic_write_text(path, json.dumps(plan.to_json(), indent=1, allow_nan=False) + "\n")


def write_plan_csv(plan: Plan, path: str | Path) -> Path:
    """Write the plan's CSV (atomically)."""
    return atomic_write_text(path, plan_csv(plan))


def read_plan(path: str | Path) -> Plan:
    """A ``plan.json`` read back.

    Raises:
        InputError: the file cannot be read or is not a plan.
    """
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError("plan", str(path), f"cannot read: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise InputError("plan", str(path), f"not valid JSON: {exc}") from None
    try:
        return Plan.from_json(doc)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError("plan", str(path), f"not a changeover plan: {type(exc).__name__} {exc}") from None
