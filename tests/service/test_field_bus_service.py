"""The bus as the field has it, through FixtureService on the virtual bus: no false latch, no wrong name."""

from __future__ import annotations

import time

import can
import numpy as np
import pytest

from hexapod_model.service import FixtureService, Simulator

from ..conftest import hexapod
from .helpers import fixture_table, pose_error, service_config, sim_config


def serve(tmp_path, faults, seconds=4.0, table=None, settle=0.2):
    """Run the service with one simulated fixture (100 Hz, trajectory A; ``table``: its fixture table).

    Returns the records, the cycle and the simulator (its ``truth``).
    """
    config = service_config(tmp_path, None if table is None else [table])
    sim = sim_config(config, [{"name": "left", "rate": 100.0, "trajectory": "A", "faults": faults}])
    records = []
    hexa = hexapod("reference")
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    service = FixtureService(config, hexapods={"left": hexa}, http=False)
    service.subscribe(records.append)
    try:
        service.start()
        simulator = Simulator(config, sim, bus, hexapods={"left": hexa})
        simulator.run(seconds)
        time.sleep(settle)
        cycle = service.cycles["left"]
    finally:
        service.stop()
        bus.shutdown()
    return records, cycle, simulator


def sent_at(simulator, t):
    """The simulated set whose newest frame is stamped ``t`` (a record's time), within a quarter period.

    A record's ``t`` is its set's newest frame's stamp, ``t_last`` (six frames after the set's own
    stamp ``t_first``): rounding it to the 10 ms grid named the next set whenever a run started near
    half a period.
    """
    last = np.array([s.t_last for s in simulator.truth])
    i = int(np.argmin(np.abs(last - t)))
    assert abs(last[i] - t) < 0.25 / 100.0, (t, last[i])
    return simulator.truth[i]


@pytest.mark.parametrize(
    "fault",
    [
        {"kind": "lost_sets", "probability": 0.3, "start": 0.3, "duration": 60},
        {"kind": "repeated_frames", "sets": 10, "start": 0.3, "duration": 60},
        [  # two consecutive one-frame glitches on one leg
            {"kind": "spike", "leg": 4, "start": 1.0, "size": 0.002},
            {"kind": "spike", "leg": 4, "start": 1.01, "size": -0.0015},
        ],
    ],
)
def test_lost_sets_repeated_frames_and_glitches_latch_nothing(tmp_path, fault):
    records, cycle, _ = serve(tmp_path, fault if isinstance(fault, list) else [fault])
    assert cycle.fault is None, cycle.fault
    assert sum(r.status == "ok" for r in records) > 150
    if isinstance(fault, dict) and fault["kind"] == "repeated_frames":
        assert cycle.counters["repeated_frames"] > 9 * 6 * 150


def test_a_leg_stamped_50_ms_ahead_is_the_one_named_and_no_record_runs_ahead(tmp_path):
    ahead = {"kind": "ahead_stamp", "leg": 4, "seconds": 0.05, "start": 1.0, "duration": 60}
    records, cycle, _ = serve(tmp_path, [ahead])
    assert cycle.fault is None, cycle.fault
    times = [r.t for r in records]
    assert all(b >= a for a, b in zip(times, times[1:])), "record times ran backwards"
    later = [r for r in records if r.t >= records[0].t + 1.2]
    assert later and not any(r.status == "ok" for r in later)
    for r in later:
        if r.status == "silent_leg" and len(r.flags) == 6:  # the simulator's thread stalled: every leg was silent
            continue
        assert {f.split(":")[1] for f in r.flags if ":leg" in f} == {"leg4"}, r.flags
    assert cycle.counters["ahead_frames"] > 100


def test_a_batching_gateway_gives_no_wrong_ok_through_the_service(tmp_path):
    fault = {"kind": "gateway_burst", "sets": 5, "start": 0.0, "duration": 60}
    records, _, _ = serve(tmp_path, [fault], seconds=3.0)
    assert len(records) > 100
    assert not any(r.status == "ok" for r in records), [r.flags for r in records if r.status == "ok"][:3]
    assert sum("batched_stamps" in r.flags for r in records) > 100


def test_a_batching_gateway_with_the_sampling_period_given_gives_right_poses_through_the_service(tmp_path):
    table = fixture_table(encoder={"sample_period": 0.01}, staleness=0.2)  # staleness: longer than a burst's span
    fault = {"kind": "gateway_burst", "sets": 5, "start": 0.0, "duration": 60}
    records, _, simulator = serve(tmp_path, [fault], seconds=3.0, table=table, settle=0.3)
    ok = [r for r in records if r.status == "ok"]
    assert len(ok) > 150, sorted({(r.status, tuple(r.flags)) for r in records})[:10]
    for r in ok:  # the pose of the instant its t names
        dp, _ = pose_error(r, sent_at(simulator, r.t).pose)
        assert dp < 5 * r.sigma["translation_mm"] * 1e-3, (r.t, dp)


def test_bit_flips_and_an_intruder_on_a_checked_layout_give_no_wrong_ok_through_the_service(tmp_path):
    encoder = {"error_bit": 32, "warning_bit": 33, "counter": {"offset": 40, "bits": 4}, "crc": {"offset": 7}}
    faults = [
        {"kind": "bit_flip", "probability": 0.01, "start": 0.3, "duration": 60},
        {"kind": "intruder", "leg": 2, "size": 0.0003, "start": 1.5, "duration": 1.0},
    ]
    records, cycle, simulator = serve(tmp_path, faults, seconds=3.5, table=fixture_table(encoder=encoder))
    ok = [r for r in records if r.status == "ok"]
    assert len(ok) > 100, (cycle.fault, sorted({(r.status, tuple(r.flags)) for r in records})[:12])
    for r in ok:
        dp, _ = pose_error(r, sent_at(simulator, r.t).pose)
        assert dp < 5 * r.sigma["translation_mm"] * 1e-3, (r.t, dp, r.flags)
    assert cycle.counters["bad_crc"] > 3 and cycle.counters["counter_gap"] > 30
    assert any("bad_crc:leg" in f for r in records for f in r.flags)
