"""The warm solve's hot path and the batch result's columns give what the general code gives them."""

from __future__ import annotations

import threading
from dataclasses import FrozenInstanceError, fields, replace

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.kinematics.newton.outcomes import new_solution
from hexapod_model.kinematics.newton.solver import Solution

FIELDS = [f.name for f in fields(Solution)]


def test_new_solution_is_the_dataclass_built_by_its_init():
    values = (np.eye(4), np.zeros(3), np.ones(6), "converged", 2, 1e-13, np.eye(2), "m", ("near_singular",), (), -1)
    a, b = Solution(*values), new_solution(*values)
    assert type(b) is Solution and list(vars(b)) == FIELDS == list(vars(a))
    assert all(getattr(a, f) is getattr(b, f) for f in FIELDS)
    with pytest.raises(FrozenInstanceError):
        b.status = "singular"  # type: ignore[misc]
    assert replace(b, status="singular").status == "singular" and b.status == "converged"
    assert repr(a) == repr(b)


def _in_new_thread(call):
    """``call()`` on a thread of its own: a thread's first solve takes the general path (it builds its solver)."""
    out: list = []
    t = threading.Thread(target=lambda: out.append(call()))
    t.start()
    t.join()
    return out[0]


def _fields(sol: Solution) -> tuple:
    return tuple(getattr(sol, f) for f in FIELDS)


def _same(a: Solution, b: Solution) -> bool:
    """Every field equal (arrays bit for bit, NaN included): the same compiled solve, packaged twice."""
    for x, y in zip(_fields(a), _fields(b)):
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            if not (isinstance(x, np.ndarray) and isinstance(y, np.ndarray)) or x.dtype != y.dtype:
                return False
            if not np.array_equal(x, y, equal_nan=True):
                return False
        elif isinstance(x, tuple):
            if len(x) != len(y) or not all(np.array_equal(u, v) for u, v in zip(x, y)):
                return False
        elif type(x) is not type(y) or x != y:
            return False
    return True


@pytest.mark.parametrize("name", ["reference", "guideway"])
def test_the_hot_path_gives_the_first_solves_solution(name):
    """After a thread's first solve, ``forward`` takes one compiled call; each answer is the first-solve path's."""
    hexa = hm.Hexapod.from_preset(name)
    # each step proven by its own test: a region proven by the thread's earlier steps, which the new
    # thread has not, would prove the same step with other bounds (docs/solver.md)
    hexa.engine.prover.regions = False
    rng = np.random.default_rng(3)
    lo, hi = hexa.stroke[:, 0], hexa.stroke[:, 1]
    near = hexa.forward(0.2 * lo + 0.2 * hi)
    steps = [near.lengths + 1e-4 * k for k in range(1, 4)]  # 1 kHz-like warm steps
    jumps = list(rng.uniform(lo, hi, (12, 6)))  # far jumps: some fail certified, out of limits, ...
    statuses = set()
    for x, guess in [(x, near) for x in steps] + [(x, None) for x in jumps] + [(x, near) for x in jumps]:
        hot = hexa.forward(x, guess, check=False)
        first = _in_new_thread(lambda x=x, guess=guess: hexa.forward(x, guess, check=False))
        assert _same(hot, first), (x, hot.status, first.status)
        statuses.add(hot.status)
    assert "converged" in statuses and len(statuses) > 1  # the hot path's shortcut and its way out both ran
    assert hexa.engine.local.staged is hexa.engine.solver(hexa.engine.held_forward)  # the hot path ran
    with pytest.raises(hm.LimitError) as hot_error:
        hexa.forward(hi + 0.01, near)
    with pytest.raises(hm.InputError, match="lengths"):
        hexa.forward(np.full(6, np.nan), near)
    fresh = hm.Hexapod.from_preset(name)
    with pytest.raises(hm.LimitError) as first_error:
        fresh.forward(hi + 0.01, near)
    assert str(hot_error.value) == str(first_error.value)


def test_batch_status_column_is_as_wide_as_its_longest_status():
    """``status`` is the string array ``astype(str)`` of the names gives: as wide as the longest name present."""
    hexa = hm.Hexapod.from_preset("reference")
    rng = np.random.default_rng(4)
    rows = rng.uniform(hexa.stroke[:, 0], hexa.stroke[:, 1], (20, 6))
    for batch in (rows[:1], rows, np.vstack([rows, np.full(6, np.nan)])):
        res = hexa.forward_batch(batch)
        expected = np.array(list(res.status), dtype=object).astype(str)
        assert res.status.dtype == expected.dtype and np.array_equal(res.status, expected)
        solved = [hexa.forward(x, check=False).status if np.all(np.isfinite(x)) else "invalid_input" for x in batch]
        assert list(res.status) == solved
    assert hexa.forward_batch(np.empty((0, 6))).status.dtype == np.array([], dtype=object).astype(str).dtype
