"""FixtureService on python-can's virtual bus (this process only) with simulated encoders and HTTP on 127.0.0.1."""

from __future__ import annotations

import bisect
import json
import time
import urllib.error
import urllib.request

import can
import numpy as np
import pytest

from hexapod_model.service import RECORD_KEYS, FixtureService, Simulator, Store

from ..conftest import hexapod
from .helpers import fixture_table, pose_error, service_config, sim_config


def get(address, path):
    host, port = address
    assert host == "127.0.0.1"
    try:
        with urllib.request.urlopen(f"http://{host}:{port}{path}", timeout=5) as r:
            return r.status, json.load(r)
    except urllib.error.HTTPError as e:
        return e.code, json.load(e)


def run_service(config, sim, seconds, hexapods):
    """Start the service and the simulator on the same virtual channel; returns (records, truth, http answers)."""
    records = []
    service = FixtureService(config, hexapods=hexapods)
    service.subscribe(records.append)
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    answers = {}
    try:
        service.start()
        simulator = Simulator(config, sim, bus, hexapods=hexapods)
        simulator.start()
        time.sleep(seconds)
        for path in ("/fixtures", "/fixtures/left/pose", "/fixtures/nope/pose", "/health", "/other"):
            answers[path] = get(service.address, path)
        simulator.stop()
    finally:
        service.stop()
        bus.shutdown()
    return records, list(simulator.truth), answers


def truth_of(truth, fixture, t):
    """The simulated set whose frames were sent around ``t`` (the record's newest frame time)."""
    sets = [s for s in truth if s.fixture == fixture]
    k = bisect.bisect_right([s.t_first for s in sets], t) - 1
    return sets[k] if k >= 0 and sets[k].t_first <= t <= sets[k].t_last else None


def test_end_to_end_poses_equal_the_truth_within_sigma_over_http_and_subscribers(tmp_path):
    config = service_config(tmp_path, [fixture_table("left"), fixture_table("right", 1, home_counts=50_000)])
    sim = sim_config(
        config,
        [
            {"name": "left", "rate": 200.0, "trajectory": "A", "period": 6.0},
            {"name": "right", "rate": 50.0, "hold": [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]},
        ],
    )
    hexapods = {"left": hexapod("reference"), "right": hexapod("reference")}
    records, truth, answers = run_service(config, sim, 3.0, hexapods)
    good = [r for r in records if r.status == "ok"]
    assert len([r for r in good if r.fixture == "left"]) > 200 and len([r for r in good if r.fixture == "right"]) > 50
    # silent only before the encoders start, unless this busy machine stalled the simulator
    assert len(good) >= 0.9 * len(records), {r.status for r in records}
    ratios = []
    for r in good:
        sent = truth_of(truth, r.fixture, r.t)
        assert sent is not None, r.t
        dp, dr = pose_error(r, sent.pose)
        ratios.append((dp / (r.sigma["translation_mm"] * 1e-3), dr / np.radians(r.sigma["rotation_deg"])))
    ratios = np.array(ratios)
    assert ratios.max() < 5.0 and 0.5 < np.mean(ratios**2) < 1.6, (ratios.max(0), np.mean(ratios**2, 0))
    code, body = answers["/fixtures"]
    assert code == 200 and body == {"fixtures": ["left", "right"]}
    code, body = answers["/fixtures/left/pose"]
    assert code == 200 and tuple(body) == RECORD_KEYS and body["fixture"] == "left" and body["status"] == "ok"
    assert set(body["pose"]) == {"x", "y", "z", "qx", "qy", "qz", "qw", "roll", "pitch", "yaw"}
    assert set(body["sigma"]) == {"translation_mm", "rotation_deg"}
    assert answers["/fixtures/nope/pose"][0] == 404 and answers["/other"][0] == 404
    code, body = answers["/health"]
    assert code == 200 and body["fixtures"]["right"]["state"] == "locked" and body["frames"] > 1000
    assert body["fixtures"]["right"]["stored"] is True and body["store"]["error"] is None
    right = [r for r in records if r.fixture == "right"]
    locking = next(k for k, r in enumerate(right) if r.state == "locked")
    first_stored = next(k for k, r in enumerate(right) if r.stored)
    # the locking record is published, then committed: stored only from a later record on (the
    # next one, unless the commit took longer than a set period on a busy machine)
    assert locking < first_stored and all(r.state == "locked" for r in right[locking:first_stored])
    with Store(config.store.path, create=False) as store:
        events = store.locks("right")
        assert [e.t for e in events] == [right[locking].t]
        assert 0 < len(store.samples()) <= len(records)


def test_start_compiles_before_reading_and_drops_the_frames_queued_meanwhile(tmp_path, caplog):
    # the kernels compile (a minute after installation) in start(), before the cycle reads a frame;
    # frames that arrived meanwhile are old: dropped and counted, not solved late
    config = service_config(tmp_path, [fixture_table("left")])
    channel = config.bus.channel
    service_bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
    sender = can.Bus(interface="virtual", channel=channel)
    service = FixtureService(config, bus=service_bus, http=False, hexapods={"left": hexapod("reference")})
    try:
        for can_id in config.fixtures[0].legs[0].can_id, config.fixtures[0].legs[1].can_id:
            sender.send(can.Message(arbitration_id=can_id, data=bytes(8), is_extended_id=False))
        caplog.set_level("INFO", logger="hexapod_model.service.service")
        service.start()
        time.sleep(0.3)
        assert service.frames == 0 and service.unknown_frames == 0
        assert any("2 frames received meanwhile dropped" in m for m in caplog.messages), caplog.messages
    finally:
        service.stop()
        sender.shutdown()
        service_bus.shutdown()


def test_restart_recovers_the_last_lock_or_says_why_not(tmp_path):
    config = service_config(tmp_path, [fixture_table("left", lock_time=0.2)])
    hold = {"name": "left", "rate": 100.0, "hold": [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]}
    hexapods = {"left": hexapod("reference")}
    records, _, _ = run_service(config, sim_config(config, [hold]), 1.0, hexapods)
    with Store(config.store.path, create=False) as store:
        last = store.last_lock("left")
    assert last is not None
    records, _, answers = run_service(config, sim_config(config, [hold]), 0.6, hexapods)
    health = answers["/health"][1]["fixtures"]["left"]
    assert health["recovered_t"] == last.t and "initial guess" in health["recovery"]
    good = [r for r in records if r.status == "ok"]
    assert good[0].state == "locked" and good[0].stored and "moved_while_off" not in good[0].flags
    other = service_config(tmp_path, [fixture_table("left", hexapod="intersecting")], channel=config.bus.channel)
    records, _, answers = run_service(other, sim_config(other, [hold]), 0.6, {"left": hexapod("intersecting")})
    health = answers["/health"][1]["fixtures"]["left"]
    assert health["recovered_t"] is None and "another geometry" in health["recovery"]
    assert all("stored_geometry_changed" in r.flags for r in records if r.status == "ok")


def test_non_get_methods_are_refused(tmp_path):
    config = service_config(tmp_path)
    with FixtureService(config, bus=can.Bus(interface="virtual", channel=config.bus.channel)) as service:
        host, port = service.address
        req = urllib.request.Request(f"http://{host}:{port}/fixtures", data=b"{}", method="POST")
        with pytest.raises(urllib.error.HTTPError) as info:
            urllib.request.urlopen(req, timeout=5)
        assert info.value.code == 405


def test_stop_before_the_cycle_thread_started_is_clean(tmp_path):
    """Ctrl-C between creating the cycle thread and starting it: stop() must not raise."""
    import threading

    from hexapod_model.service import service as service_module

    svc = service_config(tmp_path, [fixture_table()])
    service = service_module.FixtureService(svc)
    service._thread = threading.Thread(target=lambda: None)  # created, not started
    service.stop()
    assert service._thread is None


def test_stop_before_the_preparation_thread_started_is_clean(tmp_path):
    """Ctrl-C between creating the preparation thread (``start(wait=False)``) and starting it."""
    import threading

    from hexapod_model.service import service as service_module

    service = service_module.FixtureService(service_config(tmp_path, [fixture_table()]))
    service._preparing = threading.Thread(target=lambda: None)  # created, not started
    service.stop()  # a RuntimeError (join of a thread not started) was the process's exit 1
    assert not service.preparing


def test_simulator_stop_before_its_thread_started_is_clean(tmp_path):
    import threading

    svc = service_config(tmp_path, [fixture_table()])
    sim = Simulator(svc, sim_config(svc, [{"name": "left", "rate": 100.0, "trajectory": "A"}]), None)
    sim._thread = threading.Thread(target=lambda: None)  # created, not started (Ctrl-C in between)
    sim.stop()
    assert sim._thread is None


def test_http_answers_503_starting_while_preparing_and_stop_is_prompt(tmp_path, monkeypatch):
    import threading

    from hexapod_model.service import service as service_module

    release = threading.Event()
    monkeypatch.setattr(service_module, "warm_up", lambda *args: release.wait(30))  # a long first compile
    config = service_config(tmp_path)
    bus = can.Bus(interface="virtual", channel=config.bus.channel)
    service = FixtureService(config, bus=bus, hexapods={"left": hexapod("reference")})
    try:
        service.start(wait=False)
        code, body = get(service.address, "/health")
        assert code == 503 and body["status"] == "starting" and body["phase"] != "running"
        assert get(service.address, "/fixtures/left/pose")[0] == 503
        t0 = time.monotonic()
        service.stop()
        assert time.monotonic() - t0 < 2.0 and service.preparing
        release.set()
        service._preparing.join(10)
        assert not service.preparing and service.store is None and not service.ready
    finally:
        release.set()
        service.stop()
        bus.shutdown()


def test_health_does_not_show_the_store_path(tmp_path):
    config = service_config(tmp_path)
    with FixtureService(config, bus=can.Bus(interface="virtual", channel=config.bus.channel), http=False) as svc:
        health = svc.health()
    assert health["store"]["file"] == "store.sqlite" and str(tmp_path) not in json.dumps(health)


def test_a_health_section_with_an_error_degrades_the_service(tmp_path):
    config = service_config(tmp_path)
    with FixtureService(config, bus=can.Bus(interface="virtual", channel=config.bus.channel), http=False) as svc:
        svc.health_sections["bridge"] = lambda: {"error": "peer gone", "sent": 3}
        health = svc.health()
    assert health["status"] == "degraded" and "bridge: peer gone" in health["problems"]
    assert health["bridge"] == {"error": "peer gone", "sent": 3}


def test_fixtures_naming_one_hexapod_share_its_model_and_sensitivity_buffers(tmp_path):
    """Two fixtures of one geometry file: one Hexapod and one evaluator (~6 MB and ~3 MB a fixture otherwise)."""
    config = service_config(tmp_path, [fixture_table("left"), fixture_table("right", 1)])
    with FixtureService(config, bus=can.Bus(interface="virtual", channel=config.bus.channel), http=False) as service:
        assert service.hexapods["left"] is service.hexapods["right"]
        left, right = (service.cycles[name].solver for name in ("left", "right"))
        assert left.tracker._sens is right.tracker._sens is left._sens
        assert left.tracker is not right.tracker
