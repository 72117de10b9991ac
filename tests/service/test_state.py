"""Locked / moving / drift and stuck legs, judged from synthetic readings."""

from __future__ import annotations

import numpy as np

from hexapod_model.service.cycle.lock import LockDetector
from hexapod_model.service.cycle.stuck import StuckDetector

NOISE = 10e-6


def feed(det: LockDetector, readings, rate=64.0, t0=0.0, lock_when_ready=True):
    """(state, drift, locked on this sample) per sample; 64 Hz keeps the sample times exact."""
    events = []
    for k, r in enumerate(readings):
        t = t0 + k / rate
        locked_now = det.update(t, np.asarray(r)) and lock_when_ready
        if locked_now:
            det.lock(t, det.run_mean)
        events.append((det.state, det.drift, locked_now))
    return events


def test_steady_readings_lock_after_lock_time_and_the_reference_is_their_mean():
    rng = np.random.default_rng(0)
    det = LockDetector(lock_time=0.5, band=10 * NOISE, drift_limit=3 * NOISE, unlock_samples=3)
    moving = [np.full(6, 0.001 * k) for k in range(20)]  # 1 mm per sample: never steady
    still = 0.02 + rng.normal(0, NOISE, (100, 6))
    events = feed(det, moving + list(still))
    assert [k for k, e in enumerate(events) if e[2]] == [20 + 32]  # 0.5 s at 64 Hz after the motion stopped
    assert det.state == "locked" and np.allclose(det.reference, still[:33].mean(0), atol=1e-12)
    assert not det.drift


def test_one_spike_does_not_unlock_three_samples_outside_do():
    rng = np.random.default_rng(1)
    det = LockDetector(0.2, 10 * NOISE, 3 * NOISE, 3)
    base = list(0.01 + rng.normal(0, NOISE, (40, 6)))
    feed(det, base)
    assert det.state == "locked"
    spike = base[-1].copy()
    spike[2] += 0.002
    feed(det, [spike, base[0], base[1]], t0=1.0)
    assert det.state == "locked"
    away = [b + 0.001 for b in base[:3]]
    states = [e[0] for e in feed(det, away, t0=2.0, lock_when_ready=False)]
    assert states == ["locked", "locked", "moving"]


def test_slow_creep_while_locked_raises_drift_before_it_unlocks():
    rng = np.random.default_rng(2)
    det = LockDetector(0.2, 10 * NOISE, 3 * NOISE, 3)
    feed(det, list(0.01 + rng.normal(0, NOISE, (40, 6))))
    assert det.state == "locked"
    creep = [0.01 + rng.normal(0, NOISE, 6) + np.array([0, 0, 0, 0, 0, 1e-6 * k]) for k in range(100)]
    events = feed(det, creep, t0=1.0, lock_when_ready=False)
    first_drift = next(k for k, e in enumerate(events) if e[1])
    assert events[first_drift][0] == "locked"
    # the average crosses 3 sigma = 30 um: the creep's 30 um plus the average's lag (0.2 s = 13 samples)
    assert 25 <= first_drift <= 60
    assert all(e[0] == "locked" for e in events)


def test_noise_alone_never_drifts_or_unlocks():
    rng = np.random.default_rng(3)
    det = LockDetector(0.2, 10 * NOISE, 3 * NOISE, 3)
    events = feed(det, list(0.01 + rng.normal(0, NOISE, (3000, 6))))
    assert sum(e[2] for e in events) == 1  # locked once, never released
    assert all(e[0] == "locked" and not e[1] for e in events[100:])


def test_stuck_leg_is_a_repeat_its_own_recent_motion_rules_out():
    rng = np.random.default_rng(4)
    det = StuckDetector(sigmas=8, noise=NOISE, resolution=1e-6)
    found, frozen = [], 0.0
    for k in range(40):
        r = 2e-5 * k + rng.normal(0, NOISE, 6)  # 20 um per set: 2 sigma
        if k >= 20:
            r[5] = frozen
        else:
            frozen = r[5]
        found.append(det.update(k, [round(v / 1e-6) for v in r], r))
    # 8 sigma = 80 um of expected motion, 4 sets after the stop at the true speed; this leg moves
    # 2 sigma per set, so its estimated speed is noisy: caught within 10 sets, then for good
    first = next(k for k, f in enumerate(found) if f)
    assert 21 <= first <= 30 and all(f == [5] for f in found[first:]) and not any(found[:first])
    still = StuckDetector(8, NOISE, 1e-6)  # a still leg repeating counts (here: no noise at all) is not stuck
    assert all(still.update(k, [7] * 6, np.full(6, 7e-6)) == [] for k in range(50))
    assert StuckDetector(0, NOISE, 1e-6).update(0, [1] * 6, np.zeros(6)) == []


def test_noisy_still_legs_repeating_counts_are_not_stuck():
    rng = np.random.default_rng(5)
    det = StuckDetector(8, NOISE, 1e-6)
    hits = 0
    for k in range(20_000):  # counts repeat by chance about 3 % of the sets
        r = 0.01 + rng.normal(0, NOISE, 6)
        hits += len(det.update(k, [round(v / 1e-6) for v in r], r))
    assert hits == 0


class _NumpyLockDetector(LockDetector):
    """The detector's per-set arithmetic as it was written with NumPy arrays (the reference for the float version)."""

    def update(self, t: float, readings) -> bool:
        r = np.asarray(readings, dtype=float)
        if self.state == "locked":
            ref = np.array(self._ref)
            if float(abs(r - ref).max()) > self.band:
                self._outside += 1
                if self._outside >= self.unlock_samples:
                    self.state, self.reference, self.drift, self._outside = "moving", None, False, 0
                    self._restart(t, r.tolist())
                return False
            self._outside = 0
            alpha = 1.0 - np.exp(-max(t - self._t_last, 0.0) / max(self.lock_time, 1e-9))
            ema = np.array(self._ema)
            ema += alpha * (r - ema)
            self._ema = ema.tolist()
            self._t_last = t
            self.drift = float(abs(ema - ref).max()) > self.drift_limit
            return False
        assert self._n == 0 or self._run_start is not None
        if self._run_start is None or float(abs(r - np.array(self._run_start[1])).max()) > self.band:
            self._restart(t, r.tolist())
        else:
            self._sum = (np.array(self._sum) + r).tolist()
            self._n += 1
        return t - self._run_start[0] >= self.lock_time  # type: ignore[index]


def test_float_arithmetic_gives_the_numpy_detectors_states_and_values():
    """Steady runs, locks, a creep, spikes and unlocks: the same events; reference, mean, average to 1e-15 m."""
    rng = np.random.default_rng(5)
    base = 0.01 + rng.normal(0, 1e-3, 6)
    readings = [base + rng.normal(0, NOISE, 6) for _ in range(120)]  # still
    readings += [base + 1e-6 * k + rng.normal(0, NOISE, 6) for k in range(60)]  # creeps: drift
    readings += [base + 5e-3 + rng.normal(0, NOISE, 6) for k in range(10)]  # moved: unlocks
    readings += [base + rng.normal(0, NOISE, 6) for _ in range(80)]  # still again: locks again
    readings[150][2] += 1e-3  # one spike while locked
    fast, slow = LockDetector(0.3, 10 * NOISE, 3 * NOISE, 3), _NumpyLockDetector(0.3, 10 * NOISE, 3 * NOISE, 3)
    assert feed(fast, [r.tolist() for r in readings]) == feed(slow, readings)
    assert fast.state == "locked"
    np.testing.assert_allclose(fast.reference, slow.reference, rtol=0, atol=1e-15)  # readings ~1e-2 m
    np.testing.assert_allclose(fast._ema, slow._ema, rtol=0, atol=1e-15)
    np.testing.assert_allclose(fast.run_mean, slow.run_mean, rtol=0, atol=1e-15)
    events = feed(LockDetector(0.3, 10 * NOISE, 3 * NOISE, 3), readings)
    assert any(drift for _, drift, _ in events) and sum(now for _, _, now in events) == 2


def test_a_nan_reading_neither_unlocks_nor_counts_as_a_step_as_with_numpy():
    det = LockDetector(0.2, 10 * NOISE, 3 * NOISE, 1)
    det.lock(0.0, np.zeros(6))
    assert det.update(0.1, [np.nan, 1.0, 0, 0, 0, 0]) is False and det.state == "locked"


def test_a_leg_stopping_repeats_counts_naturally_and_is_not_stuck():
    """1 um counts, 10 um noise, 100 sets/s: a leg that slows to a stop repeats its count while its
    average speed still says it moves (the old check flagged it about every 6 s here)."""
    rng = np.random.default_rng(7)
    det = StuckDetector(8, NOISE, 1e-6)
    hits, k, x = 0, 0, 0.0
    ramp = np.linspace(0.0, 0.05, 20)  # m/s: 0.2 s ramps, 0.6 s at 50 mm/s, 0.5 s still
    profile = np.concatenate([ramp, np.full(60, 0.05), ramp[::-1], np.zeros(50)])
    for _ in range(100):
        for v in profile:
            x += v / 100.0
            r = x + rng.normal(0, NOISE, 6)
            hits += len(det.update(k, [round(u / 1e-6) for u in r], r))
            k += 1
    assert hits == 0
