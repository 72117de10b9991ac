"""The simulator's scripted changeover: the plate moves to its fixture's target, overshoots, settles and stays."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.lie import xyz_rpy_to_pose as placement
from hexapod_model.service import ConfigError, Simulator
from hexapod_model.service.sim.changeover import ChangeoverScript

from ..conftest import hexapod
from .helpers import CollectingBus, fixture_table, service_config, sim_config

HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]


def following(service, sim, name):
    """A simulator of ``name`` on a collecting bus, and the dict whose ``key`` and ``pose`` are its target."""
    current: dict = {"key": None, "pose": None}
    bus = CollectingBus()
    targets = lambda _: (current["key"], current["pose"])  # noqa: E731
    return Simulator(service, sim, bus, hexapods={name: hexapod("reference")}, targets=targets), current  # type: ignore[arg-type]


def test_the_progress_overshoots_and_settles_on_the_target():
    s = ChangeoverScript(move=2.0, overshoot=0.2, settle=1.0)
    values = [s.progress(t) for t in np.linspace(0.0, 4.0, 401)]
    assert values[0] == 0.0 and max(values) == pytest.approx(1.2) and values[-1] == 1.0
    assert s.progress(2.0) == pytest.approx(1.2) and s.progress(3.0) == 1.0
    assert all(b >= a for a, b in zip(values[:200], values[1:201]))  # monotone up to the overshoot


def test_a_simulated_plate_follows_its_target_when_it_changes(tmp_path):
    service = service_config(tmp_path, [fixture_table("right", 1)])
    script = {"move": 1.0, "overshoot": 0.25, "settle": 0.5}
    sim = sim_config(service, [{"name": "right", "rate": 50.0, "noise": 0.0, "hold": HOLD, "changeover": script}])
    goal = placement([0.012, -0.02, 0.412, 5.0, -3.0, 10.5])
    simulator, current = following(service, sim, "right")
    before = [simulator.send_set(0, k / 50.0) for k in range(10)]
    assert all(np.allclose(s.pose, placement(HOLD), atol=1e-9) for s in before)
    current.update(key=7, pose=goal)
    during = [simulator.send_set(0, 0.2 + k / 50.0) for k in range(100)]  # 2 s: move, overshoot, settle, stay
    start = pin.SE3(placement(HOLD))
    step = pin.log6(start.inverse() * pin.SE3(goal)).vector
    distance = [float(np.linalg.norm(pin.log6(start.inverse() * pin.SE3(s.pose)).vector[:3])) for s in during]
    assert max(distance) == pytest.approx(1.25 * np.linalg.norm(step[:3]), rel=1e-3)  # the overshoot
    assert np.allclose(during[-1].pose, goal, atol=1e-9) and np.allclose(during[-20].pose, goal, atol=1e-9)
    assert np.allclose(during[-1].readings, hexapod("reference").inverse(goal).lengths, atol=1e-12)
    current.update(key=None, pose=None)  # cleared: the plate stays where it is
    after = simulator.send_set(0, 2.5)
    assert np.allclose(after.pose, goal, atol=1e-9)


def test_a_bad_changeover_script_names_the_field(tmp_path):
    service = service_config(tmp_path, [fixture_table("right", 1)])
    with pytest.raises(ConfigError, match=r"fixtures\[0\].changeover.overshoot"):
        sim_config(service, [{"name": "right", "hold": HOLD, "changeover": {"overshoot": 2.0}}])
    with pytest.raises(ConfigError, match=r"fixtures\[0\].changeover.speed"):
        sim_config(service, [{"name": "right", "hold": HOLD, "changeover": {"speed": 2.0}}])


def test_a_playing_plate_slows_to_a_stop_before_it_moves_to_its_target(tmp_path):
    service = service_config(tmp_path, [fixture_table("left")])
    script = {"move": 1.0, "overshoot": 0.1, "settle": 0.5}
    fixture = {"name": "left", "rate": 100.0, "noise": 0.0, "trajectory": "A", "period": 4.0, "changeover": script}
    sim = sim_config(service, [fixture])
    simulator, current = following(service, sim, "left")
    goal = placement([0.0, 0.003, 0.405, 1.0, 0.0, -2.0])
    positions = []
    for k in range(460):  # 1 s of trajectory, the request, the stop (ramp 0.2 s), two moves of 1.5 s
        if k == 100:
            current.update(key=1, pose=goal)
        if k == 200:
            current.update(key=2, pose=placement(HOLD))  # during the move: taken once it has settled
        positions.append(simulator.send_set(0, k / 100.0).pose[:3, 3])
    p = np.array(positions)
    accel = np.linalg.norm(np.diff(p, 2, axis=0), axis=1)
    assert accel[100:].max() <= 3.0 * accel[:98].max()  # no velocity step when it stops, turns or starts
    # request at set 100, stopped after the ramp (0.2 s), moved and settled 1.5 s later: then the second move
    reached = [k for k in range(250, 300) if np.allclose(p[k], goal[:3, 3], atol=1e-9)]
    assert reached and 268 <= reached[0] <= 273, reached
    assert np.allclose(p[-1], placement(HOLD)[:3, 3], atol=1e-9)  # then the second one
