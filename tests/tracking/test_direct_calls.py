"""The compiled entries a tracker calls directly get, call after call, the types of the call that chose them.

:func:`hexapod_model.kinematics.newton.entries.direct` hands back the machine code numba compiled
for one call's argument types; that code converts later arguments by those types without
checking them. An array of another layout (a strided row, a Fortran-ordered or read-only one)
would be read as if it had the first's: wrong numbers, no error. So every caller keeps its
arguments' types fixed; here every direct call of a tracker's streams is checked against the
types its entry was chosen for, on streams that take the tracker's other paths too (settling, a
stuck leg, a jump, unreadable samples, a re-anchoring after a gap, a fixture at rest reading
encoder counts).
"""

from __future__ import annotations

import sys
from collections import Counter

import numba
import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import trajectory_poses
from hexapod_model.kinematics.newton import entries
from hexapod_model.studies.track import true_readings
from hexapod_model.tracking.tracker import Tracker, characteristic_length


@pytest.fixture
def checked_direct(monkeypatch):
    """``direct`` replaced in every module of the package by one whose entries check each call's types.

    Returns the calls counted by entry name and the mismatches found, ``(name, got, expected)``.
    """
    real = entries.direct
    calls: Counter[str] = Counter()
    mismatches: list[tuple[str, tuple, tuple]] = []

    def checked(dispatcher, args):
        entry = real(dispatcher, args)
        if entry is dispatcher:  # no machine code chosen: the dispatcher checks its own calls
            return entry
        expected = tuple(numba.typeof(a) for a in args)
        name = dispatcher.py_func.__name__

        def call(*given):
            calls[name] += 1
            got = tuple(numba.typeof(a) for a in given)
            if got != expected:
                mismatches.append((name, got, expected))
            return entry(*given)

        return call

    monkeypatch.setattr(entries, "direct", checked)  # for a module imported from now on
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("hexapod_model") and getattr(module, "direct", None) is real:
            monkeypatch.setattr(module, "direct", checked)
    return calls, mismatches


def test_every_direct_call_of_a_tracker_gets_the_types_its_entry_was_compiled_for(checked_direct):
    calls, mismatches = checked_direct
    hexa = hm.Hexapod.from_preset("reference")  # a new one: its solvers choose their entries under the check
    length = characteristic_length(hexa)
    _, poses = trajectory_poses("B", hexa.home_pose, length / 50.0, 1000.0, 4.0)
    readings = true_readings(hexa, poses[:400])[0] + np.random.default_rng(3).normal(0.0, 2e-6, (400, 6))
    readings[120:150, 2] = readings[119, 2]  # a stuck leg
    readings[200, 4] += 2e-3  # a jump
    readings[260] = np.nan  # an unreadable sample
    readings[300:312] = np.nan  # a gap longer than max_gap: the next sample re-anchors
    tracker = Tracker(hexa, initial=hexa.inverse(poses[0], check=False), noise=2e-6)
    results = [tracker.step(row) for row in readings]
    flags = {f for r in results for f in r.flags} | {r.status for r in results}
    assert {"settling", "stuck", "jump", "invalid_input"} <= flags  # the stream took those paths
    # a fixture at rest reading 1 um encoder counts: its legs repeat counts (the stuck test runs)
    at_rest = Tracker(hexa, initial=hexa.inverse(poses[0], check=False), noise=1e-6, resolution=1e-6)
    counts = np.round((readings[0] + np.random.default_rng(4).normal(0.0, 1e-6, (300, 6))) / 1e-6) * 1e-6
    assert all(r.status == "ok" for r in [at_rest.step(row) for row in counts][-50:])
    assert not mismatches, mismatches[:3]
    # the entries a stream calls directly, each many times
    assert {"begin_sample", "push_trusted", "stuck_checks", "predict_into", "measure_solved"} <= set(calls)
    assert min(calls[name] for name in ("begin_sample", "push_trusted", "predict_into")) >= 300
