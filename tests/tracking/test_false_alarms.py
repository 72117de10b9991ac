"""The tracker's false alarms: the quantisation model, the stated rates, and none at rest with counts."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from hexapod_model.tracking.false_alarms import false_alarm_rates, repeat_probability, stuck_run
from hexapod_model.tracking.reading_tests import TrackerSettings
from hexapod_model.tracking.tracker import Tracker

from ..conftest import hexapod

NOISE, COUNT = 10e-6, 5e-6  # m: the encoder noise and resolution of the reported case


def readings(n: int, speed: float, rng: np.random.Generator) -> np.ndarray:
    """``n`` samples (1 kHz) of six legs moving at ``speed`` (m/s, a slow sine), noisy, rounded to counts."""
    t = np.arange(n)[:, None] * 1e-3
    phase = np.arange(6)[None, :]
    true = speed / (2 * np.pi * 0.5) * np.sin(2 * np.pi * 0.5 * t + phase)
    return np.round((true + rng.normal(0.0, NOISE, (n, 6))) / COUNT) * COUNT


@pytest.mark.parametrize("speed", [0.0, 2e-4])
def test_no_false_stuck_from_encoder_counts_at_rest_or_moving_slowly(speed):
    """10 um noise, 5 um counts, 20,000 samples: 8 false stuck at rest and 13 moving slowly before."""
    tracker = Tracker(hexapod("reference"), noise=NOISE, resolution=COUNT)
    flags = [tracker.step(r).flags for r in readings(20_000, speed, np.random.default_rng(7))]
    assert sum("stuck" in f for f in flags) == 0
    assert sum("jump" in f for f in flags) <= 2  # 0.07 expected (3.4e-6 a sample)


def test_a_frozen_leg_is_still_stuck_with_counts():
    tracker = Tracker(hexapod("reference"), noise=NOISE, resolution=COUNT)
    data = readings(600, 2e-3, np.random.default_rng(8))
    data[300:, 1] = data[300, 1]  # leg 2 freezes while the others move
    flags = [tracker.step(r).flags for r in data]
    first = next(k for k, f in enumerate(flags) if "stuck" in f)
    # after the improbable run (11 samples), once the others moved 3 sqrt(2) sigmas (~22 samples at 2 mm/s)
    assert 300 + tracker.settings.frozen_run <= first <= 300 + 40


def test_repeat_probability_matches_a_simulation_and_the_stated_rates():
    rng = np.random.default_rng(9)
    u = rng.uniform(0.0, COUNT, 400_000)
    a, b = (np.round((u + rng.normal(0.0, NOISE, u.size)) / COUNT) for _ in range(2))
    p_sim = np.mean(a == b)
    p = repeat_probability(NOISE, COUNT)
    assert abs(p - p_sim) < 4 * np.sqrt(p * (1 - p) / u.size)
    assert p == pytest.approx(COUNT / (2 * np.sqrt(np.pi) * NOISE), rel=0.02)  # noise spans counts
    assert repeat_probability(NOISE, 0.0) == 0.0 and repeat_probability(1e-7, COUNT) > 0.95
    assert p ** stuck_run(NOISE, COUNT, 3) <= 1e-9 < p ** (stuck_run(NOISE, COUNT, 3) - 1)
    rates = false_alarm_rates(1000.0, NOISE, COUNT)
    assert rates["jump"] == pytest.approx(3.6e6 * (1 - (1 - 2 * norm.sf(5.0)) ** 6), rel=1e-9)  # ~12 an hour
    assert rates["stuck"] < 0.05
    assert TrackerSettings(resolution=COUNT).reading_sigma == pytest.approx(np.hypot(NOISE, COUNT / np.sqrt(12)))
