"""Redundant sensors in the service: configuration, complete sets, the consistency test, the simulator."""

from __future__ import annotations

import importlib.util
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from hexapod_model.service import ConfigError, FixtureCycle, Simulator, geometry_hash
from hexapod_model.service.config.tilt import TiltCodec

from ..conftest import hexapod
from .helpers import CollectingBus, drive, pose_error, service_config, sim_config

ROOT = Path(__file__).resolve().parents[2]
SEVEN = [0x181 + k for k in range(7)]


def fixture(preset: str, ids: list[int], **extra) -> dict:
    # sigma of the geometry (1 um) and counts well below it: the consistency test's weights hold
    return {
        "name": "left",
        "hexapod": preset,
        "can_ids": ids,
        "noise": 1e-6,
        "encoder": {"metres_per_count": 1e-7},
        **extra,
    }


TILT = {"inclinometer": {"can_id": 0x1A0}}


def run(tmp_path, preset: str, faults: list[dict], seconds: float = 1.5, drop=(), **extra):
    """Feed ``seconds`` of simulated sets (100/s, trajectory A) to a cycle; ``drop``: CAN ids whose frames are lost."""
    ids = SEVEN if preset == "reference7" else SEVEN[:6]
    config = service_config(tmp_path, [fixture(preset, ids, **extra)])
    sim = sim_config(config, [{"name": "left", "rate": 100.0, "trajectory": "A", "noise": 1e-6, "faults": faults}])
    cfg, hexa = config.fixture("left"), hexapod(preset)
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 1e9)
    bus = CollectingBus()
    simulator = Simulator(config, sim, bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    channel = {leg.can_id: k for k, leg in enumerate(cfg.legs)}
    if cfg.inclinometer is not None:
        channel[cfg.inclinometer.can_id] = len(cfg.legs)
    out = []
    for k in range(int(seconds * 100)):
        bus.sent.clear()
        sent = simulator.send_set(0, k / 100, stamp=1e9 + k / 100, stall_check=False)
        for msg in bus.sent:
            if msg.arbitration_id not in drop:
                rec = cycle.on_frame(channel[msg.arbitration_id], msg.data, msg.timestamp)
                if rec is not None:
                    out.append((sent, rec))
    return cycle, out


def test_the_configuration_must_name_every_reading_of_the_hexapod(tmp_path):
    cfg = service_config(tmp_path, [fixture("reference7", SEVEN[:6])]).fixture("left")
    with pytest.raises(ConfigError, match=r"can_ids.*expected 7 CAN ids.*leg7"):
        cfg.load_hexapod()
    cfg = service_config(tmp_path, [fixture("reference_tilt", SEVEN[:6])]).fixture("left")
    with pytest.raises(ConfigError, match=r"inclinometer.*configure its frame"):
        cfg.load_hexapod()
    cfg = service_config(tmp_path, [fixture("reference", SEVEN[:6], **TILT)]).fixture("left")
    with pytest.raises(ConfigError, match=r"has no inclinometer"):
        cfg.load_hexapod()
    assert service_config(tmp_path, [fixture("reference7", SEVEN)]).fixture("left").channels == 7


@pytest.mark.parametrize(
    ("table", "field", "words"),
    [
        ({"can_id": 0x1A0, "x_offset": 0, "y_offset": 2}, "inclinometer.y_offset", "overlaps"),
        ({"can_id": 0x1A0, "error_bit": 10}, "inclinometer.error_bit", "inside the count field"),
        ({"can_id": 0x1A0, "radians_per_count": 0}, "inclinometer.radians_per_count", "non-zero"),
        ({"can_id": 0x181}, "inclinometer.can_id", "duplicate CAN id"),
        ({}, "inclinometer.can_id", "missing"),
        ({"can_id": 0x1A0, "zero_counts": [1]}, "inclinometer.zero_counts", "two integers"),
    ],
)
def test_a_bad_inclinometer_table_is_one_line_naming_the_field(tmp_path, table, field, words):
    with pytest.raises(ConfigError) as info:
        service_config(tmp_path, [fixture("reference_tilt", SEVEN[:6], inclinometer=table)])
    assert field in info.value.field and words in info.value.reason and "\n" not in str(info.value)


def test_the_inclinometer_frame_carries_both_angles_to_one_count():
    cfg_codec = TiltCodec
    from hexapod_model.service.config.codec import FrameLayout

    x, y = FrameLayout("big", 0, 3, True, 1e-6, 48, None), FrameLayout("big", 3, 3, True, 1e-6, 48, None)
    codec = cfg_codec(0x1A0, x, y, (5, -7))
    msg = codec.message(0.0123456, -0.0456789, error=True)
    tx, ty, err, warn = codec.readings(msg.data)
    assert abs(tx - 0.0123456) <= 0.5e-6 and abs(ty + 0.0456789) <= 0.5e-6 and err and not warn


def test_a_seventh_leg_completes_the_set_and_an_offset_is_never_ok(tmp_path):
    cycle, clean = run(tmp_path, "reference7", [])
    ok = [(s, r) for s, r in clean if r.status == "ok"]
    assert len(ok) > 100 and len(clean) == 150  # one record a set of seven frames
    for sent, rec in ok:
        dp, dr = pose_error(rec, sent.pose)
        assert dp < 10e-6 and dr < 50e-6
    cycle, bad = run(tmp_path, "reference7", [{"kind": "step", "leg": 3, "size": 3e-4, "start": 0.5}])
    after = [r for s, r in bad if s.t_sim >= 0.5]
    assert after and all(r.status != "ok" for r in after)
    assert sum(r.status == "inconsistent_readings" for r in after) >= len(after) - 3
    assert all("inconsistent_readings" in r.flags for r in after if r.status == "inconsistent_readings")
    assert cycle.counters["inconsistent_sets"] >= len(after) - 3


def test_a_lost_seventh_frame_leaves_the_set_incomplete_naming_it(tmp_path):
    _, out = run(tmp_path, "reference7", [], seconds=0.3, drop={SEVEN[6]})
    assert out and all(r.status in ("incomplete", "silent_leg") for _, r in out)
    assert any("missing:leg7" in r.flags or "silent:leg7" in r.flags for _, r in out)
    _, out = run(tmp_path, "reference_tilt", [], seconds=0.3, drop={0x1A0}, **TILT)
    assert any("missing:inclinometer" in r.flags or "silent:inclinometer" in r.flags for _, r in out)


def test_the_inclinometer_names_the_faulty_leg_and_its_estimate_is_flagged(tmp_path):
    _, out = run(tmp_path, "reference_tilt", [{"kind": "step", "leg": 3, "size": 3e-4, "start": 0.5}], **TILT)
    after = [(s, r) for s, r in out if s.t_sim >= 0.5]
    flags = Counter(f for _, r in after for f in r.flags)
    assert flags["isolated:leg3"] >= len(after) - 3
    assert not any(f.startswith("isolated:") and f != "isolated:leg3" for f in flags)
    for sent, rec in after:
        assert rec.status != "ok"
        if rec.pose is not None:  # the pose of the others: an estimate near the truth
            assert "estimate" in rec.flags
            assert pose_error(rec, sent.pose)[0] < 50e-6


@pytest.mark.parametrize("preset", ["reference7", "reference_tilt"])
def test_the_records_carry_the_extra_readings_and_the_tests_statistic(tmp_path, preset):
    extra = TILT if preset == "reference_tilt" else {}
    fault = [{"kind": "step", "leg": 3, "size": 3e-4, "start": 0.5}]
    _, out = run(tmp_path, preset, fault, seconds=1.0, **extra)
    names = hexapod(preset).reading_names[6:]
    for sent, rec in out:
        assert rec.extra_readings is not None and tuple(rec.extra_readings) == names
        if rec.status not in ("ok", "flagged", "inconsistent_readings"):
            continue
        truth = hexapod(preset).redundancy.extra_readings(sent.pose)
        got = np.array([rec.extra_readings[n] for n in names])
        assert np.all(np.abs(got - truth) < 1e-4)  # m and rad: the simulated frames' values, noise and counts
        test = rec.consistency
        assert test is not None and test["dof"] == len(names) and test["alpha"] == 1e-3
        # the record's status is the test's verdict on its statistic
        assert (test["chi2"] > test["bound"]) == (rec.status == "inconsistent_readings"), (rec.status, test)
    failing = [rec for sent, rec in out if sent.t_sim >= 0.55 and rec.status == "inconsistent_readings"]
    assert failing and all(r.consistency["chi2"] > r.consistency["bound"] for r in failing)


def test_a_six_leg_fixtures_records_carry_no_extra_readings_and_no_test(tmp_path):
    config = service_config(tmp_path, [{"name": "left", "hexapod": "reference", "can_ids": SEVEN[:6]}])
    sim = sim_config(config, [{"name": "left", "rate": 100.0, "trajectory": "A"}])
    _, out = drive(config, sim, 0.3)
    assert out and all(r.extra_readings is None and r.consistency is None for _, r in out)
    assert any(r.status == "ok" for _, r in out)


def test_the_simulator_sends_the_extra_frames_from_the_true_pose_and_faults_any_reading(tmp_path):
    config = service_config(tmp_path, [fixture("reference_tilt", SEVEN[:6], **TILT)])
    fault = {"kind": "step", "reading": "tilt_x", "size": 1e-3, "start": 0.0}
    sim = sim_config(
        config, [{"name": "left", "rate": 100.0, "trajectory": "A", "noise": 0.0, "tilt_noise": 0.0, "faults": [fault]}]
    )
    hexa = hexapod("reference_tilt")
    bus = CollectingBus()
    simulator = Simulator(config, sim, bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    sent = simulator.send_set(0, 0.3, stamp=1e9, stall_check=False)
    assert len(bus.sent) == 7 and sent.readings.shape == (8,)
    assert np.allclose(sent.readings[6:], hexa.redundancy.extra_readings(sent.pose), atol=1e-12)
    codec = config.fixture("left").inclinometer
    tx, ty, _, _ = codec.readings(next(m for m in bus.sent if m.arbitration_id == 0x1A0).data)
    assert abs(tx - (sent.readings[6] + 1e-3)) <= 0.5e-6 and abs(ty - sent.readings[7]) <= 0.5e-6
    with pytest.raises(ConfigError, match="leg or reading"):
        sim_config(config, [{"name": "left", "hold": [0, 0, 0, 0, 0, 0], "faults": [{**fault, "leg": 2}]}])


@pytest.mark.slow
def test_the_service_gives_no_wrong_ok_with_a_seventh_leg_for_faults_above_the_detectable_size():
    spec = importlib.util.spec_from_file_location("redundancy_faults", ROOT / "benchmarks" / "redundancy_faults.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["redundancy_faults"] = module
    spec.loader.exec_module(module)
    seven = module.service_faults("reference7", 200)
    for case, c in seven["cases"].items():
        assert c["records"] >= 190, case
        assert c["wrong_ok_above"] == 0, (case, c)
    # the large offset: every set flagged, none ok
    assert seven["cases"]["offset 0.3"]["ok"] == 0


def test_the_inclinometer_frame_is_routed_to_its_cycle_after_the_legs(tmp_path):
    from hexapod_model.service.cycle.routes import frame_routes

    config = service_config(tmp_path, [fixture("reference_tilt", SEVEN[:6], **TILT)])
    cycle = type("Cycle", (), {"on_frame": None})()
    routes = frame_routes(config, {"left": cycle})  # type: ignore[dict-item]
    assert routes[False][0x1A0][0] is cycle and routes[False][0x1A0][2] == 6
    assert [routes[False][i][2] for i in SEVEN[:6]] == list(range(6))


@pytest.mark.slow
def test_the_service_routes_the_inclinometer_frame_and_health_and_log_name_the_leg(tmp_path, caplog):
    import time

    import can

    from hexapod_model.service import FixtureService

    config = service_config(tmp_path, [fixture("reference_tilt", SEVEN[:6], **TILT)])
    fault = {"kind": "step", "leg": 3, "size": 3e-4, "start": 0.3}
    sim = sim_config(config, [{"name": "left", "rate": 100.0, "trajectory": "A", "noise": 1e-6, "faults": [fault]}])
    hexa = hexapod("reference_tilt")
    records = []
    service = FixtureService(config, hexapods={"left": hexa})
    service.subscribe(records.append)
    caplog.set_level("INFO", logger="hexapod_model.service")
    service.start()
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    try:
        simulator = Simulator(config, sim, bus, hexapods={"left": hexa})
        wall = time.time()
        for k in range(50):
            simulator.send_set(0, k / 100, wall + k / 100, stall_check=False)
            end = time.monotonic() + 10.0
            while len(records) < k - 2 and time.monotonic() < end:
                time.sleep(0.002)
        end = time.monotonic() + 10.0
        while not (records and records[-1].t >= wall + 0.49) and time.monotonic() < end:
            time.sleep(0.01)
        health = service.health()
    finally:
        bus.shutdown()
        service.stop()
    before = [r for r in records if wall <= r.t < wall + 0.3 and r.status != "no_data"]
    after = [r for r in records if wall + 0.3 <= r.t < wall + 0.5]  # then silence: the simulator stopped
    assert before and all(r.status in ("ok", "flagged") for r in before)  # every frame, the inclinometer's too
    assert after and all(r.status == "inconsistent_readings" and "isolated:leg3" in r.flags for r in after)
    fixture_health = health["fixtures"]["left"]
    assert "isolated:leg3" in fixture_health["flags"] and fixture_health["counters"]["inconsistent_sets"] == len(after)
    assert any("inconsistent_readings" in p and "isolated:leg3" in p for p in health["problems"])
    assert any("inconsistent readings (isolated:leg3)" in m for m in caplog.messages)


@pytest.mark.parametrize(
    ("fault", "expected"),
    [
        ({"kind": "late_reading", "sets": 3}, lambda z, k, t: z[k - 3]),
        ({"kind": "creep", "size": 1e-4}, lambda z, k, t: z[k] + 1e-4 * t),
        ({"kind": "replay", "sets": 5, "size": 2e-5}, lambda z, k, t: z[k - 5] + 2e-5),
        ({"kind": "step", "size": 1e-4}, lambda z, k, t: z[k] + 1e-4),
    ],
)
def test_the_faults_six_readings_cannot_reveal_act_on_the_frames_to_the_end(tmp_path, fault, expected):
    config = service_config(tmp_path, [fixture("reference7", SEVEN)])
    sim = sim_config(
        config,
        [{"name": "left", "rate": 100.0, "trajectory": "A", "noise": 0.0, "faults": [{**fault, "leg": 7}]}],
    )
    bus = CollectingBus()
    simulator = Simulator(config, sim, bus, hexapods={"left": hexapod("reference7")})  # type: ignore[arg-type]
    leg7 = config.fixture("left").legs[6]
    truth, sent = [], []
    for k in range(250):  # 2.5 s: beyond the 1 s other faults last by default
        bus.sent.clear()
        truth.append(simulator.send_set(0, k / 100, stamp=1e9 + k / 100, stall_check=False).readings[6])
        frame = next(m for m in bus.sent if m.arbitration_id == leg7.can_id)
        assert frame.timestamp == pytest.approx(1e9 + k / 100 + 6 * 130e-6, abs=1e-9)  # stamped now
        sent.append(leg7.reading(leg7.layout.unpack(frame.data)[0]))
    for k in range(10, 250):
        assert abs(sent[k] - expected(truth, k, k / 100)) <= 0.51e-7, k  # to the count


@pytest.mark.parametrize("preset", ["reference7", "reference_tilt"])
def test_a_simulation_without_noise_given_simulates_the_noise_the_consistency_test_assumes(tmp_path, preset):
    ids = SEVEN if preset == "reference7" else SEVEN[:6]
    config = service_config(tmp_path, [fixture(preset, ids, **({} if preset == "reference7" else TILT))])
    sim = sim_config(config, [{"name": "left", "rate": 100.0, "trajectory": "A"}]).fixtures[0]
    sigmas = hexapod(preset).redundancy.sigmas
    assert sim.noise == sigmas[0]  # not the 10 um of a hexapod without redundant sensors: 10 sigma, an alarm a set
    if preset == "reference_tilt":
        assert sim.tilt_noise == sigmas[-1]
