"""A stalled service is not a fault of the fixture: bus time, not the service's own delays, judges silence."""

from __future__ import annotations

import time

from hexapod_model.service import Simulator

from ..conftest import hexapod
from .helpers import CollectingBus, served, service_config, sim_config


class StallingBus:
    """A bus whose frames come due in real time; once, ``recv`` returns nothing and the thread stalls 0.2 s."""

    def __init__(self, config, rate=100.0):
        sim = sim_config(config, [{"name": "left", "rate": rate, "trajectory": "A"}])
        self.out = CollectingBus()
        self.sim = Simulator(config, sim, self.out, hexapods={"left": hexapod("reference")})  # type: ignore[arg-type]
        self.rate, self.k, self.queue = rate, 0, []
        self.start = None
        self.stalled = False

    def _due(self):
        now = time.time()
        if self.start is None:
            self.start = now
        while self.start + self.k / self.rate <= now:
            self.out.sent.clear()
            self.sim.send_set(0, self.k / self.rate, stamp=self.start + self.k / self.rate, stall_check=False)
            self.queue += self.out.sent
            self.k += 1

    def recv(self, timeout=None):
        self._due()
        if not self.stalled and self.start is not None and time.time() - self.start > 1.0:
            self.stalled = True  # the queue was empty at the deadline; then the thread was not run for 0.2 s
            time.sleep(0.2)
            return None
        if self.queue:
            return self.queue.pop(0)
        time.sleep(min(timeout or 0.0, 0.001))
        self._due()
        return self.queue.pop(0) if self.queue else None

    def shutdown(self):
        pass


def test_a_stall_of_the_service_thread_is_no_silent_leg(tmp_path):
    config = service_config(tmp_path)
    bus = StallingBus(config)
    records, _ = served(config, bus, 2.0)
    assert bus.stalled
    assert not any(r.status == "silent_leg" for r in records), [r.flags for r in records if r.status == "silent_leg"]


class BacklogBus(StallingBus):
    """The service thread gets the CPU back 0.5 s late at every frame: a queue that never empties."""

    def recv(self, timeout=None):
        self._due()
        if timeout == 0.0:  # the start's drain: what is there now
            return self.queue.pop(0) if self.queue else None
        while not self.queue:
            time.sleep(0.001)
            self._due()
        time.sleep(max(0.0, self.queue[0].timestamp + 0.5 - time.time()))
        self._due()
        return self.queue.pop(0)


def test_a_service_behind_the_bus_says_service_overloaded_and_blames_no_leg(tmp_path):
    config = service_config(tmp_path)
    records, health = served(config, BacklogBus(config), 2.0, lambda service: service.health())
    assert any(p.startswith("service_overloaded: ") for p in health["problems"]), health["problems"]
    assert health["lag_s"] > 0.25
    assert not any(r.status == "silent_leg" for r in records)
    assert sum(r.status == "ok" for r in records) > 50
