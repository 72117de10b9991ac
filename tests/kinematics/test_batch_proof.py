"""A batch's warm rows carry the Krawczyk proof of their step, as ``forward`` gives it (docs/solver.md)."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.kinematics.batch import PROOF_STEP
from hexapod_model.kinematics.newton.proven import Proof


def _walk(hexa: hm.Hexapod, n: int, seed: int) -> np.ndarray:
    """``n`` readings 0.1-0.3 mm apart about a pose off home (a time series, as ``hexapod fk`` reads)."""
    rng = np.random.default_rng(seed)
    T = hexa.home_pose.copy()
    T[:3, 3] += [0.01, -0.005, 0.004]
    start = hexa.inverse(T).lengths
    return start + np.cumsum(rng.uniform(-2e-4, 2e-4, (n, 6)), axis=0)


def _forward_rows(hexa: hm.Hexapod, rows: np.ndarray, guess) -> list[hm.Solution]:
    out = []
    for x in rows:
        sol = hexa.forward(x, guess, check=False)
        out.append(sol)
        if sol.converged:
            guess = sol
    return out


def _fail_proof_of_row(hexa: hm.Hexapod, rows: np.ndarray, bad: int, monkeypatch) -> None:
    """Make the prover fail on the step that ends at warm row ``bad``'s answer (every other step as before)."""
    target = hexa.forward_batch(rows, warm=True, prove=False).q[bad].copy()
    prover = hexa.engine.prover
    prove = prover.prove

    def failing(q0, q1, *args, **kwargs):
        if np.allclose(q1, target, rtol=0, atol=1e-9):
            return Proof(False, np.inf, np.inf, 1, 0)
        return prove(q0, q1, *args, **kwargs)

    monkeypatch.setattr(prover, "prove", failing)


@pytest.mark.parametrize("name", ["reference", "guideway"])
def test_warm_rows_carry_the_proof_forward_gives_them(name):
    hexa = hm.Hexapod.from_preset(name)
    hexa.engine.prover.regions = False  # each step by its own test: the same bounds row by row and in the batch
    rows = _walk(hexa, 40, seed=1)
    res = hexa.forward_batch(rows, warm=True)
    expected = _forward_rows(hexa, rows, None)
    assert list(res.status) == [s.status for s in expected] and res.converged.all()
    assert res.proofs[0] is None and expected[0].proof is None  # from home: the certificate's checks
    for k in range(1, len(rows)):
        got, want = res.proofs[k], expected[k].proof
        assert got is not None and got.proven and want is not None and want.proven, k
        assert got.position_m <= 1e-9 and got.rotation_rad <= 1e-8  # the exact pose lies this close (m, rad)
        assert res.solution(k).proof is got
    # a pose the proof bounds: the rows' own exact solutions (Newton at a tolerance far below the bound)
    exact = [hexa.forward(rows[k], expected[k], tol=1e-14, prove=False).pose for k in (1, 20, 39)]
    for k, T in zip((1, 20, 39), exact):
        assert np.linalg.norm(res.poses[k][:3, 3] - T[:3, 3]) <= res.proofs[k].position_m
    unproven = hexa.forward_batch(rows, warm=True, prove=False)
    assert all(p is None for p in unproven.proofs) and list(unproven.status) == list(res.status)


def test_rows_from_a_guess_are_proven_and_a_long_step_keeps_the_certificate():
    hexa = hm.Hexapod.from_preset("reference")
    rows = _walk(hexa, 12, seed=2)
    guess = hexa.forward(rows[0] - 1e-4)
    res = hexa.forward_batch(rows[:6], guess)  # every row from the guess: 0.1-1 mm steps
    assert all(p is not None and p.proven for p in res.proofs)
    poses = np.repeat(hexa.home_pose[None], 4, axis=0)
    poses[:, 0, 3] += np.array([0.0, 0.01, 0.02, 0.03])  # rows of poses 1 cm apart
    far = hexa.inverse_batch(poses).lengths
    steps = np.abs(np.diff(far, axis=0)).max(axis=1)
    assert (steps > PROOF_STEP).all()
    res = hexa.forward_batch(far, warm=True)
    assert res.converged.all() and all(p is None for p in res.proofs)  # the certificate's checks, as before


def test_a_warm_row_not_proven_is_uncertified_and_the_next_rows_start_before_it(monkeypatch):
    """A row whose proof fails is ``uncertified`` and no start: the rows after it are solved from the row before."""
    hexa = hm.Hexapod.from_preset("reference")
    hexa.engine.prover.regions = False
    rows = _walk(hexa, 10, seed=3)
    bad = 4
    _fail_proof_of_row(hexa, rows, bad, monkeypatch)
    res = hexa.forward_batch(rows, warm=True)
    expected = _forward_rows(hexa, rows, None)
    assert expected[bad].status == "uncertified" and "Krawczyk" in expected[bad].message
    assert list(res.status) == [s.status for s in expected]
    assert res.messages[bad] == expected[bad].message
    for k in range(len(rows)):
        np.testing.assert_allclose(res.q[k], expected[k].q, rtol=0, atol=1e-9)
        assert (res.proofs[k] is None) == (expected[k].proof is None), k
    # the row after the failed one started from the row before it, as forward's would
    assert res.iterations[bad + 1] == expected[bad + 1].iterations


def test_a_long_step_after_a_row_not_proven_keeps_the_certificate(monkeypatch):
    """The rows solved again after a failed proof follow the batch's rule: a step over PROOF_STEP is not proven."""
    hexa = hm.Hexapod.from_preset("reference")
    rows = _walk(hexa, 8, seed=4)
    rows[6:] += 0.005  # a 5 mm step from row 5 to row 6
    bad = 3
    _fail_proof_of_row(hexa, rows, bad, monkeypatch)
    res = hexa.forward_batch(rows, warm=True)
    assert res.status[bad] == "uncertified" and res.converged[bad + 1 :].all()
    assert all(res.proofs[k] is not None and res.proofs[k].proven for k in (1, 2, 4, 5, 7))  # short steps
    assert res.proofs[6] is None  # the long step: the certificate's checks, as in a batch without a failure
    assert hexa.forward_batch(rows, warm=True, prove=False).converged[6]


def test_a_row_solved_again_takes_any_guess_forward_takes():
    """The review's redo of a 3-6 batch hands the batch's own guess to each row: a list is a guess there too.

    The step's length was read from ``guess[prismatic_q]``, which a list cannot index (TypeError).
    """
    from hexapod_model.kinematics.batch import _solve_proven

    hexa = hm.Hexapod.from_preset("3-6")
    sol = hexa.forward(hexa.inverse(hexa.home_pose).lengths + 1e-4)
    x = sol.lengths + 1e-4
    from_list = _solve_proven(hexa.engine, 1e-10, 20, x, list(sol.q))
    from_array = _solve_proven(hexa.engine, 1e-10, 20, x, sol.q.copy())
    assert from_list.status == from_array.status == "converged"
    assert np.array_equal(from_list.q, from_array.q) and from_list.proof == from_array.proof
