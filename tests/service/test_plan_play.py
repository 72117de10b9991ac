"""A changeover plan played by the simulated encoders and watched by the service for coupling mismatch.

The plans here are made from the cell and the hexapod alone (no UR10: the monitor compares the
flange the plan commands with the coupling the encoders give, the arm's joints do not enter):
each fixture's plate is carried on the SE(3) geodesic from its home pose to a target, the flange
at ``base_in_robot * pose * coupling`` while coupled. Through the real service on the virtual
bus: played as planned, both fixtures end locked in tolerance with no ``coupling_mismatch``;
with one brake held (the leg that changes most keeps its reading), the monitor raises it.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import can
import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.lie import xyz_rpy_to_pose
from hexapod_model.planning.model import PHASES, FixtureCell, Margins, Plan
from hexapod_model.service import ConfigError, FixtureService, Simulator, load_simulation, simulation_from_dict
from hexapod_model.service.sim.plan_player import PlatePath

from ..conftest import hexapod
from .helpers import CollectingBus, fixture_table, record_pose, service_config

CELLS = {
    "left": {"base_in_robot": [0.75, 0.40, 0.0, 0.0, 0.0, 90.0], "coupling": [0.0, 0.0, 0.07, 180.0, 0.0, 0.0]},
    "right": {"base_in_robot": [0.75, -0.40, 0.0, 0.0, 0.0, 90.0], "coupling": [0.0, 0.0, 0.07, 180.0, 0.0, 0.0]},
}
MOVES = {"left": [0.004, -0.003, 0.003, 1.0, -0.5, 2.0], "right": [-0.003, 0.004, -0.002, -1.5, 1.0, -1.0]}
TOLERANCE = {"translation_mm": 0.1, "rotation_deg": 0.05}
PAUSE, CARRY, RATE = 0.3, 1.5, 50  # s per other phase, s of carry, carry points per second


def xyzquat(T: np.ndarray) -> np.ndarray:
    return pin.SE3ToXYZQUAT(pin.SE3(T))


def make_plan(config, names=("left", "right")) -> Plan:
    """Each fixture in turn: approach, couple, release, carry (home to its move), lock, decouple, retract."""
    hexa = hexapod("reference")
    rows: list[tuple] = []  # t, phase, fixture, flange 4x4, platform 4x4 | None
    t = 0.0
    cells = []
    for name in names:
        cell = config.fixture(name).cell
        start = hexa.home_pose
        target = start @ xyz_rpy_to_pose(MOVES[name])
        step = pin.log6(pin.SE3(start).inverse() * pin.SE3(target)).vector

        def flange(T, cell=cell):
            return cell.base_in_robot @ T @ cell.coupling

        above = flange(start) @ xyz_rpy_to_pose([0.0, 0.0, -0.15, 0.0, 0.0, 0.0])
        rows += [(t, "approach", name, above, None), (t + PAUSE, "approach", name, flange(start), None)]
        t += PAUSE
        for phase in ("couple", "release_brakes"):
            t += PAUSE
            rows.append((t, phase, name, flange(start), None))
        n = int(CARRY * RATE)
        for k in range(n + 1):
            s = 0.5 * (1.0 - math.cos(math.pi * k / n))
            T = (pin.SE3(start) * pin.exp6(s * step)).homogeneous
            rows.append((t + CARRY * k / n, "carry", name, flange(T), T))
        t += CARRY
        for phase in ("lock_brakes", "decouple"):
            t += PAUSE
            rows.append((t, phase, name, flange(target), None))
        t += PAUSE
        rows.append((t, "retract", name, flange(target) @ xyz_rpy_to_pose([0.0, 0.0, -0.15, 0.0, 0.0, 0.0]), None))
        cells.append(FixtureCell(name, "reference", cell.base_in_robot, cell.coupling, start, target))
    n = len(rows)
    nan7, nan6 = np.full(7, np.nan), np.full(6, np.nan)
    return Plan(
        tuple(f"joint{k}" for k in range(6)),
        np.array([r[0] for r in rows]),
        np.zeros((n, 6)),
        np.zeros((n, 6)),
        np.zeros((n, 6)),
        tuple(r[1] for r in rows),
        tuple(r[2] for r in rows),
        np.array([xyzquat(r[3]) for r in rows]),
        np.array([nan7 if r[4] is None else xyzquat(r[4]) for r in rows]),
        np.array([nan6 if r[4] is None else hexa.inverse(r[4]).lengths for r in rows]),
        tuple(names),
        "exact",
        Margins(*([1.0] * 8)),
        tuple(cells),
    )


@pytest.fixture
def cell_config(tmp_path):
    fixtures = [fixture_table("left", 0, cell=CELLS["left"]), fixture_table("right", 1, cell=CELLS["right"])]
    return service_config(tmp_path, fixtures)


def write_plan(tmp_path, plan: Plan):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan.to_json(), allow_nan=False))
    return path


def simulation(tmp_path, config, plan: Plan, faults=(), **table):
    path = write_plan(tmp_path, plan)
    fixtures = [
        {"name": "left", "rate": 100.0, "noise": 5e-6, "hold": [0, 0, 0.4, 0, 0, 0], "faults": list(faults)},
        {"name": "right", "rate": 100.0, "noise": 5e-6, "hold": [0, 0, 0.4, 0, 0, 0]},
    ]
    return _with_plan(config, fixtures, path, table)


def _with_plan(config, fixtures, path, table):
    return simulation_from_dict({"seed": 3, "fixtures": fixtures, "plan": {"file": str(path), **table}}, config)


def test_the_simulated_plates_follow_the_plan_at_its_times(tmp_path, cell_config):
    plan = make_plan(cell_config)
    sim = simulation(tmp_path, cell_config, plan, start=0.5)
    hexa = hexapod("reference")
    simulator = Simulator(cell_config, sim, CollectingBus(), hexapods={"left": hexa, "right": hexa})  # type: ignore[arg-type]
    for name, index in (("left", 0), ("right", 1)):
        carry = [k for k in range(len(plan.t)) if plan.fixture[k] == name and plan.phase[k] == "carry"]
        first = next(f for f in plan.fixtures if f.name == name)
        assert np.allclose(simulator.send_set(index, 0.1).pose, first.start, atol=1e-9)  # before the plan
        for k in carry[:: len(carry) // 7]:  # at the plan's points: its platform pose and its readings
            sent = simulator.send_set(index, 0.5 + plan.t[k])
            assert np.allclose(sent.pose, pin.XYZQUATToSE3(plan.platform_pose[k]).homogeneous, atol=1e-9)
            assert np.allclose(sent.readings, plan.readings[k], atol=1e-9)
        after = simulator.send_set(index, 0.5 + plan.t[-1] + 1.0)
        assert np.allclose(after.pose, first.target, atol=1e-9)
        # between the points the velocity is continuous (a step at each point would be a discontinuity to the
        # service): the acceleration at 1 kHz stays within 3 times the carry's own, pi^2 d / (2 T^2) for a distance d
        t = 0.5 + np.arange(plan.t[carry[0]] - 0.05, plan.t[carry[-1]] + 0.05, 1e-3)
        path = PlatePath(sim.plan, name)
        p = np.array([path.pose(x)[:3, 3] for x in t])
        accel = np.linalg.norm(np.diff(p, 2, axis=0), axis=1) / 1e-6
        d = np.linalg.norm(first.target[:3, 3] - first.start[:3, 3])
        assert accel.max() < 3.0 * math.pi**2 * d / (2 * CARRY**2)


def test_a_held_brake_keeps_its_leg_and_the_plate_goes_where_the_readings_put_it(tmp_path, cell_config):
    plan = make_plan(cell_config, ("left",))
    carry = [k for k in range(len(plan.t)) if plan.phase[k] == "carry"]
    leg = int(np.argmax(np.abs(plan.readings[carry[-1]] - plan.readings[carry[0]])))
    fault = {"kind": "held_brake", "leg": leg + 1, "start": 0.0}
    sim = simulation(tmp_path, cell_config, plan, faults=[fault], start=0.0)
    hexa = hexapod("reference")
    simulator = Simulator(cell_config, sim, CollectingBus(), hexapods={"left": hexa})  # type: ignore[arg-type]
    sent = [simulator.send_set(0, plan.t[k]) for k in carry]
    assert len({s.readings[leg] for s in sent}) == 1  # the held leg never moves
    others = [k for k in range(6) if k != leg]
    assert np.allclose(sent[-1].readings[others], plan.readings[carry[-1]][others], atol=1e-12)
    assert np.allclose(hexa.forward(sent[-1].readings).lengths, sent[-1].readings, atol=1e-9)
    off = np.linalg.norm(sent[-1].pose[:3, 3] - pin.XYZQUATToSE3(plan.platform_pose[carry[-1]]).translation)
    assert off > 1e-3  # the plate did not follow the plan
    assert "held_brake" in sent[-1].faults


def test_a_plan_the_configuration_cannot_play_is_refused_in_one_line(tmp_path, cell_config):
    plan = make_plan(cell_config)
    path = write_plan(tmp_path, plan)
    other = service_config(
        tmp_path,
        [
            fixture_table("left", 0, cell={**CELLS["left"], "base_in_robot": [0.7, 0.4, 0, 0, 0, 90]}),
            fixture_table("right", 1, cell=CELLS["right"]),
        ],
    )
    fixtures = [{"name": n, "hold": [0, 0, 0.4, 0, 0, 0]} for n in ("left", "right")]
    with pytest.raises(ConfigError, match=r"plan.file.*left.*another base_in_robot"):
        _with_plan(other, fixtures, path, {})
    with pytest.raises(ConfigError, match=r"plan.file.*'right' of the plan is not simulated"):
        _with_plan(cell_config, fixtures[:1], path, {})
    with pytest.raises(ConfigError, match=r"plan.speed"):
        _with_plan(cell_config, fixtures, path, {"speed": 2.0})
    (tmp_path / "sim.toml").write_text('[[fixtures]]\nname = "left"\nhold = [0, 0, 0.4, 0, 0, 0]\n')
    with pytest.raises(ConfigError, match=r"plan.file.*not valid JSON"):
        load_simulation(tmp_path / "sim.toml", cell_config, plan=tmp_path / "sim.toml")


def play(config, sim, until, seconds, then=None):
    """The service and the simulated plan on one virtual channel until ``until(service, monitor)`` or ``seconds``.

    ``then(service)`` runs once ``until`` holds, before the service stops.
    """
    hexa = hexapod("reference")
    hexapods = {"left": hexa, "right": hexa}
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    service = FixtureService(config, hexapods=hexapods, http=then is not None)
    try:
        service.start()
        for f in sim.plan.plan.fixtures:
            pose = {k: float(v) for k, v in zip(("x", "y", "z", "qx", "qy", "qz", "qw"), xyzquat(f.target))}
            service.changeover.set_target(f.name, {"pose": pose, "tolerance": TOLERANCE}, by="test")
        monitor = sim.plan.monitor(config)
        service.watch(monitor)
        simulator = Simulator(config, sim, bus, hexapods=hexapods, monitor=monitor)
        simulator.start()
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and not until(service, monitor):
            time.sleep(0.1)
        if then is not None:
            then(service)
        simulator.stop()
        return monitor, service.changeover.overview(), service.health()
    finally:
        service.stop()
        bus.shutdown()


@pytest.mark.slow
def test_played_as_planned_both_fixtures_lock_in_tolerance_without_coupling_mismatch(tmp_path, cell_config):
    plan = make_plan(cell_config)
    sim = simulation(tmp_path, cell_config, plan, start=1.0)

    def done(service, monitor):
        overview = service.changeover.overview()
        finished = overview["plan"]["phase"] == "done"
        return finished and all(g["in_tolerance"] and g["state"] == "locked" for g in overview["fixtures"])

    monitor, overview, health = play(cell_config, sim, done, 1.0 + plan.total_time + 15.0)
    progress = overview["plan"]
    assert progress["phase"] == "done" and progress["fraction"] == 1.0 and progress["coupling_mismatch"] is None
    coupled = sum(1 for p in plan.phase if p in ("couple", "release_brakes", "carry", "lock_brakes", "decouple"))
    assert progress["checked"] > coupled  # records of both fixtures' coupled phases were compared (100 sets/s)
    assert progress["largest"]["translation_mm"] < 0.05  # the encoders' coupling is the commanded flange
    assert progress["unchecked"] < 0.05 * progress["checked"]  # a set lost on a busy machine has no pose
    for g in overview["fixtures"]:
        assert g["in_tolerance"] and g["state"] == "locked", g
        target = next(f.target for f in plan.fixtures if f.name == g["fixture"])
        assert np.linalg.norm(record_pose(g)[:3, 3] - target[:3, 3]) < 0.1e-3
    assert health["plan"]["error"] is None and not any("coupling_mismatch" in p for p in health["problems"])


def test_a_brake_that_does_not_release_raises_coupling_mismatch(tmp_path, cell_config):
    plan = make_plan(cell_config)
    carry = [k for k in range(len(plan.t)) if plan.phase[k] == "carry" and plan.fixture[k] == "left"]
    leg = int(np.argmax(np.abs(plan.readings[carry[-1]] - plan.readings[carry[0]])))
    fault = {"kind": "held_brake", "leg": leg + 1, "start": 0.0}
    sim = simulation(tmp_path, cell_config, plan, faults=[fault], start=1.0)
    monitor, overview, health = play(cell_config, sim, lambda s, m: m.mismatch is not None, 1.0 + plan.total_time + 5.0)
    m = overview["plan"]["coupling_mismatch"]
    assert m is not None and m["fixture"] == "left" and m["phase"] == "carry", overview["plan"]
    assert m["translation_mm"] > 2.0 or m["rotation_deg"] > 0.5
    assert health["status"] == "degraded"
    assert any(p.startswith("plan: fixture left: coupling_mismatch at t = ") for p in health["problems"]), health


@pytest.mark.chromium
def test_the_dashboard_shows_the_plans_progress_and_its_mismatch(tmp_path, cell_config):
    from .browser import fields, render_until

    plan = make_plan(cell_config)
    carry = [k for k in range(len(plan.t)) if plan.phase[k] == "carry" and plan.fixture[k] == "left"]
    leg = int(np.argmax(np.abs(plan.readings[carry[-1]] - plan.readings[carry[0]])))
    sim = simulation(tmp_path, cell_config, plan, faults=[{"kind": "held_brake", "leg": leg + 1}], start=1.0)
    dom = []

    def shows_mismatch(page: str) -> bool:
        return 'data-field="plan.coupling_mismatch"' in page

    def look(service):
        host, port = service.address
        # (a dump taken before the service's first event shows no plan: browser.py)
        dom.insert(0, render_until(f"http://{host}:{port}/", tmp_path / "profile", shows_mismatch))

    monitor, _, _ = play(cell_config, sim, lambda s, m: m.mismatch is not None, 1.0 + plan.total_time + 5.0, look)
    shown = fields(dom[0])
    assert shown[(None, "plan.coupling_mismatch")][1] == "left"
    assert "coupling_mismatch: left (carry)" in shown[(None, "plan.coupling_mismatch")][0]
    # the plan's clock runs on while the page renders: a slow machine may render after its end
    phase, fraction = shown[(None, "plan.phase")][1], float(shown[(None, "plan.fraction")][1])
    assert phase in PHASES or phase == "done" and fraction == 1.0, (phase, fraction)
    assert 0.0 < fraction <= 1.0
    assert 0.0 < float(shown[(None, "plan.t_s")][1]) <= plan.total_time + 10.0


def test_serve_plays_a_plan_in_the_simulator_only(capsys):
    from hexapod_model.cli.main import main

    config = Path(__file__).resolve().parents[2] / "docs/examples/fixture.toml"
    assert main(["serve", str(config), "--plan", "plan.json"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert (
        line
        == "hexapod serve: error: invalid --plan 'plan.json': plays in the simulator only: give --simulate SIM.toml"
    )
