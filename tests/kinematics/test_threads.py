"""One Hexapod shared by threads gives exactly the single-thread results."""

from __future__ import annotations

import sys
import threading

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.jacobian import leg_jacobian
from hexapod_model.analysis.trajectories import box_poses

THREADS = 4


@pytest.fixture
def fast_switching():
    """Switch threads every microsecond (default 5 ms), so that solves interleave mid-iteration."""
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    yield
    sys.setswitchinterval(old)


def _work(hexa: hm.Hexapod, readings: np.ndarray, poses: np.ndarray) -> list[tuple]:
    """Per pose: statuses and arrays of cold and warm direct kinematics, inverse kinematics and
    the leg Jacobian.
    """
    out, prev = [], None
    for lengths, T in zip(readings, poses):
        cold = hexa.forward(lengths, check=False)
        warm = hexa.forward(lengths, guess=prev, check=False)
        prev = warm if warm.converged else None
        ik = hexa.inverse(T, check=False)
        statuses = (cold.status, cold.flags, warm.status, warm.flags, ik.status)
        out.append((statuses, cold.pose, warm.pose, ik.lengths, leg_jacobian(hexa, ik.q)))
    return out


@pytest.mark.parametrize("name", ["reference", "3-6"])
def test_shared_hexapod_in_threads_matches_single_thread(name, fast_switching):
    hexa = hm.Hexapod.from_preset(name)  # fresh: each thread builds its solvers while others solve
    sols = [(T, hexa.inverse(T, check=False)) for T in box_poses(hexa.home_pose, 60, seed=12)]
    poses = [T for T, s in sols if s.converged]  # within the cones and free of collision
    readings = np.array([s.lengths for _, s in sols if s.converged])
    expected = _work(hm.Hexapod.from_preset(name), readings, poses)
    results: list[list] = [[] for _ in range(THREADS)]
    errors: list[str] = []

    def run(k: int) -> None:
        try:
            for _ in range(3):
                results[k].append(_work(hexa, readings, poses))
        except Exception as exc:  # noqa: BLE001 - reported below with the thread number
            errors.append(f"thread {k}: {exc!r}")

    threads = [threading.Thread(target=run, args=(k,)) for k in range(THREADS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for runs in results:
        assert len(runs) == 3
        for got in runs:
            for a, b in zip(got, expected, strict=True):
                assert a[0] == b[0]
                for x, y in zip(a[1:], b[1:], strict=True):
                    np.testing.assert_array_equal(x, y)  # bit-identical, not just close
