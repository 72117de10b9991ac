"""The fixture pose service: one CAN bus in, per-fixture cycles, records out (HTTP, subscribers, store).

>>> from hexapod_model.service import FixtureService, load_config
>>> with FixtureService(load_config("fixture.toml")) as svc:   # doctest: +SKIP
...     svc.subscribe(print)          # every published record (a PoseRecord)
...     svc.record("left")            # the latest one; also GET /fixtures/left/pose

Threads: one reads the bus and runs every fixture's cycle (a record is published within the
frame's own iteration; with several fixtures, once no frame waits on the bus, or within 2 ms:
the sets completed meanwhile are solved back to back), one writes the store
(:class:`~hexapod_model.service.store.writer.StoreWriter`), and the HTTP server's. Subscribers run
on the bus thread: keep them short.
"""

from __future__ import annotations

import gc
import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from functools import partial
from typing import TYPE_CHECKING

import can

from ..analysis.sensitivity import SensitivityEvaluator
from ..tracking.tracker import characteristic_length
from .changeover.changeover import Changeover
from .config.settings import ServiceConfig, geometry_hash
from .cycle.alarms import Acknowledgement
from .cycle.bus import open_bus
from .cycle.fixture_cycle import FixtureCycle
from .cycle.routes import frame_routes
from .cycle.solver import warm_up
from .errors import ServiceError
from .http.health import health
from .record.pose_record import PoseRecord
from .store.fixture_store import Store, sample_row
from .store.owner import StoreOwner
from .store.writer import StoreWriter
from .threads import NamedThread

if TYPE_CHECKING:
    from starlette.routing import BaseRoute

    from ..kinematics.hexapod import Hexapod
    from .changeover.plan_monitor import PlanMonitor
    from .http.server import HttpServer

log = logging.getLogger(__name__)
TRANSIT_WINDOW = 1.0  # s: silence is judged allowing for the longest wait of a frame over this long
HOLD_LIMIT = 0.002  # s: a complete set waits at most this long for the frames queued behind it (_loop)


def bus_wait(config: ServiceConfig) -> float:
    """How long (s) the service's loop waits for a frame before it checks the fixtures for silence.

    Half the shortest ``staleness`` of the fixtures, within 2 ms and 50 ms: a silent leg is
    reported within half its staleness, and a quiet bus wakes the loop no more often than that.
    """
    return min(0.05, max(0.002, min(f.staleness for f in config.fixtures) / 2))


class FixtureService:
    """Run the pose service of every fixture of ``config``.

    Args:
        config: the validated configuration (:func:`~hexapod_model.service.config.settings.load_config`).
        bus: an open python-can bus to read instead of the configured one (it is not closed here).
        http: serve ``GET /fixtures``, ``/fixtures/NAME/pose`` and ``/health`` on ``config.http``.
        hexapods: already loaded hexapods by fixture name (else loaded from the configuration).

    Raises:
        ConfigError: a fixture's hexapod cannot be loaded.
    """

    def __init__(
        self,
        config: ServiceConfig,
        bus: can.BusABC | None = None,
        http: bool = True,
        hexapods: dict[str, Hexapod] | None = None,
        routes: Sequence[BaseRoute] = (),
    ):
        self.config = config
        #: the fixtures' hexapods, by name: those given, the others loaded by :meth:`start`
        self.hexapods = {f.name: hexapods[f.name] for f in config.fixtures if hexapods and f.name in hexapods}
        self._bus, self._own_bus, self._http = bus, bus is None, http
        self._extra_routes = list(routes)
        self._lock = threading.Lock()
        self._ready = threading.Event()
        self._preparing: threading.Thread | None = None
        #: what the service does while starting (``/health`` says it with ``503 starting``)
        self.phase = "starting"
        #: the error that stopped a background start (``start(wait=False)``), else None
        self.failure: Exception | None = None
        self._subscribers: list[Callable[[PoseRecord], None]] = []
        #: more ``/health`` sections by name, each a dict (one whose ``error`` is not None: ``degraded``)
        self.health_sections: dict[str, Callable[[], dict]] = {}
        self._json: dict[str, tuple[PoseRecord, str]] = {}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.cycles: dict[str, FixtureCycle] = {}
        self.endpoint: HttpServer | None = None
        self.store: Store | None = None
        self._owner: StoreOwner | None = None  # the exclusive lock on the store while started
        #: targets, recipes and guidance (:class:`~hexapod_model.service.changeover.Changeover`), once started
        self.changeover: Changeover | None = None
        self.writer: StoreWriter | None = None
        self.frames = self.unknown_frames = 0
        #: seconds the frames of the last check interval waited between their bus stamps and their handling (more than
        #: :data:`~hexapod_model.service.http.health.OVERLOADED`: ``/health`` says ``service_overloaded``)
        self.lag = 0.0
        self._started = 0.0

    # ----- life cycle -----
    def start(self, wait: bool = True) -> FixtureService:
        """Serve HTTP (``503 starting`` at first), open the bus, then prepare and start the cycle.

        Preparing loads the hexapods, opens the store, recovers every fixture's last lock and
        compiles the solver's kernels (about a minute after installation). With ``wait`` it
        happens here (its errors are raised); without, in a thread: :attr:`ready` says when the
        cycle runs, :attr:`failure` holds the error that stopped the preparation.
        """
        cfg = self.config
        self._started = time.time()
        self._stop.clear()
        try:  # what can fail fails first, before anything is logged or written
            self._owner = StoreOwner(cfg.store.path)  # one service per store: a second one is refused here
            if self._http:
                from .http.server import HttpServer

                try:
                    from .http.app import build_app
                except ImportError:
                    from .http.server import INSTALL_HINT

                    raise ServiceError(INSTALL_HINT) from None
                from .http.changeover_routes import changeover_routes

                self.endpoint = HttpServer(build_app(self, [*changeover_routes(), *self._extra_routes]), cfg.http)
            if self._bus is None:
                self._bus = open_bus(cfg)
            if self.endpoint is not None:
                self.endpoint.start()
                self._owner.describe(self.endpoint.url)
                log.info("serving %s", self.endpoint.url)
            if wait:
                self._prepare()
        except BaseException:
            self._close()
            raise
        if not wait:
            self._preparing = NamedThread(target=self._prepare_logged, name="hx-start")
            self._preparing.start()
        return self

    def _prepare_logged(self) -> None:
        try:
            self._prepare()
        except Exception as exc:  # noqa: BLE001 - kept for the caller (one line), never a traceback
            self.failure = exc
            log.debug("cannot start: %s", exc)

    def _prepare(self) -> None:
        """Hexapods, store, recovered locks, kernels; then the store writer and the cycle thread."""
        cfg = self.config
        self.phase = "loading the hexapods"
        loaded: dict[str, Hexapod] = {}  # fixtures naming one file share its hexapod (a model is ~6 MB)
        for f in cfg.fixtures:
            if f.name not in self.hexapods:
                if f.hexapod not in loaded:
                    loaded[f.hexapod] = f.load_hexapod()
                self.hexapods[f.name] = loaded[f.hexapod]
        self.phase = "opening the store"
        store = Store(cfg.store.path, cfg.store.samples)
        try:
            cycles = {}
            hashes: dict[int, str] = {}
            evaluators: dict[int, SensitivityEvaluator] = {}  # one per hexapod: every cycle runs on one thread
            for f in cfg.fixtures:
                hexa = self.hexapods[f.name]
                if id(hexa) not in hashes:
                    hashes[id(hexa)] = geometry_hash(hexa)
                    evaluators[id(hexa)] = SensitivityEvaluator(hexa, characteristic_length(hexa))
                last = store.last_lock(f.name)
                cycles[f.name] = FixtureCycle(f, hexa, hashes[id(hexa)], last, self._started, evaluators[id(hexa)])
                # several fixtures: their complete sets wait for the frames queued behind them (_loop)
                cycles[f.name].hold_sets = len(cfg.fixtures) > 1
                log.info("fixture %s: %s", f.name, cycles[f.name].recovery)
            self.phase = "compiling the solver's kernels"
            self._warm_up()
        except BaseException:
            store.close()
            raise
        with self._lock:
            if self._stop.is_set():  # stopped meanwhile
                store.close()
                return
            self.store, self.cycles = store, cycles
            self.changeover = Changeover(store, self.hexapods, cycles)
            self._routes = frame_routes(cfg, self.cycles)  # by extended flag, then id (CANopen links too)
            self.writer = StoreWriter(self.store)
            self._last_logged = {name: -1e300 for name in self.cycles}
            # what is alive now (numba, pinocchio, python-can, the hexapods) lives as long as the
            # service: out of the cyclic collector's reach, whose full passes over it stalled every
            # thread for ~100 ms (the p99 latency); the records' garbage is still collected
            gc.collect()
            gc.freeze()
            listening = time.time()  # the warm-up's time was no silence of the legs
            for cycle in cycles.values():
                cycle.listen(listening)
            self._thread = NamedThread(target=self._loop, name="hx-cycle")
            self._thread.start()
            self.phase = "running"
            self._ready.set()

    @property
    def running(self) -> bool:
        """Whether the cycle thread runs."""
        return self._thread is not None and self._thread.is_alive()

    @property
    def started(self) -> float:
        """Unix time (s) of the last :meth:`start`."""
        return self._started

    @property
    def ready(self) -> bool:
        """Whether the cycle runs (before: HTTP answers ``503`` with :meth:`starting`)."""
        return self._ready.is_set()

    def starting(self) -> dict:
        """What ``/health`` says before the service is ready: ``starting`` (and what it does) or ``failed``."""
        if self.failure is not None:
            return {"status": "failed", "error": str(self.failure)}
        return {"status": "starting", "phase": self.phase, "uptime_s": time.time() - self._started}

    def _warm_up(self) -> None:
        """Compile the kernels a reading set runs before the cycle reads its first frame; drop what queued meanwhile.

        After installation numba compiles for about a minute; frames received during it are
        discarded (a count is logged): their poses are that old.
        """
        t0 = time.monotonic()
        seen = set()  # numba compiles once per process: one throwaway tracker per hexapod and predictor
        for f in self.config.fixtures:
            if (id(self.hexapods[f.name]), f.predictor) not in seen:
                seen.add((id(self.hexapods[f.name]), f.predictor))
                warm_up(self.hexapods[f.name], f.noise, f.predictor)
        seconds = time.monotonic() - t0
        dropped = 0
        while dropped < 10_000_000 and self._bus is not None and self._bus.recv(timeout=0.0) is not None:
            dropped += 1
        if seconds > 1.0 or dropped:
            log.info(
                "kernels ready in %.1f s (compiled on a first run); %d frames received meanwhile dropped",
                seconds,
                dropped,
            )

    def stop(self) -> None:
        """Stop the cycle, flush the store, close HTTP and (an own) bus; unfreeze the collector's objects.

        Returns within about a second even while the kernels compile: the preparation then
        ends on its own and closes the store it opened (see :attr:`preparing`).
        """
        self._stop.set()
        if self._preparing is not None and self._preparing.ident is not None:  # Ctrl-C may land before it starts
            self._preparing.join(0.3)
        with self._lock:  # the preparation either finished or will see _stop and clean up itself
            self._ready.clear()
            if self._thread is not None:
                if self._thread.ident is not None:  # Ctrl-C may land between creating and starting it
                    self._thread.join()
                self._thread = None
            if self.writer is not None:
                self.writer.stop()
                self.writer = None
            self._close()
        gc.unfreeze()

    @property
    def preparing(self) -> bool:
        """Whether the background preparation still runs (a compile cannot be interrupted)."""
        return self._preparing is not None and self._preparing.is_alive()

    def _close(self) -> None:
        if self.endpoint is not None:
            self.endpoint.stop()
            self.endpoint = None
        if self._own_bus and self._bus is not None and not self.preparing:
            self._bus.shutdown()
            self._bus = None
        if self.store is not None:
            self.store.close()
            self.store = None
        if self._owner is not None:
            self._owner.release()
            self._owner = None

    def __enter__(self) -> FixtureService:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    @property
    def address(self) -> tuple[str, int] | None:
        """``(host, port)`` of the HTTP endpoint once started (None without HTTP)."""
        return None if self.endpoint is None else self.endpoint.address

    # ----- outputs -----
    def subscribe(self, callback: Callable[[PoseRecord], None]) -> None:
        """Call ``callback(record)`` for every published record (on the cycle thread)."""
        self._subscribers.append(callback)

    def names(self) -> list[str]:
        """Fixture names, configuration order."""
        return [f.name for f in self.config.fixtures]

    def record(self, name: str) -> PoseRecord | None:
        """The latest record of fixture ``name`` (None for an unknown name)."""
        cycle = self.cycles.get(name)
        return None if cycle is None else cycle.last

    def record_json(self, name: str) -> str | None:
        """The latest record of fixture ``name`` as JSON text (None for an unknown name)."""
        cycle = self.cycles.get(name)
        return None if cycle is None else self.json_of(cycle.last)

    def json_of(self, rec: PoseRecord) -> str:
        """The record's JSON text (:meth:`PoseRecord.to_json`), made once per record (HTTP and JSON lines share it)."""
        name = rec.fixture
        hit = self._json.get(name)
        if hit is not None and hit[0] is rec:  # the record itself is kept: its id cannot be reused
            return hit[1]
        text = rec.to_json()
        self._json[name] = (rec, text)  # one entry per fixture; a race only serialises twice
        return text

    def watch(self, monitor: PlanMonitor) -> None:
        """Check every record against a playing changeover plan (once ready).

        The plan's progress and a ``coupling_mismatch`` appear in ``GET /events``' ``plan`` (the
        dashboard) and in ``/health``'s ``plan`` section (a mismatch: ``degraded``).
        """
        if self.changeover is None:
            raise ServiceError("the service is not ready: watch a plan once it runs")
        self.changeover.monitor = monitor
        self.subscribe(monitor.check)
        self.health_sections["plan"] = monitor.health

    def acknowledge(self, name: str, by: str, client: str = "local", note: str = "") -> Acknowledgement | None:
        """Acknowledge the fault latched on fixture ``name`` (None when none waits; ``KeyError``: no such fixture).

        The cycle clears it at its next set (see :mod:`~hexapod_model.service.cycle.alarms`); logged
        with who, from where and when.
        """
        ack = self.cycles[name].acknowledge(by, client, note)
        if ack is not None:
            flags = ",".join(ack.fault.flags())
            log.warning("fixture %s: acknowledgement of %s by %s from %s", name, flags, by, client)
        return ack

    def health(self) -> dict:
        """Service state: ``ok`` or ``degraded``, each problem one line (:mod:`~hexapod_model.service.http.health`)."""
        return health(self)

    # ----- the cycle thread -----
    def _loop(self) -> None:
        assert self._bus is not None
        tick = bus_wait(self.config)
        routes, recv, last_check = self._routes, self._bus.recv, time.time()
        behind = 0.0  # s, the most a frame waited between its stamp and its handling since the last check
        # the most a frame waited lately: a quiet bus is quiet up to the wall clock minus this (frames stamped
        # earlier may still be on their way: a gateway's delivery, a sender or this thread running late)
        waits: deque[float] = deque(maxlen=max(1, round(TRANSIT_WINDOW / tick)))
        transit = 0.0
        # the cycles holding a complete set (FixtureCycle.hold_sets, with several fixtures): the sets
        # are solved back to back once no frame is queued, before a holding cycle takes another
        # frame, HOLD_LIMIT after the first was held, and before the silence checks. Solving each
        # set between the frames of the others runs the solver's code and data cold from the
        # caches every time
        held: list[FixtureCycle] = []
        since = 0.0  # when the first of them was held
        while not self._stop.is_set():
            asked = time.time()
            try:
                msg = recv(0.0 if held else tick)
            except (can.CanError, OSError) as exc:
                log.error("bus: %s", exc)
                self._solve_held(held)
                self._stop.wait(tick)
                continue
            if msg is None and held:  # nothing queued: the held sets now, then wait for frames
                self._solve_held(held)
                continue
            if msg is None:  # nothing queued until the wait ended: quiet until then, not until this thread ran
                # (a stall after the wait is the service's), less the longest wait lately: the frames handled
                # since the last check count too (their wait is not in `waits` yet)
                clock = min(time.time(), asked + tick) - max(transit, behind)
            else:
                now = time.time()
                stamp = msg.timestamp or now  # the bus's own clock: a backlog is not silence
                if now - stamp > behind:  # behind = max(behind, now - stamp), without a builtin's call a frame
                    behind = now - stamp
                clock = now if now < stamp else stamp  # for silence: a stamp ahead of the wall clock has not come yet
                route = routes[bool(msg.is_extended_id)].get(msg.arbitration_id)
                if route is None or msg.is_error_frame or msg.is_remote_frame:
                    self.unknown_frames += 1
                else:
                    self.frames += 1
                    cycle, on_frame, leg = route
                    if held and (cycle.holding or now - since > HOLD_LIMIT):
                        self._solve_held(held)
                    rec = on_frame(leg, msg.data, stamp)
                    if rec is not None:
                        self._publish(cycle, rec)
                    if cycle.holding:
                        if not held:
                            since = now
                        held.append(cycle)
            if clock - last_check >= tick:
                self._solve_held(held)
                last_check = clock
                self.lag, behind = behind, 0.0  # the most a frame waited since the last check: the service's delay
                waits.append(self.lag)
                transit = max(waits)
                for cycle in self.cycles.values():
                    rec = cycle.check_silence(clock)
                    if rec is not None:
                        self._publish(cycle, rec)
        self._solve_held(held)  # stopping: every set taken is published

    def _solve_held(self, held: list[FixtureCycle]) -> None:
        """Solve and publish the sets ``held`` (in the order they were completed); empties it."""
        for cycle in held:
            rec = cycle.finish_held()
            if rec is not None:  # (None: the cycle published it itself, before a record of its own)
                self._publish(cycle, rec)
        held.clear()

    def _publish(self, cycle: FixtureCycle, rec: PoseRecord) -> None:
        writer = self.writer
        assert writer is not None
        if cycle.pending_lock is not None:
            episode, event = cycle.pending_lock
            cycle.pending_lock = None
            writer.lock(event, partial(cycle.lock_stored, episode))
        name = rec.fixture
        if rec.t - self._last_logged[name] >= self.config.store.sample_interval:
            self._last_logged[name] = rec.t
            writer.sample(sample_row(rec))
        for callback in self._subscribers:
            try:
                callback(rec)
            except Exception:  # noqa: BLE001 - one bad subscriber must not stop the fixtures
                log.exception("record subscriber %r failed", callback)
