"""Sets held for solving back to back (``FixtureCycle.hold_sets``): the same records, in order, none lost."""

from __future__ import annotations

import queue
import threading
import time

import can
import numpy as np
import pytest

from hexapod_model.service import FixtureCycle, FixtureService, PoseRecord, geometry_hash

from ..conftest import hexapod
from .helpers import fixture_table, service_config

RATE = 100.0  # sets per second
SPACING = 130e-6  # s between two frames of a set


def frames(cfg, sets: int, t0: float, rise: float = 1e-4) -> list[tuple[int, can.Message, float]]:
    """``(leg, message, stamp)`` of ``sets`` sets of a fixture rising ``rise`` m a set on every leg."""
    out = []
    for k in range(sets):
        for j, leg in enumerate(cfg.legs):
            out.append((j, leg.message(rise * k), t0 + k / RATE + j * SPACING))
    return out


def same(a: PoseRecord, b: PoseRecord) -> bool:
    """Two records of one code path: equal field by field (poses bit for bit)."""
    return (a.fixture, a.t, a.readings, a.pose, a.status, a.flags, a.iterations, a.state, a.sigma) == (
        b.fixture,
        b.t,
        b.readings,
        b.pose,
        b.status,
        b.flags,
        b.iterations,
        b.state,
        b.sigma,
    )


def direct_records(cfg, stream, t0: float) -> list[PoseRecord]:
    """What a cycle that does not hold sets publishes for ``stream``."""
    hexa = hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, t0)
    cycle.listen(t0)
    out = []
    for leg, msg, t in stream:
        rec = cycle.on_frame(leg, msg.data, t)
        if rec is not None:
            out.append(rec)
    return out


def test_a_held_set_is_published_as_at_once_by_finish_held_the_next_frame_or_the_silence_check(tmp_path):
    cfg = service_config(tmp_path).fixtures[0]
    t0 = 1.0e9
    stream = frames(cfg, 30, t0)
    expected = direct_records(cfg, stream, t0)
    assert len(expected) == 30 and sum(r.pose is not None for r in expected) >= 25

    hexa = hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, t0)
    cycle.listen(t0)
    cycle.hold_sets = True
    got = []
    for n, (leg, msg, t) in enumerate(stream):
        rec = cycle.on_frame(leg, msg.data, t)
        if rec is not None:
            got.append(rec)
        if leg == len(cfg.legs) - 1:  # the set is complete: held, nothing published yet
            assert rec is None and cycle.holding
            if (n // len(cfg.legs)) % 2 == 0:  # half of them finished by the caller, half by the next frame
                got.append(cycle.finish_held())
                assert not cycle.holding and cycle.finish_held() is None
    assert cycle.holding  # the last set: the silence check publishes it before judging silence
    last = cycle.check_silence(stream[-1][2] + 0.001)
    assert last is not None and not cycle.holding
    got.append(last)
    assert len(got) == len(expected)
    assert all(same(a, b) for a, b in zip(got, expected, strict=True))
    assert cycle.last is got[-1]


def test_a_cycle_that_does_not_hold_sets_publishes_at_the_completing_frame(tmp_path):
    cfg = service_config(tmp_path).fixtures[0]
    hexa = hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 1.0e9)
    records = [cycle.on_frame(leg, msg.data, t) for leg, msg, t in frames(cfg, 3, 1.0e9)]
    assert [r is not None for r in records] == [False] * 5 + [True] + [False] * 5 + [True] + [False] * 5 + [True]
    assert not cycle.holding and cycle.finish_held() is None


@pytest.mark.parametrize("fixtures", [1, 2])
def test_a_service_publishes_every_set_once_in_order_as_a_cycle_alone_would(tmp_path, monkeypatch, fixtures):
    """Several fixtures' frames queued at once: their sets are held and solved back to back, one record each."""
    finished = []
    finish_held = FixtureCycle.finish_held

    def counted(cycle: FixtureCycle) -> PoseRecord | None:
        rec = finish_held(cycle)
        finished.append(rec is not None)
        return rec

    monkeypatch.setattr(FixtureCycle, "finish_held", counted)
    tables = [fixture_table("left"), fixture_table("right", 1)][:fixtures]
    config = service_config(tmp_path, tables)
    sets = 40
    records: list[PoseRecord] = []
    done = threading.Event()

    def on_record(rec: PoseRecord) -> None:
        if rec.status not in ("no_data", "silent_leg"):
            records.append(rec)
            if len(records) == sets * fixtures:
                done.set()

    bus = can.Bus(interface="virtual", channel=config.bus.channel)
    receiving = bus.queue
    hexa = hexapod("reference")
    service = FixtureService(config, bus=bus, hexapods={f.name: hexa for f in config.fixtures}, http=False)
    service.subscribe(on_record)
    try:
        service.start()
        assert all(c.hold_sets == (fixtures > 1) for c in service.cycles.values())
        t0 = time.time() + 0.2
        streams = {f.name: frames(f, sets, t0) for f in config.fixtures}
        # the frames of every period queued before the service reads them (a virtual bus's send
        # would stamp them with its clock): each period, every fixture's frames in turn
        full: queue.Queue = queue.Queue()
        for k in range(sets):
            for f in config.fixtures:
                for _, msg, t in streams[f.name][6 * k : 6 * k + 6]:
                    msg.timestamp = t
                    full.put(msg)
        bus.queue = full  # the cycle thread's next read takes from it
        assert done.wait(60.0), f"{len(records)} of {sets * fixtures} records"
    finally:
        service.stop()
        bus.queue = receiving
        bus.shutdown()
    assert len(records) == sets * fixtures  # none lost, none twice (after the stop too)
    assert sum(finished) == (sets * fixtures if fixtures > 1 else 0)  # several fixtures: every set held
    for f in config.fixtures:
        mine = [r for r in records if r.fixture == f.name]
        expected = direct_records(f, streams[f.name], service.started)
        assert len(mine) == sets and all(a.t < b.t for a, b in zip(mine, mine[1:]))
        assert [(r.t, r.status, r.pose) for r in mine] == [(r.t, r.status, r.pose) for r in expected]
        assert np.isfinite(mine[-1].pose["z"])
