"""A tracker step holds the interpreter lock throughout: another thread of the process cannot slow it.

NumPy's ``ndarray.dot`` hands even a product of six numbers to BLAS and releases the interpreter
lock around it. With another thread of the process waiting for the lock (a service's HTTP, store
or feeder thread), each such release wakes it, and on a machine of several cores the step then
costs a fifth to a half more. The step makes no such call: this test fails if one comes back
(a step that released it three times failed it in every run: :mod:`tests.lock_watch`).
"""

from __future__ import annotations

import numpy as np

import hexapod_model as hm
from hexapod_model.tracking.tracker import Tracker

from ..lock_watch import LockWatch


def _readings(hexa: hm.Hexapod, n: int) -> np.ndarray:
    """A smooth walk of ``n`` samples away from home (m): every sample checked, trusted and solved warm."""
    T = hexa.home_pose.copy()
    out = []
    for k in range(n):
        T[:3, 3] = hexa.home_pose[:3, 3] + np.array([1e-4, -5e-5, 3e-5]) * k
        out.append(hexa.inverse(T).lengths)
    return np.array(out)


def test_a_tracker_step_never_releases_the_interpreter_lock():
    hexa = hm.Hexapod.from_preset("reference")
    readings = _readings(hexa, 140)
    tracker = Tracker(hexa)
    for k in range(40):  # warm: kernels loaded, the motion model and the branch check in use
        tracker.step(readings[k])
    with LockWatch() as watch:
        results = [tracker.step(readings[k]) for k in range(40, 140)]  # ~15 ms in all
        ran = watch.ran
    assert all(r.ok and np.isfinite(r.innovation) for r in results)  # checked against the motion model
    assert ran == 0, f"another thread ran {ran} times during the steps: a step released the lock"
