"""A locked fixture's records carry the process wrench's leg forces and the brakes' load margin."""

from __future__ import annotations

import numpy as np
import pytest

from hexapod_model.analysis.statics import leg_forces
from hexapod_model.lie import rpy_to_matrix
from hexapod_model.service import ConfigError

from ..conftest import hexapod
from .helpers import drive, fixture_table, service_config, sim_config

HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]  # m and deg
WRENCH = [20.0, -10.0, -500.0, 0.0, 20.0, 5.0]  # N, N m, platform frame


def test_locked_records_carry_leg_forces_and_margin(tmp_path):
    fixture = fixture_table(lock_time=0.2, process_wrench=WRENCH, wrench_point=[0.0, 0.0, 0.1], brake_capacity=150.0)
    svc = service_config(tmp_path, [fixture])
    cycle, out = drive(svc, sim_config(svc, [{"name": "left", "rate": 100.0, "hold": HOLD}]), 0.6)
    locked = [rec for _, rec in out if rec.state == "locked"]
    assert locked and all(rec.load is None for _, rec in out if rec.state != "locked")
    truth = np.eye(4)
    truth[:3, 3] = HOLD[:3]
    truth[:3, :3] = rpy_to_matrix(*np.radians(HOLD[3:]))
    expected = leg_forces(hexapod("reference"), truth, WRENCH, point=[0.0, 0.0, 0.1])
    for rec in locked:
        load = rec.load
        # the lock pose is the truth within the reading noise (10 um): forces within 1e-3 relative
        np.testing.assert_allclose(load["leg_forces_N"], expected.axial_force, atol=1e-3 * expected.largest_axial_force)
        assert load["largest_leg_force_N"] == pytest.approx(max(abs(f) for f in load["leg_forces_N"]))
        assert load["brake_capacity_N"] == 150.0
        assert load["margin_N"] == pytest.approx(150.0 - load["largest_leg_force_N"])


def test_no_wrench_no_load_and_bad_wrench_is_named(tmp_path):
    svc = service_config(tmp_path, [fixture_table(lock_time=0.2)])
    _, out = drive(svc, sim_config(svc, [{"name": "left", "rate": 100.0, "hold": HOLD}]), 0.4)
    assert any(rec.state == "locked" for _, rec in out) and all(rec.load is None for _, rec in out)
    with pytest.raises(ConfigError, match=r"process_wrench"):
        service_config(tmp_path, [fixture_table(process_wrench=[1.0, 2.0])])
    with pytest.raises(ConfigError, match=r"brake_capacity"):
        service_config(tmp_path, [fixture_table(process_wrench=WRENCH, brake_capacity=-1.0)])
