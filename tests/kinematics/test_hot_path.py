"""The warm solve's hot path and the batch result's columns give what the general code gives them."""

from __future__ import annotations

import threading
from dataclasses import FrozenInstanceError, fields, replace

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.kinematics.newton.iteration import solve_schur
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


def test_new_proof_is_the_dataclass_built_by_its_init():
    from hexapod_model.kinematics.newton.proven import Proof, new_proof

    for values in (
        (True, 3.6e-11, 2.8e-10, 1, 1, False),
        (False, np.inf, np.inf, 3, 0, False),
        (True, 1e-9, 1e-8, 0, 1, True),
    ):
        a, b = Proof(*values), new_proof(*values)
        assert type(b) is Proof and a == b and repr(a) == repr(b)
        assert list(vars(b)) == [f.name for f in fields(Proof)] == list(vars(a))
        with pytest.raises(FrozenInstanceError):
            b.proven = False  # type: ignore[misc]


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


@pytest.mark.parametrize("name", ["reference", "guideway"])
def test_a_configuration_guess_takes_the_hot_path_with_the_first_solves_answer(name, monkeypatch):
    """A configuration array as the guess (a tracker's prediction: not closed, no determinant sign).

    The hot path answers as the thread's first solve does, bit for bit; a bad array is the same
    one-line input error on both paths, and a reading outside its stroke is named first on both.
    """
    hexa = hm.Hexapod.from_preset(name)
    hexa.engine.prover.regions = False  # each step proven by its own test (see above)
    rng = np.random.default_rng(5)
    lo, hi = hexa.stroke[:, 0], hexa.stroke[:, 1]
    near = hexa.forward(0.2 * lo + 0.2 * hi)
    predicted = [near.q.copy()]
    for k in range(3):  # off the closure: joints moved 0.1-0.3 mm / mrad, as a prediction is
        q = near.q.copy()
        legs = np.setdiff1d(np.arange(q.size), np.arange(hexa.closed_loop.platform_q, hexa.closed_loop.platform_q + 7))
        q[legs] += rng.normal(0.0, 1e-4 * (k + 1), legs.size)
        predicted.append(q)
    steps = [near.lengths + 1e-4 * k for k in range(1, 4)]
    jumps = list(rng.uniform(lo, hi, (6, 6)))
    statuses = set()
    hexa.forward(steps[0], near, check=False)  # this thread takes the hot path from here on
    for x in steps + jumps:
        for guess in predicted:
            hot = hexa.forward(x, guess, check=False)
            first = _in_new_thread(lambda x=x, guess=guess: hexa.forward(x, guess, check=False))
            assert _same(hot, first), (x, hot.status, first.status)
            assert hot.det_sign == first.det_sign
            statuses.add(hot.status)
    assert "converged" in statuses and len(statuses) > 1
    general = []  # calls of the general path on this thread
    engine_forward = hexa.engine.forward
    monkeypatch.setattr(hexa.engine, "forward", lambda *a: general.append(a) or engine_forward(*a))
    assert all(hexa.forward(x, p, check=False).proof.proven for x in steps for p in predicted)
    assert general == []  # every one a warm step on the hot path
    monkeypatch.undo()
    bad = near.q.copy()
    bad[hexa.closed_loop.platform_q + 3] += 0.5  # not a unit quaternion
    for guess in (bad, np.full(near.q.size, np.nan), near.q[:-1].copy()):
        with pytest.raises(hm.InputError, match="guess") as hot_error:
            hexa.forward(steps[0], guess)
        first_error = _in_new_thread(lambda guess=guess: _raised(lambda: hexa.forward(steps[0], guess)))
        assert str(hot_error.value) == str(first_error)
    for guess in (predicted[1].astype(np.float32), predicted[1].astype(object), predicted[1][::-1][::-1]):
        hot = hexa.forward(steps[0], guess, check=False)  # another dtype or layout: checked and copied as before
        assert _same(hot, _in_new_thread(lambda guess=guess: hexa.forward(steps[0], guess, check=False)))
    kept = predicted[1].copy()
    hot = hexa.forward(steps[0], predicted[1])
    assert np.array_equal(predicted[1], kept) and not np.shares_memory(hot.q, predicted[1])  # the guess is not written
    with pytest.raises(hm.LimitError):
        hexa.forward(hi + 0.01, bad)  # the stroke is checked before the guess, as on the first solve
    assert isinstance(_in_new_thread(lambda: _raised(lambda: hexa.forward(hi + 0.01, bad))), hm.LimitError)


def _raised(call) -> Exception | None:
    try:
        call()
    except Exception as exc:  # noqa: BLE001 - returned for the test to compare
        return exc
    return None


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


def test_the_compiled_start_check_takes_what_check_configuration_takes():
    """:func:`valid_start` against :func:`check_configuration` at the edges of its rule (finite, unit quaternion)."""
    from hexapod_model.kinematics.input_checks import POSE_TOLERANCE, check_configuration
    from hexapod_model.kinematics.newton.compiled import valid_start

    hexa = hm.Hexapod.from_preset("reference")
    i = hexa.closed_loop.platform_q
    q0 = hexa.q_home.copy()
    cases = []
    for change in (0.0, 0.5, -0.5, 0.9 * POSE_TOLERANCE, 1.1 * POSE_TOLERANCE, -1.1 * POSE_TOLERANCE):
        q = q0.copy()
        q[i + 3 : i + 7] *= 1.0 + change  # the quaternion's norm 1 + change
        cases.append(q)
    for k, value in ((0, np.nan), (i + 6, np.inf), (q0.size - 1, -np.inf), (0, 1e200)):  # 1e200: finite, |q| overflows
        q = q0.copy()
        q[k] = value
        cases.append(q)
    verdicts = []
    for q in cases:
        try:
            check_configuration("guess", q, q.size, i)
            taken = True
        except hm.InputError:
            taken = False
        assert valid_start(q, i, POSE_TOLERANCE) == taken, q
        verdicts.append(taken)
    assert verdicts.count(True) == 3 and verdicts.count(False) == 7


def test_a_finite_guess_of_huge_entries_is_checked_without_a_warning():
    """A guess entry of 1e200 is finite: taken or not by the quaternion rule alone; no overflow warning escapes."""
    import warnings

    from hexapod_model.kinematics.input_checks import check_configuration

    hexa = hm.Hexapod.from_preset("reference")
    i = hexa.closed_loop.platform_q
    q = hexa.q_home.copy()
    q[0] = 1e200
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning would raise here
        assert np.array_equal(check_configuration("guess", q, q.size, i), q)
        q[i + 3] = 1e200  # the quaternion is not of norm 1: the one-line error with its norm, no warning
        with pytest.raises(hm.InputError, match=r"has norm 1e\+200"):
            check_configuration("guess", q, q.size, i)


def test_the_compiled_copy_keeps_the_interpreter_lock():
    """``kernels.copied`` (the certificate's copy of the reduced Jacobian) never lets another thread in."""
    from hexapod_model.kinematics.newton.kernels import copied

    from ..lock_watch import LockWatch

    G = np.random.default_rng(0).normal(size=(36, 42))  # the presets' reduced Jacobian
    copied(G)  # compiled (or loaded) before the watch
    with LockWatch() as watch:
        copies = [copied(G) for _ in range(200)]
        ran = watch.ran
    assert ran == 0 and all(np.array_equal(c, G) for c in copies)


def test_strided_readings_take_the_hot_path_by_its_one_compiled_signature():
    """Readings in a column of a 2-D array: the same answer, and no second compiled solve (seconds, unannounced)."""
    hexa = hm.Hexapod.from_preset("reference")
    hexa.engine.prover.regions = False  # each step proven by its own test
    near = hexa.forward(np.full(6, 0.01))
    x = near.lengths + 1e-4
    want = hexa.forward(x, near)  # the thread's warm path is set up
    before = len(solve_schur.signatures)
    columns = np.stack([x, x], axis=1)  # (6, 2): each column a strided view
    assert not columns[:, 0].flags.c_contiguous
    got = hexa.forward(columns[:, 0], near)
    assert len(solve_schur.signatures) == before
    assert _same(got, want)
    with pytest.raises(hm.LimitError):
        hexa.forward(np.stack([x + 1.0, x], axis=1)[:, 0], near)  # the stroke checked on the strided readings too


def _read_only(a: np.ndarray) -> np.ndarray:
    b = np.array(a)
    b.setflags(write=False)  # as pandas' copy-on-write to_numpy() or np.load(..., mmap_mode="r") give them
    return b


def test_read_only_arrays_take_the_hot_paths_by_their_one_compiled_signature():
    """Read-only readings, guess and configurations: the same answers, no second compiled solve or proof.

    numba types a read-only array apart: each entry would compile again, unannounced (the solve
    seconds, the proof half a minute).
    """
    from hexapod_model.kinematics.newton.proof_kernel import prove_packed

    hexa = hm.Hexapod.from_preset("reference")
    hexa.engine.prover.regions = False  # each step proven by its own test
    near = hexa.forward(np.full(6, 0.01))
    x = near.lengths + 1e-4
    want = hexa.forward(x, near)  # the warm path and the proof compiled (or loaded)
    before = len(solve_schur.signatures), len(prove_packed.signatures)
    got = hexa.forward(_read_only(x), near)
    assert _same(got, want)
    guess = replace(near, q=_read_only(near.q))
    assert _same(hexa.forward(x, guess), want)
    cold = hexa.forward(_read_only(np.full(6, 0.01)))
    assert _same(cold, near)
    prover = hexa.engine.prover
    assert prover.prove(_read_only(near.q), _read_only(want.q)) == prover.prove(near.q, want.q)
    assert (len(solve_schur.signatures), len(prove_packed.signatures)) == before


def _signatures() -> dict[str, int]:
    """The compiled signatures of every numba entry the package has imported, by module and name."""
    import sys

    from numba.core.registry import CPUDispatcher

    out = {}
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("hexapod_model."):
            for name, value in list(vars(module).items()):
                if isinstance(value, CPUDispatcher):
                    out[f"{module.__name__}.{name}"] = len(value.signatures)
    return out


def test_read_only_inputs_of_the_public_calls_compile_nothing_more():
    """Each public call, with read-only inputs after writeable ones: the same answer, no entry compiled again."""
    from hexapod_model.tracking.tracker import Tracker

    hexa = hm.Hexapod.from_preset("reference")
    x = np.full(6, 0.01)
    near = hexa.forward(x)
    rows = np.array([x, x + 1e-4, x + 2e-4])

    def track(c):
        tracker = Tracker(hexa)
        return [tracker.step(c(x + k * 1e-5)).solution.q for k in range(12)][-1]

    calls = {
        "forward": lambda c: hexa.forward(c(x + 1e-4), near).q,
        "forward from a configuration": lambda c: hexa.forward(c(x + 1e-4), c(near.q)).q,
        "inverse": lambda c: hexa.inverse(c(near.pose)).q,
        "inverse from a configuration": lambda c: hexa.inverse(c(near.pose), c(near.q)).q,
        "forward_batch": lambda c: hexa.forward_batch(c(rows)).q,
        "forward_batch warm": lambda c: hexa.forward_batch(c(rows), warm=True).q,
        "inverse_batch": lambda c: hexa.inverse_batch(c(np.array([near.pose, near.pose]))).q,
        "clearance": lambda c: hexa.clearance(c(near.q)).distance,
        "tracker": track,
    }
    for name, call in calls.items():
        want = call(np.array)  # compiles (or loads) what the call runs
        before = _signatures()
        got = call(_read_only)
        assert np.array_equal(got, want), name
        assert _signatures() == before, name
