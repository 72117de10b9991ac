"""A tracker step holds the interpreter lock throughout: another thread of the process cannot slow it.

NumPy's ``ndarray.dot`` hands even a product of six numbers to BLAS and releases the interpreter
lock around it. With another thread of the process waiting for the lock (a service's HTTP, store
or feeder thread), each such release wakes it, and on a machine of several cores the step then
costs a fifth to a half more. The step makes no such call: this test fails if one comes back.

A release lets the waiting thread in only when it takes the lock before this thread takes it
back, so the test runs a hundred steps: a step that released it three times failed the test in
every run.
"""

from __future__ import annotations

import sys
import threading

import numpy as np

import hexapod_model as hm
from hexapod_model.tracking.tracker import Tracker

SWITCH = 2.0  # s: the interpreter takes the lock from a thread only after this long (the test's own setting)


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
    spins, ready, stop = [0], threading.Event(), threading.Event()

    def spinner() -> None:  # runs only while it holds the lock: the count moves only then
        ready.set()
        while not stop.is_set():
            spins[0] += 1

    old = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH)
    other = threading.Thread(target=spinner, daemon=True)
    try:
        other.start()
        ready.wait()  # this thread holds the lock again from here, the spinner waits for it
        before = spins[0]
        results = [tracker.step(readings[k]) for k in range(40, 140)]  # ~15 ms in all
        after = spins[0]
    finally:
        stop.set()
        sys.setswitchinterval(old)
        other.join()
    assert all(r.ok and np.isfinite(r.innovation) for r in results)  # checked against the motion model
    assert after == before, f"the spinner ran {after - before} times during the steps: a step released the lock"
