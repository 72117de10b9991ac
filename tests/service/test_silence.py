"""Silence on the bus's time: frames on their way, a leg stamped ahead, a set being collected are no silence.

The service asks each cycle for silence between frames (``check_silence``) with the bus's time:
the stamp of the frame just handled, or the wall clock less the longest a frame waited lately.
A ``silent_leg`` record never names a leg whose frames come, and no record after it is older.
"""

from __future__ import annotations

import time

import numpy as np

from hexapod_model.service import FixtureCycle, Simulator, geometry_hash

from ..conftest import hexapod
from .helpers import CollectingBus, fixture_table, served, service_config, sim_config
from .test_cycle import RATE, check_ok_poses

T0 = 1.0e9
TICK = 0.025  # s: the service's check interval for a staleness of 0.05 s


def frames_of(tmp_path, sets, faults=()):
    """The frames of ``sets`` simulated sets (trajectory A, 100 Hz) as ``(leg, data, stamp)``, and the truth."""
    svc = service_config(tmp_path, [fixture_table()])
    sim = sim_config(svc, [{"name": "left", "rate": RATE, "trajectory": "A", "faults": list(faults)}])
    cfg, hexa = svc.fixtures[0], hexapod("reference")
    bus = CollectingBus()
    simulator = Simulator(svc, sim, bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    leg_of = {leg.can_id: k for k, leg in enumerate(cfg.legs)}
    frames, truth = [], []
    for k in range(sets):
        bus.sent.clear()
        truth.append(simulator.send_set(0, k / RATE, stamp=T0 + k / RATE, stall_check=False))
        frames.append([(leg_of[m.arbitration_id], bytes(m.data), m.timestamp) for m in bus.sent])
    return FixtureCycle(cfg, hexa, geometry_hash(hexa), None, T0), frames, truth


def with_truth(out, truth):
    """``(sent set, record)`` pairs for check_ok_poses: the set whose stamp the record's ``t`` names."""
    return [(truth[round((rec.t - T0) * RATE)], rec) for rec in out]


def test_a_silence_judged_while_sets_were_on_their_way_is_never_followed_by_an_older_record(tmp_path):
    cycle, frames, truth = frames_of(tmp_path, 200)
    out = []
    for k, frame_set in enumerate(frames):
        for frame in frame_set:
            rec = cycle.on_frame(*frame)
            if rec is not None:
                out.append(rec)
        if k == 100:  # sets 101-108 are still on their way when silence is judged at the stamp of set 108
            rec = cycle.check_silence(T0 + 1.08)
            assert rec is not None and rec.status == "silent_leg"
            out.append(rec)
    times = [rec.t for rec in out]
    assert all(b >= a for a, b in zip(times, times[1:])), "record times ran backwards"
    assert any(f.startswith("late_frame:") for rec in out for f in rec.flags)  # the frames that came too late
    assert out[-1].status == "ok"
    check_ok_poses(with_truth([rec for rec in out if rec.status == "ok"], truth))


def test_a_leg_stamped_ahead_is_no_silence_and_no_healthy_leg_is_blamed_while_frames_flow(tmp_path):
    # the service checks silence at each frame's stamp (every TICK): a set being collected, a frame held to see
    # whether it ran ahead, and the ahead leg's own frames are no silence; sets lost (30 %) do not change that
    ahead = [{"kind": "ahead_stamp", "leg": 4, "seconds": 0.05, "start": 1.0, "duration": 60}]
    cycle, frames, _ = frames_of(tmp_path, 300, ahead)
    lost = np.random.default_rng(4).random(300) < 0.3
    out, last_check = [], T0
    for k, frame_set in enumerate(frames):
        if lost[k] and k > 20:
            continue
        for frame in frame_set:
            rec = cycle.on_frame(*frame)
            if rec is not None:
                out.append(rec)
            clock = min(frame[2], T0 + k / RATE + 0.001)  # a stamp ahead of the wall clock has not come yet
            if clock - last_check >= TICK:
                last_check = clock
                rec = cycle.check_silence(clock)
                if rec is not None:
                    out.append(rec)
    later = [rec for rec in out if rec.t >= T0 + 1.1]
    assert later and not any(rec.status == "silent_leg" for rec in later), [
        (rec.t - T0, rec.flags) for rec in later if rec.status == "silent_leg"
    ][:3]
    for rec in later:
        assert {f.split(":")[1] for f in rec.flags if ":leg" in f} == {"leg4"}, rec.flags
    times = [rec.t for rec in out]
    assert all(b >= a for a, b in zip(times, times[1:])), "record times ran backwards"


class DelayedBus:
    """Frames due in real time, each set ``delay(k)`` s after its stamp (a gateway's or a late sender's delivery)."""

    def __init__(self, config, delay):
        sim = sim_config(config, [{"name": "left", "rate": RATE, "trajectory": "A"}])
        self.out = CollectingBus()
        self.sim = Simulator(config, sim, self.out, hexapods={"left": hexapod("reference")})  # type: ignore[arg-type]
        self.delay, self.k, self.queue, self.start = delay, 0, [], None

    def _due(self):
        now = time.time()
        if self.start is None:
            self.start = now
        while self.start + self.k / RATE + self.delay(self.k) <= now:
            self.out.sent.clear()
            self.sim.send_set(0, self.k / RATE, stamp=self.start + self.k / RATE, stall_check=False)
            self.queue += self.out.sent
            self.k += 1

    def recv(self, timeout=None):
        self._due()
        deadline = time.time() + (timeout or 0.0)
        while not self.queue and time.time() < deadline:
            time.sleep(0.001)
            self._due()
        return self.queue.pop(0) if self.queue else None

    def shutdown(self):
        pass


def test_frames_delivered_up_to_48_ms_after_their_stamps_are_no_silent_leg_through_the_service(tmp_path):
    # staleness 0.05 s: every fourth set comes 48 ms late (the next ones queue behind it), the others at once;
    # the wall clock ran ahead of the frames on their way, which read as a silent fixture
    config = service_config(tmp_path)
    records, _ = served(config, DelayedBus(config, lambda k: 0.048 if k % 4 == 0 else 0.001), 2.5)
    assert sum(r.status == "ok" for r in records) > 100
    assert not any(r.status == "silent_leg" for r in records), [r.flags for r in records if r.status == "silent_leg"]
    times = [r.t for r in records]
    assert all(b >= a for a, b in zip(times, times[1:])), "record times ran backwards"


def test_no_leg_is_silent_before_staleness_has_passed_since_the_cycle_began_listening(tmp_path):
    # the service builds its cycles, warms the kernels up (up to a minute after installation), then reads the bus
    cycle, frames, _ = frames_of(tmp_path, 3)
    cycle.listen(T0 + 2.0)
    assert cycle.check_silence(T0 + 2.04) is None
    rec = cycle.check_silence(T0 + 2.06)
    assert rec is not None and rec.status == "silent_leg" and len(rec.flags) == 6, rec


class ListeningBus(DelayedBus):
    """A DelayedBus whose first set is due after the service began listening (the warm-up's drain reads nothing)."""

    def recv(self, timeout=None):
        if self.start is None and not timeout:
            return None
        return super().recv(timeout)


def test_the_warm_up_before_the_first_frame_is_no_silence_through_the_service(tmp_path):
    # the first set comes 45 ms after the cycle began reading, within the staleness of 0.05 s; the service's
    # warm-up before it took longer than that, and its time was judged as the legs' silence
    config = service_config(tmp_path)
    bus = ListeningBus(config, lambda k: 0.045 if k == 0 else 0.001)
    records, service = served(config, bus, 0.6)
    assert bus.start is not None and bus.start - service.started > 0.05  # the warm-up took longer than staleness
    assert sum(r.status == "ok" for r in records) > 10
    assert not any(r.status == "silent_leg" for r in records), [r.flags for r in records if r.status == "silent_leg"]


def test_the_loops_wait_is_half_the_shortest_staleness_within_its_bounds(tmp_path):
    """``bus_wait``: half the shortest staleness of the fixtures, never under 2 ms nor over 50 ms."""
    from hexapod_model.service.service import bus_wait

    def wait(*stale: float) -> float:
        tables = [fixture_table(f"f{i}", i, staleness=s) for i, s in enumerate(stale)]
        return bus_wait(service_config(tmp_path, tables))

    assert wait(0.05) == TICK and wait(0.05, 0.02) == 0.01
    assert wait(1e-3) == 0.002 and wait(10.0) == 0.05
