"""A fixture's cycle turns frames into records holding the interpreter lock throughout (:mod:`tests.lock_watch`).

The service's HTTP, store and main threads wait for the lock; a release in the cycle's per-set
work (decoding, set assembly, the tracker step, the detectors, the record) would wake one of
them at every set and slow the cycle (docs/service.md).
"""

from __future__ import annotations

from hexapod_model.service import FixtureCycle, Simulator, geometry_hash

from ..conftest import hexapod
from ..lock_watch import LockWatch
from .helpers import CollectingBus, fixture_table, service_config, sim_config

RATE = 100.0


def test_the_cycle_never_releases_the_interpreter_lock(tmp_path):
    svc = service_config(tmp_path, [fixture_table()])
    sim = sim_config(svc, [{"name": "left", "rate": RATE, "trajectory": "A", "faults": []}])
    cfg, hexa = svc.fixtures[0], hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 1.0e9)
    bus = CollectingBus()
    simulator = Simulator(svc, sim, bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    leg_of = {leg.can_id: k for k, leg in enumerate(cfg.legs)}
    for k in range(200):  # the frames of 2 s of sets, made before the watch
        simulator.send_set(0, k / RATE, stamp=1.0e9 + k / RATE, stall_check=False)
    frames = [(leg_of[m.arbitration_id], bytes(m.data), m.timestamp) for m in bus.sent]
    half = len(frames) // 2
    warm = [cycle.on_frame(*f) for f in frames[:half]]  # settled: kernels loaded, the tracker warm
    with LockWatch() as watch:
        records = [cycle.on_frame(*f) for f in frames[half:]]
        ran = watch.ran
    published = [r for r in records if r is not None]
    assert [r for r in warm if r is not None] and len(published) >= 95
    assert all(r.status == "ok" for r in published)
    assert ran == 0, f"another thread ran {ran} times during the sets: the cycle released the lock"
