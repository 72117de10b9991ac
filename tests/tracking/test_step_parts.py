"""The tracker step's shortcuts give, bit for bit, what the plain calls they replace give."""

from __future__ import annotations

import dataclasses
import threading

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.sensitivity import SensitivityEvaluator, _holds
from hexapod_model.tracking.types import _COEFFS, PREDICTORS, TrackResult, predict, track_result


@pytest.fixture(scope="module")
def reference():
    return hm.Hexapod.from_preset("reference")


def _plain_predict(model, history, predictor):
    """``P0 (+) (0 + a1 (P1 (-) P0) + a2 (P2 (-) P0))``, summed from a zero vector."""
    a1, a2 = _COEFFS[predictor]
    if a1 == 0.0 and a2 == 0.0:
        return history[0].copy()
    dv = np.zeros(model.nv)
    if a1:
        dv += a1 * pin.difference(model, history[0], history[1])
    if a2:
        dv += a2 * pin.difference(model, history[0], history[2])
    return pin.integrate(model, history[0], dv)


@pytest.mark.parametrize("predictor", PREDICTORS)
def test_predict_sums_in_place_what_the_plain_sum_gives(reference, predictor):
    model = reference.model
    rng = np.random.default_rng(3)
    q0 = reference.q_home
    for k in range(20):
        h = [pin.integrate(model, q0, rng.normal(0.0, 1e-3, model.nv)) for _ in range(3)]
        if k % 4 == 0:
            h[1] = h[0].copy()  # a zero difference: -1 * 0 is -0, the plain sum makes it +0
        got, want = predict(model, h, predictor), _plain_predict(model, h, predictor)
        assert np.array_equal(got, want) and np.array_equal(np.signbit(got), np.signbit(want))


def test_track_result_is_the_frozen_dataclass(reference):
    sol = reference.forward(np.full(6, 1e-3))
    values = (sol, "ok", ("jump",), (2,), 1.5, 1e-5, 2e-5, 30.0, 0.5, 1e-4)
    fast, plain = track_result(*values), TrackResult(*values)
    assert type(fast) is TrackResult and fast == plain and repr(fast) == repr(plain)
    assert [getattr(fast, f.name) for f in dataclasses.fields(TrackResult)] == list(values)
    with pytest.raises(dataclasses.FrozenInstanceError):
        fast.status = "failed"  # type: ignore[misc]


def test_holds_compares_as_numpy_does():
    rng = np.random.default_rng(0)
    q = rng.normal(size=9)
    cases = [q.copy(), np.r_[q, 1.0, 2.0], q + 1e-17, q * (1 + 1e-15), q[:5]]
    z = q.copy()
    z[2] = 0.0
    cases += [np.where(np.arange(9) == 2, -0.0, q), np.where(np.arange(9) == 4, np.nan, q)]
    for aug, qq in [(c, q) for c in cases] + [(z, cases[5]), (cases[6], cases[6])]:
        want = aug.shape[0] >= qq.shape[0] and bool((aug[: qq.shape[0]] == qq).all())
        assert _holds(aug, qq) == want


def test_evaluate_solved_follows_the_calling_threads_solver(reference):
    """One evaluator used after solves on two threads gives what a fresh evaluator gives on each."""
    length = 0.25
    ev = SensitivityEvaluator(reference, length)
    rng = np.random.default_rng(1)
    readings = [rng.uniform(-4e-3, 4e-3, 6) for _ in range(4)]
    out: dict[int, tuple] = {}

    def solve_and_evaluate(i: int) -> None:
        sol = reference.forward(readings[i], check=False)
        a = ev.evaluate_solved(sol.q)
        ja = ev.Jinv.copy()
        fresh = SensitivityEvaluator(reference, length)
        b = fresh.evaluate_solved(sol.q)
        out[i] = (a, b, ja, fresh.Jinv.copy())

    for i in range(4):
        if i % 2:
            t = threading.Thread(target=solve_and_evaluate, args=(i,))
            t.start()
            t.join()
        else:
            solve_and_evaluate(i)
    for a, b, ja, jb in out.values():
        assert a == b and np.array_equal(ja, jb)
    assert len({a.condition_number for a, _, _, _ in out.values()}) == 4


@pytest.mark.parametrize("name", ["reference", "spherical", "3-6"])
def test_evaluate_solved_gives_what_the_full_closure_jacobian_gives(name):
    """The tracker's evaluation from the solve's own blocks (6- and 3-row closures) against the
    elimination of the full closure Jacobian (:meth:`SensitivityEvaluator.evaluate`), another
    route: the 6x6 Jacobian to 1e-12 of its largest entry, the figures to 1e-9 relative."""
    hexa = hm.Hexapod.from_preset(name, check_body=False)
    solved, full = SensitivityEvaluator(hexa, 0.25), SensitivityEvaluator(hexa, 0.25)
    home = hexa.inverse(hexa.home_pose).lengths
    rng = np.random.default_rng(5)
    for _ in range(10):
        sol = hexa.forward(home + rng.uniform(-8e-3, 8e-3, 6), check=False)
        assert sol.converged
        a, b = solved.evaluate_solved(sol.q), full.evaluate(sol.q)
        np.testing.assert_allclose(solved.J, full.J, rtol=0, atol=1e-12 * np.abs(full.J).max())
        np.testing.assert_allclose(solved.Jinv, full.Jinv, rtol=0, atol=1e-9 * np.abs(full.Jinv).max())
        assert a.det_sign == b.det_sign != 0
        for field in ("translation", "rotation", "condition_number"):
            assert getattr(a, field) == pytest.approx(getattr(b, field), rel=1e-9)


def test_ages_without_a_hole_give_what_the_ages_computed_give(reference):
    """The motion model's ages taken from the table (no untrusted sample among the last ones) or
    computed from the sample numbers: the same samples, bit for bit, through gaps and jumps."""
    from hexapod_model.tracking.tracker import Tracker

    rng = np.random.default_rng(2)
    stream = np.linspace(0.0, 0.003, 120)[:, None] * rng.uniform(-1, 1, 6) + rng.normal(0.0, 1e-6, (120, 6))
    stream[40:42] = np.nan  # unreadable samples: holes in the ages
    stream[70, 3] += 1e-3  # a jump: an untrusted sample
    stream[90:96, 1] += 4e-3  # untrusted beyond max_gap: the history restarts
    fast, plain = Tracker(reference, noise=1e-6), Tracker(reference, noise=1e-6)
    for x in stream:
        plain._run = 0  # computes the ages from the sample numbers
        a, b = fast.step(x), plain.step(x)
        assert (a.status, a.flags, a.legs) == (b.status, b.flags, b.legs)
        assert np.array_equal(a.solution.q, b.solution.q)
        figures = ("innovation", "sigma_translation", "sigma_rotation", "condition_number")
        assert np.array_equal([getattr(a, f) for f in figures], [getattr(b, f) for f in figures], equal_nan=True)
