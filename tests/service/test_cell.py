"""Poses in the robot frame: the cell placement, the coupling's sigma, locating the base from touched points."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.exceptions import InputError
from hexapod_model.lie import xyz_rpy_to_pose as placement
from hexapod_model.service import ConfigError
from hexapod_model.service.config.cell import Cell, locate
from hexapod_model.service.cycle.solver import PoseSolver
from hexapod_model.service.targets.guidance import guidance

from ..conftest import hexapod
from .helpers import drive, fixture_table, record_pose, service_config, sim_config

HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]
BASE_IN_ROBOT = [0.85, -0.3, 0.02, 1.0, -2.0, 90.0]


def test_locate_recovers_the_placement_from_three_or_more_touched_points_with_the_residual():
    rng = np.random.default_rng(4)
    T = placement(BASE_IN_ROBOT)
    base = np.array([[0.2, 0.0, 0.0], [-0.1, 0.17, 0.0], [-0.1, -0.17, 0.0], [0.0, 0.0, 0.05]])
    robot = base @ T[:3, :3].T + T[:3, 3]
    exact = locate(base[:3], robot[:3])
    assert np.allclose(exact.base_in_robot, T, atol=1e-12) and exact.rms < 1e-12
    assert np.allclose(exact.values, BASE_IN_ROBOT, atol=1e-9)
    noisy = locate(base, robot + rng.normal(0.0, 50e-6, robot.shape))
    assert 5e-6 < noisy.rms < 200e-6 and len(noisy.residuals) == 4
    assert np.linalg.norm(noisy.base_in_robot[:3, 3] - T[:3, 3]) < 200e-6


@pytest.mark.parametrize(
    "base, why",
    [
        (np.zeros((2, 3)), "at least three"),
        (np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 0, 0]]), "one line"),
        (np.array([[0.0, 0, 0], [0.1, 0, 0], [np.nan, 0, 0]]), "finite"),
    ],
)
def test_locate_refuses_what_cannot_fix_a_placement(base, why):
    with pytest.raises(InputError, match=why):
        locate(base, base)


def test_the_coupling_sigma_is_the_linear_propagation_of_the_reading_noise():
    hexa = hexapod("reference")
    T = placement(HOLD)
    sol = hexa.inverse(T)
    X = PoseSolver(hexa, 10e-6).propagation(sol.q)
    cell = Cell(placement(BASE_IN_ROBOT), placement([0.0, 0.05, 0.03, 0, 0, 30.0]))
    rng = np.random.default_rng(1)
    xi = rng.normal(0.0, 10e-6, (20000, 6)) @ X.T  # platform twists (platform frame)
    moved = np.array([(pin.SE3(T) * pin.exp6(x)).homogeneous for x in xi[:4000]])
    c = cell.coupling[:3, 3]
    errors = (moved[:, :3, :3] @ c + moved[:, :3, 3]) - (T[:3, :3] @ c + T[:3, 3])
    rms = float(np.sqrt(np.mean(np.sum(errors**2, axis=1))))
    assert cell.translation_sigma(X, 10e-6) == pytest.approx(rms, rel=0.05)
    plain = Cell(cell.base_in_robot, np.eye(4)).translation_sigma(X, 10e-6)  # the platform origin's
    assert plain == pytest.approx(PoseSolver(hexa, 10e-6).uncertainty(sol.q).translation, rel=1e-9)


def test_records_carry_pose_in_robot_from_the_configured_cell(tmp_path):
    cell = {"base_in_robot": BASE_IN_ROBOT, "coupling": [0.0, 0.0, 0.012, 0.0, 0.0, 0.0]}
    service = service_config(tmp_path, [fixture_table("right", 1, cell=cell)])
    sim = sim_config(service, [{"name": "right", "rate": 100.0, "hold": HOLD}])
    _, out = drive(service, sim, 0.3)
    ok = [rec for _, rec in out if rec.status == "ok"]
    assert ok
    hexa = hexapod("reference")
    coupling = Cell(placement(BASE_IN_ROBOT), placement(cell["coupling"]))
    X = PoseSolver(hexa, 10e-6).propagation(hexa.inverse(placement(HOLD)).q)
    for rec in ok:
        expected = placement(BASE_IN_ROBOT) @ record_pose(rec) @ placement(cell["coupling"])
        got = record_pose(rec.pose_in_robot)
        assert np.allclose(got, expected, atol=1e-12)
        s, r = rec.pose_in_robot["sigma"], rec.sigma
        assert s["rotation_deg"] == r["rotation_deg"]
        assert s["translation_mm"] == pytest.approx(coupling.translation_sigma(X, 10e-6) * 1e3, rel=1e-3)
    assert guidance(ok[-1], None)["pose_in_robot"] == ok[-1].pose_in_robot  # /guidance gives it too
    plain = service_config(tmp_path, [fixture_table("right", 1)])
    _, out = drive(plain, sim_config(plain, [{"name": "right", "rate": 100.0, "hold": HOLD}]), 0.1)
    assert all(rec.pose_in_robot is None for _, rec in out)


def test_a_bad_cell_placement_names_the_field(tmp_path):
    with pytest.raises(ConfigError, match=r"fixtures\[0\].cell.base_in_robot"):
        service_config(tmp_path, [fixture_table("right", 1, cell={"base_in_robot": [0, 0, 0]})])
    with pytest.raises(ConfigError, match=r"fixtures\[0\].cell.origin"):
        service_config(tmp_path, [fixture_table("right", 1, cell={"base_in_robot": [0] * 6, "origin": 1})])
