"""The tracker's compiled branch-check residual against the Pinocchio calls it replaces."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.kinematics.newton.kernels import largest_step
from hexapod_model.tracking.kernels import (
    SCALARS,
    begin_sample,
    branch_residual,
    motion_readings,
    push_trusted,
)


def _free_flyer() -> pin.Model:
    model = pin.Model()
    model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "platform")
    return model


@pytest.mark.parametrize("step", [0.0, 1e-7, 1e-4, 5e-4, 1e-2, 0.3])
@pytest.mark.parametrize("turn", [0.0, 1.0, 3.1, 3.14])  # at pi itself the axis sign is a free choice
def test_branch_residual_matches_pinocchio_difference_and_integrate(step, turn):
    """``log6(Mm^-1 Ms) - Jinv (l - lhat)`` with ``Mm = M0 (+) sum_j w_j (Mj (-) M0)``, as in Pinocchio.

    History poses ``step`` apart (rad and m), the solved pose turned by ``turn`` rad from the
    newest one (a far assembly); Pinocchio's own rounding near small angles is ~1e-14.
    """
    model = _free_flyer()
    rng = np.random.default_rng(int(1e4 * step + 10 * turn))
    pin.seed(int(1e4 * step + 10 * turn))  # randomConfiguration draws from Pinocchio's own generator
    for _ in range(50):
        q0 = pin.randomConfiguration(model, -np.ones(7), np.ones(7))
        n = int(rng.integers(3, 7))
        F = np.array([q0] + [pin.integrate(model, q0, rng.normal(0.0, step, 6)) for _ in range(n - 1)])
        w = rng.normal(0.0, 1.0, n)
        w /= w.sum()
        axis = rng.normal(0.0, 1.0, 3)
        twist = np.r_[rng.normal(0.0, 0.1, 3), turn * axis / np.linalg.norm(axis)] + rng.normal(0.0, step, 6)
        fs = pin.integrate(model, q0, twist)
        Jinv, l = rng.normal(0.0, 1.0, (6, 6)), rng.normal(0.0, 1e-3, 6)
        lhat = l + rng.normal(0.0, 1e-5, 6)
        dv = np.zeros(6)
        for j in range(1, n):
            dv += w[j] * pin.difference(model, q0, F[j])
        expected = pin.difference(model, pin.integrate(model, q0, dv), fs) - Jinv @ (l - lhat)
        padded = np.vstack([F, np.full((2, 7), np.nan)])  # rows beyond n are never read
        e = np.zeros(6)
        norms = branch_residual(padded, n, w, fs, Jinv, l, lhat, e)
        assert np.abs(e - expected).max() <= 1e-12 * (1.0 + np.abs(w).sum())
        # the parts' norms (m, rad), as np.linalg.norm gives them to rounding
        assert np.allclose(norms, [np.linalg.norm(e[:3]), np.linalg.norm(e[3:])], rtol=1e-15, atol=0.0)


@pytest.mark.parametrize("n", [1, 2, 3, 5])
def test_motion_readings_are_the_weighted_rows(n):
    """``lhat = w @ L[:n]`` over the newest ``n`` rows, to rounding (m); rows beyond ``n`` are never read."""
    rng = np.random.default_rng(n)
    w = rng.normal(0.0, 1.0, n)
    L = np.vstack([rng.uniform(0.5, 0.9, (n, 6)), np.full((2, 6), np.nan)])
    lhat = np.full(6, np.nan)
    motion_readings(w, L, lhat)
    assert np.allclose(lhat, w @ L[:n], rtol=0.0, atol=1e-15 * np.abs(w).sum())


def test_branch_residual_is_zero_on_a_constant_twist_motion():
    """Poses on a constant-twist path, the motion model's weights (sum 1, exact on it): ``e = 0``."""
    model = _free_flyer()
    pin.seed(0)  # Pinocchio's generator, else a new start each run: the bound is met at rounding level
    q0 = pin.randomConfiguration(model, -np.ones(7), np.ones(7))
    xi = np.array([1e-3, -2e-3, 5e-4, 2e-3, -1e-3, 3e-3])
    F = np.array([pin.integrate(model, q0, -k * xi) for k in range(3)])  # newest first
    w = np.array([3.0, -3.0, 1.0])  # quadratic extrapolation one step ahead from ages 1, 2, 3
    fs = pin.integrate(model, q0, xi)
    e = np.zeros(6)
    branch_residual(F, 3, w, fs, np.eye(6), np.zeros(6), np.zeros(6), e)
    assert np.abs(e).max() < 1e-15


def test_begin_sample_is_the_numpy_statistics_ring_and_noise_scale_step_by_step():
    """One call against the tracker's NumPy of these steps: motion readings, reading statistics, ring, noise scale.

    Over 500 samples, some unchecked (no weights), some beyond ``jump_sigmas`` (the scale kept),
    legs now and then unchanged (frozen runs), latched legs, two stuck tolerances: the frozen
    counts, the stuck flag, the ring and its state exactly (comparisons of exact differences,
    copies, counts); the motion model's readings (m), ``z`` (standard deviations), its maximum,
    ``z . z`` and the noise scale to 1e-12 relative (a compiled kernel and NumPy may round the
    last bit differently, by CPU and by library version).
    """
    rng = np.random.default_rng(11)
    rows, jump, rate, floor = 12, 4.0, 0.02, 1e-3
    ring, state, frozen = np.zeros((rows, 6)), np.zeros(2, dtype=np.int64), np.zeros(6, dtype=np.int64)
    values = {"jump_sigmas": jump, "scale_rate": rate, "scale_floor": floor, "z2": 1.0, "scale": 1.0}
    scalars = np.array([values.get(name, 0.0) for name in SCALARS])  # the tolerance and the sigma set below
    index = {name: i for i, name in enumerate(SCALARS)}
    expected_ring, at, count, expected_frozen, z2 = np.zeros((rows, 6)), 0, 0, np.zeros(6, dtype=np.int64), 1.0
    l = rng.uniform(0.0, 0.1, 6)
    lhat, z = np.full(6, np.nan), np.full(6, np.nan)
    for k in range(500):
        l = l + rng.normal(0.0, 1e-5, 6) * (rng.random(6) < 0.7)  # a leg now and then unchanged
        checked = k % 7 != 0
        w = rng.uniform(0.1, 1.0, int(rng.integers(3, 8))) if checked else np.zeros(0)
        w /= w.sum() if checked else 1.0  # weights that sum to 1, as the motion model's
        jumped = k % 11 == 0  # every eleventh sample 10 sigmas from the motion model: the scale kept
        L = l + rng.normal(0.0, 2e-6, (8, 6)) + 3e-4 * jumped
        tol, sd = (0.0, 3e-5) if k % 2 else (3e-6, 2.05e-5)
        scalars[index["stuck_tolerance"]], scalars[index["innovation_sigma"]] = tol, sd
        stuck = rng.random(6) < 0.1
        out = begin_sample(l, ring, state, frozen, stuck, w, L, lhat, z, scalars)
        # the same steps in NumPy
        if count:
            expected_frozen = np.where(np.abs(l - expected_ring[at]) <= tol, expected_frozen + 1, 0)
            at = (at + 1) % rows
        expected_ring[at] = l
        count = min(count + 1, rows)
        assert out[0] and np.array_equal(frozen, expected_frozen)
        assert out[3] == int(expected_frozen.max()) and out[4] == bool(stuck.any())
        assert np.array_equal(ring, expected_ring) and list(state) == [at, count]
        if checked:
            np.testing.assert_allclose(lhat, w @ L[: w.size], rtol=1e-12, atol=0.0)
            # z from the call's own lhat: l - lhat cancels, and would magnify lhat's last bit
            expected_z = np.abs(l - lhat) / sd
            np.testing.assert_allclose(z, expected_z, rtol=1e-12, atol=0.0)
            assert out[1] == pytest.approx(float(expected_z.max()), rel=1e-12, abs=0.0)
            assert out[2] == pytest.approx(float(expected_z @ expected_z), rel=1e-12, abs=0.0)
            assert (out[1] > jump) == jumped
            if not jumped:
                z2 += rate * (min(out[2] / 6.0, 1.0) - z2)
        else:
            assert np.isnan(out[1]) and out[2] == 0.0
        assert scalars[index["z2"]] == pytest.approx(z2, rel=1e-12, abs=0.0)
        assert scalars[index["scale"]] == pytest.approx(max(np.sqrt(z2), floor), rel=1e-12, abs=0.0)
    assert z2 < 0.5 and expected_frozen.max() > 0  # the scale moved, and legs froze


def test_begin_sample_changes_nothing_for_a_non_finite_reading():
    """Readings with a NaN: not finite, and the ring, its state, the frozen counts and the scale as they were."""
    ring, state = np.arange(24.0).reshape(4, 6), np.array([2, 3], dtype=np.int64)
    frozen, scalars = np.array([1, 2, 3, 0, 0, 0], dtype=np.int64), np.linspace(0.1, 0.7, len(SCALARS))
    before = (ring.copy(), state.copy(), frozen.copy(), scalars.copy())
    l = np.array([0.0, np.nan, 0.0, 0.0, 0.0, 0.0])
    out = begin_sample(
        l,
        ring,
        state,
        frozen,
        np.zeros(6, dtype=bool),
        np.ones(3) / 3,
        np.zeros((3, 6)),
        np.zeros(6),
        np.zeros(6),
        scalars,
    )
    assert out[0] is False
    for now, then in zip((ring, state, frozen, scalars), before):
        assert np.array_equal(now, then)


@pytest.mark.parametrize("window", [1, 3, 8])
def test_push_trusted_keeps_the_newest_rows_first_across_the_buffers_copy_back(window):
    """Each push puts the configuration's free-flyer coordinates and readings first; a replace overwrites F's newest.

    Against the rows kept as lists, newest first, over five times the buffer's height (its
    window copied back to the bottom half each time its top is reached): the values are copies,
    so they are equal bit for bit.
    """
    rng = np.random.default_rng(window)
    nq, ffq = 30, 4
    prismatic_q = np.array([11, 14, 17, 20, 23, 26], dtype=np.int64)
    F, L = np.full((2 * window, 7), np.nan), np.full((2 * window, 6), np.nan)
    f_top = l_top = window
    rows_f: list[np.ndarray] = [np.full(7, np.nan)] * window  # the windows as they start: never pushed
    rows_l: list[np.ndarray] = [np.full(6, np.nan)] * window
    for k in range(10 * window + 3):
        q = rng.normal(size=nq)
        replace = k % 4 == 0  # the history's start replaced (L is pushed all the same)
        f_top, l_top = push_trusted(q, ffq, prismatic_q, F, L, f_top, l_top, replace)
        rows_f = [q[ffq : ffq + 7], *rows_f[1:]] if replace else [q[ffq : ffq + 7], *rows_f[:-1]]
        rows_l = [q[prismatic_q], *rows_l[:-1]]
        assert 0 <= f_top <= window and 0 <= l_top <= window
        np.testing.assert_array_equal(F[f_top : f_top + window], np.array(rows_f))
        np.testing.assert_array_equal(L[l_top : l_top + window], np.array(rows_l))


def test_largest_step_is_numpys_and_keeps_a_nan():
    """``max |joints - guess[idx]|`` (m) as NumPy computes it, bit for bit (a maximum rounds nothing); NaN stays NaN."""
    rng = np.random.default_rng(7)
    idx = np.array([3, 9, 15, 21, 27, 33])
    for _ in range(200):
        guess = rng.normal(0.0, 0.1, 40)
        joints = guess[idx] + rng.normal(0.0, 10.0 ** rng.uniform(-7, -1), 6)
        assert largest_step(joints, guess, idx) == np.abs(joints - guess[idx]).max()
    for k in range(6):
        joints = guess[idx].copy()
        joints[k] = np.nan
        assert np.isnan(largest_step(joints, guess, idx))
    assert largest_step(guess[idx], guess, idx) == 0.0


@pytest.mark.parametrize("name", ["reference", "3-6"])
@pytest.mark.parametrize("predictor", ["eq22", "eq23", "eq24"])
@pytest.mark.parametrize("step", [0.0, 1e-6, 1e-3, 3e-2])
def test_the_compiled_predictor_is_pinocchios_to_rounding(name, predictor, step):
    """``predict_into`` against ``types.predict`` (Pinocchio's difference and integrate) on a hexapod's model.

    Histories of configurations ``step`` apart (m and rad, every joint and the platform); the
    compiled guess agrees to 1e-13 (m, rad: rounding of the two Lie formulas, not a tolerance
    of the prediction), and a repeated configuration predicts itself exactly.
    """
    from hexapod_model.tracking.kernels import predict_into
    from hexapod_model.tracking.types import predict, predictor_layout, predictor_weights

    from ..conftest import limits_only

    hexa = limits_only(name)
    model = hexa.model
    layout = predictor_layout(model)
    assert layout is not None
    nv = model.nv
    work = (np.zeros(nv), np.zeros(nv), *[np.zeros((3, 3)) for _ in range(3)], np.zeros(3))
    rng = np.random.default_rng(int(1e6 * step) + len(predictor))
    for _ in range(20):
        q0 = pin.integrate(model, hexa.q_home, rng.normal(0.0, 0.05, nv))
        hist = [q0] + [pin.integrate(model, q0, rng.normal(0.0, step, nv)) for _ in range(2)]
        a1, a2 = predictor_weights(predictor, 3)
        out = np.empty(model.nq)
        if a1 != 0.0:
            predict_into(hist[0], hist[1], a1, hist[2], a2, layout, out, work)
        else:
            predict_into(hist[0], hist[2], a2, hist[0], 0.0, layout, out, work)
        want = predict(model, hist, predictor)
        assert np.max(np.abs(pin.difference(model, want, out))) <= 1e-13
        ffq = layout[2]
        assert abs(np.linalg.norm(out[ffq + 3 : ffq + 7]) - 1.0) <= 1e-14  # a unit quaternion
    out, as_python = np.empty(model.nq), np.empty(model.nq)
    predict_into(q0, hist[1], 0.5, hist[2], -0.75, layout, out, work)
    predict_into.py_func(q0, hist[1], 0.5, hist[2], -0.75, layout, as_python, work)  # run as Python
    np.testing.assert_allclose(as_python, out, rtol=0.0, atol=1e-15)
    predict_into(q0, q0, -1.0, q0, 0.0, layout, out, work)
    assert np.array_equal(out[layout[0]], q0[layout[0]])


def test_a_model_with_other_joints_keeps_pinocchios_predictor():
    from hexapod_model.tracking.types import predictor_layout

    model = _free_flyer()
    model.addJoint(1, pin.JointModelRUBZ(), pin.SE3.Identity(), "wheel")  # a continuous joint: nq 2, nv 1
    assert predictor_layout(model) is None
    assert predictor_layout(pin.Model()) is None  # no free flyer


def _moved_reference(raw: np.ndarray, frozen: np.ndarray, stuck_samples: int) -> np.ndarray:
    """The other legs' largest change over each leg's frozen run, as NumPy computes it (``raw`` oldest first)."""
    moved = np.zeros(6)
    for i in np.flatnonzero(frozen >= stuck_samples):
        back = min(int(frozen[i]), len(raw) - 1)
        d = np.abs(raw[-1] - raw[-1 - back])
        d[i] = 0.0
        moved[i] = d.max()
    return moved


@pytest.mark.parametrize("resolution", [0.0, 1e-6])
def test_stuck_checks_match_the_numpy_stuck_test(resolution):
    """The compiled stuck test against ``stuck_legs`` fed by ``motion_sigmas`` and NumPy's moved legs.

    Random rings of readings (a few samples, full, wrapped), frozen runs, innovations (NaN when
    the sample is not checked), latched legs; the same legs stuck and named, the same jumps.
    """
    from hexapod_model.tracking.kernels import stuck_checks
    from hexapod_model.tracking.reading_tests import TrackerSettings, motion_sigmas, stuck_legs

    s = TrackerSettings(noise=2e-6, resolution=resolution)
    first_run = s.frozen_run if resolution > 0.0 else 1
    bounds = np.array(
        [
            s.stuck_samples,
            s.stuck_sigmas,
            s.stuck_sigmas * np.sqrt(2.0) * s.reading_sigma,
            s.stuck_motion_sigmas,
            s.jump_sigmas,
            s.reading_sigma,
        ]
    )
    rng = np.random.default_rng(11)
    m = s.stuck_samples + 8
    seen = {"stuck": 0, "jump": 0, "free": 0, "moving": 0}
    for trial in range(3000):
        count = int(rng.integers(1, m + 1))
        if trial % 4 == 3:  # a slow drift: significant as a rate before as a change (the rate's test)
            sigma = s.reading_sigma
            raw = np.cumsum(rng.normal(0.6 * sigma, 0.05 * sigma, (count, 6)), axis=0)
        else:
            raw = np.cumsum(rng.normal(0.0, [1e-6, 1e-5, 3e-5][trial % 4], (count, 6)), axis=0)  # oldest first
        frozen = rng.integers(0, 3 * s.frozen_run + 4, 6).astype(np.int64) * (rng.random(6) < 0.25)
        z = np.full(6, np.nan) if trial % 5 == 0 else np.abs(rng.normal(0.0, 3.0, 6))
        latched = rng.random(6) < 0.05
        newest = int(rng.integers(0, m))
        ring = rng.normal(size=(m, 6))  # rows that are not kept hold anything
        for k in range(count):
            ring[(newest - count + 1 + k) % m] = raw[k]
        moving = motion_sigmas(raw, s.reading_sigma) if frozen.max() >= s.stuck_samples else None
        moved = _moved_reference(raw, frozen, s.stuck_samples)
        want = stuck_legs(frozen, z, moved, s, moving) | (latched & (frozen > 0))
        jump = z > s.jump_sigmas
        stuck = latched.copy()
        work = np.empty(6), np.empty(6)
        got = stuck_checks(ring, count, newest, frozen, z, stuck, first_run, s.frozen_run, bounds, *work)
        np.testing.assert_array_equal(stuck, want)
        assert got == (bool(jump.any()), bool(want.any()), sum(1 << i for i in np.flatnonzero(jump | want)))
        seen["stuck" if want.any() else "jump" if jump.any() else "free"] += 1
        if moving is not None:
            seen["moving"] += bool(
                np.any((moving > s.stuck_motion_sigmas) & (frozen >= s.frozen_run) & ~(moved > bounds[2]))
            )
    if resolution > 0.0:  # runs of counts long enough to be stuck span changes the other legs' test sees first
        del seen["moving"]
    assert min(seen.values()) > 50, seen  # every outcome drawn often, and the rate alone making legs stuck
