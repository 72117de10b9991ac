"""The encoder's count reaches the tracker: a fixture at rest with counts coarser than its noise is not ``stuck``."""

from __future__ import annotations

from .helpers import drive, fixture_table, service_config, sim_config


def test_a_fixture_at_rest_with_5um_counts_and_2um_noise_publishes_no_false_stuck(tmp_path):
    encoder = {"metres_per_count": 5e-6}
    service = service_config(tmp_path, [fixture_table(noise=2e-6, encoder=encoder)])
    sim = sim_config(
        service, [{"name": "left", "rate": 100.0, "noise": 2e-6, "hold": [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]}]
    )
    cycle, out = drive(service, sim, 5.0)
    records = [rec for _, rec in out]
    assert len(records) >= 450  # every set but the first few gives a record
    stuck = [rec for rec in records if "stuck" in rec.flags or any(f.startswith("stuck") for f in rec.flags)]
    assert stuck == [], f"{len(stuck)} of {len(records)} records falsely stuck: {stuck[0].flags}"
    assert cycle.solver.tracker.settings.resolution == 5e-6
