"""The geometry's encoder count reaches the stream tracker: no false ``stuck`` from counts by default."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.exceptions import GeometryError
from hexapod_model.tracking.tracker import Tracker

NOISE, COUNT = 2e-6, 5e-6  # m: encoder noise below the count, so a working leg often repeats its value


def counted_hexapod() -> hm.Hexapod:
    """The reference preset with 5 um encoder counts declared in its geometry."""
    geometry = dataclasses.replace(hm.get_preset("reference"), encoder_resolution=COUNT)
    return hm.Hexapod.from_geometry(geometry)


def readings(n: int, speed: float, rng: np.random.Generator) -> np.ndarray:
    """``n`` samples (1 kHz) of six legs moving at ``speed`` (m/s, a slow sine), noisy, rounded to counts."""
    t = np.arange(n)[:, None] * 1e-3
    phase = np.arange(6)[None, :]
    true = speed / (2 * np.pi * 0.5) * np.sin(2 * np.pi * 0.5 * t + phase)
    return np.round((true + rng.normal(0.0, NOISE, (n, 6))) / COUNT) * COUNT


def test_the_geometry_resolution_is_the_tracker_default():
    hexa = counted_hexapod()
    assert hexa.encoder_resolution == COUNT
    assert Tracker(hexa, noise=NOISE).settings.resolution == COUNT
    assert Tracker(hexa, noise=NOISE, resolution=1e-6).settings.resolution == 1e-6  # the caller's own
    assert Tracker(hm.Hexapod.from_preset("reference"), noise=NOISE).settings.resolution == 0.0
    round_trip = hm.geometry_from_dict(hexa.geometry.to_dict())
    assert round_trip.encoder_resolution == COUNT
    assert "encoder_resolution" not in hm.get_preset("reference").to_dict()


def test_the_stuck_run_length_is_computed_with_the_tracker_not_at_the_first_frozen_run():
    """Its first computation imports scipy (~0.2 s): at a leg's first frozen run it stalled that sample."""
    from hexapod_model.tracking.false_alarms import stuck_run

    tracker = Tracker(counted_hexapod(), noise=NOISE)
    assert "frozen_run" in vars(tracker.settings)  # the cached property, evaluated at construction
    assert tracker.settings.frozen_run == stuck_run(NOISE, COUNT, tracker.settings.stuck_samples) > 3


def test_a_bad_resolution_names_the_value_and_the_limit():
    with pytest.raises(GeometryError, match="encoder_resolution.*-1e-06"):
        dataclasses.replace(hm.get_preset("reference"), encoder_resolution=-1e-6)


@pytest.mark.parametrize("speed", [0.0, 2e-4])
def test_no_false_stuck_from_the_geometry_counts(speed):
    """2 um noise, 5 um counts in the geometry, no resolution passed: no sample flagged ``stuck``."""
    tracker = Tracker(counted_hexapod(), noise=NOISE)
    flags = [tracker.step(r).flags for r in readings(5_000, speed, np.random.default_rng(11))]
    assert sum("stuck" in f for f in flags) == 0
