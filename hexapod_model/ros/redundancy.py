"""A redundant fixture's consistency test as ``/diagnostics`` values (no DDS import).

A fixture whose hexapod has redundant sensors (a measuring leg ``leg7``, an inclinometer's
``tilt_x``, ``tilt_y``: ``docs/redundancy.md``) solves every reading of a set to their weighted
least-squares pose and tests the residual: ``chi2 = sum ((z_j - h_j(pose)) / sigma_j)^2``
against ``chi2.ppf(1 - alpha, m - 6)``. A set that fails is ``inconsistent_readings`` (never
``ok``), flagged ``isolated:NAME`` when the data name the faulty reading, else ``suspects:N``.
:func:`consistency_values` turns what a record carries of it (its status and flags, the test's
statistic and bound, the extra readings' values) and what the fixture's hexapod fixes (the
readings, the degrees of freedom, the rate ``alpha`` the service tests at and its bound) into
diagnostic key-values; a fixture of six legs gets none, so its diagnostics stay as they are.
"""

from __future__ import annotations

import json

from ..kinematics.consistency import DEFAULT_ALPHA, threshold
from ..service.record.pose_record import PoseRecord
from .names import FixtureNames

INCONSISTENT = "inconsistent_readings"
#: the false-alarm rate the service's consistency test runs at (its solves take the default)
ALPHA = DEFAULT_ALPHA


def consistency_values(rec: PoseRecord, names: FixtureNames) -> dict[str, str]:
    """The consistency test of a redundant fixture's record as diagnostic values; empty for six readings.

    Keys (values as text):

    * ``consistency``: ``passed`` (a pose solved from every reading, the test passed),
      ``failed`` (``inconsistent_readings``), or empty (no set solved: a faulty, incomplete or
      unsolved set; ``no_data``);
    * ``consistency_isolated``: the reading the data name as faulty (``leg3``, ``tilt_x``), else empty;
    * ``consistency_suspects``: how many readings' exclusion restores consistency when none is
      named (``suspects:N``), else empty;
    * ``consistency_readings``: the readings the test weighs, in their order (JSON list);
    * ``consistency_dof``: its degrees of freedom, readings minus 6;
    * ``consistency_false_alarm_rate``: ``alpha``, the rate at which clean readings fail it;
    * ``consistency_chi2_bound``: the bound on ``chi2``, ``chi2.ppf(1 - alpha, dof)``;
    * ``consistency_chi2``: the set's statistic (the record's ``consistency``), empty when no
      redundant solve ran;
    * ``reading_NAME_m`` / ``reading_NAME_rad``: each extra reading (``reading_leg7_m``,
      ``reading_tilt_x_rad``), empty without a fresh frame.

    Args:
        rec: a record of the fixture.
        names: the fixture's names (its readings).
    """
    if not names.redundant:
        return {}
    flags = rec.flags
    if rec.status == INCONSISTENT or INCONSISTENT in flags:
        verdict = "failed"
    elif rec.pose is not None:
        verdict = "passed"
    else:
        verdict = ""
    dof = len(names.readings) - 6
    test = rec.consistency
    extra = rec.extra_readings or {}
    readings = {}
    for name in names.readings[6:]:
        value = extra.get(name)
        unit = "rad" if name.startswith("tilt") else "m"
        readings[f"reading_{name}_{unit}"] = "" if value is None else repr(float(value))
    return {
        "consistency": verdict,
        "consistency_chi2": "" if test is None else repr(float(test["chi2"])),
        "consistency_isolated": _flag_value(flags, "isolated:"),
        "consistency_suspects": _flag_value(flags, "suspects:"),
        "consistency_readings": json.dumps(list(names.readings)),
        "consistency_dof": str(dof),
        "consistency_false_alarm_rate": repr(ALPHA),
        "consistency_chi2_bound": repr(threshold(ALPHA, dof) if test is None else float(test["bound"])),
        **readings,
    }


def _flag_value(flags: list[str], prefix: str) -> str:
    """The text after ``prefix`` of the first flag that starts with it, else empty."""
    return next((f[len(prefix) :] for f in flags if f.startswith(prefix)), "")
