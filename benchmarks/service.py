"""Throughput, CPU and latency of the fixture pose service (not a test: figures are printed).

python benchmarks/service.py [--seconds S] [--one 250,500,1000,2000] [--many 50,100,200] [--fixtures 20]
                             [--more FIXTURES:RATES ...] [--capacity] [--rest] [--frame-gap US]

A feeder thread plays trajectory A (reference hexapod, 10 um reading noise, frames encoded with each
fixture's layout and CAN ids) on python-can's virtual bus at a set rate per fixture; the service
(its cycle thread, the store writer, HTTP on 127.0.0.1:0) runs in the same process, as ``hexapod
serve --simulate`` does. Each run is one stream: a warm-up in which the fixtures join one after
another over the first second, that goes on until the service has published a record for the sets
sent (1.5 s at least, 5 s at most), then the measured seconds, without a pause. Frames carry their
sampling time as timestamps (as a SocketCAN receiver stamps a burst) and are put straight into the
receiving virtual bus's queue, as a kernel delivers them (the virtual bus's own ``send`` deep-copies
each frame under this process's GIL: a cost of the stand-in hardware, not of the service); the frame
objects of a run are made before the service starts, so the feeder only stamps and queues them, and
the service's start puts them out of the cyclic collector's reach with its own objects (a kernel's
buffers are not in the heap). Per run: sets sent and solved, the latency from the arrival of the
frame that completed a set to the publication of its record (the subscriber's call; a backlog
counts), and the CPU time of the service's threads (cycle + store + HTTP) a set, over every set whose
record they published while measured (a run still behind after its warm-up works the warm-up's
backlog off then: those sets count too), and in percent of one core, that CPU a set times the sets
sent a second (for a run that fell behind: what its stream needs, which can exceed 100 %), and the
whole process's (feeder included); the process's CPU is also split as read from outside, by
OS thread name (``/proc/self/task/*/comm``: the service's ``hx-cycle``, ``hx-store``, ``hx-http``;
the feeder, named ``hx-sim`` as the simulator of ``hexapod serve --simulate`` is; the rest). A rate
is *sustained* when at least 99 % of the sets sent are solved and the p99 latency stays under 10 ms
(no backlog). The machine's other load is part of the figures: run it on an idle machine for the
capacity. Each run prints the service's CPU per solved set beside the tracker step's and the solve's
own (measured first, alone, in this process), and a run of one fixture also against the solve timed
after the same idle gap (``1 / rate``): after a gap the caches are cold, and the same solve costs
more CPU (docs/performance.md). Each fed run is also split before the bus and the threads: the
same fixtures' cycles handed the same frames on this thread at the stream's pace, asleep between
periods (their caches cold after each idle gap, as the cycle thread's), beside the same handed
back to back, and a thread that only takes the stream's frames off the virtual bus (the bus's
wake-ups alone), each CPU a set. The feeder delivers a period's frames at once; ``--frame-gap
130`` delivers a set's frames leg by leg 130 us apart, as a 1 Mbit/s bus carries them, and the
cycle thread then wakes for each (the gaps delivered, the feeder's sleeps, are printed). Each
fixture plays the trajectory from a point of its own (fixture ``i`` of ``F`` from sample
``i * SETS / F``): the fixtures of a cell stand at poses of their own (fixtures in step would
share what one proof leaves for the next step, its region and preconditioner, as no cell does).
Every fixture's frames of one sampling period are queued together (without ``--frame-gap``):
the last fixture's set of a period waits for the sets of the others (its latency holds
``FIXTURES - 1`` sets' CPU). ``--more 5:1000`` adds runs of 5 fixtures at 1 kHz: the 5,000 sets a
second of 50 fixtures at 100 Hz, in periods of 5 sets instead of 50. ``--rest`` adds ``--fixtures`` fixtures at
100 Hz **at rest**, the usual state of a locked fixture: each at a pose of its own about home, 1 um
of noise on readings carried as 1 um counts (a leg repeats its count often, and the tracker's stuck
test runs), fed and, with ``--capacity``, from a full queue; set against the solve of such a
fixture. ``--capacity`` also queues the frames of 3 s of sets before the cycle thread reads them and
prints its CPU per set with no idle gaps (1 x 1000 Hz, FIXTURES x 100 Hz and each ``--more`` run):
the cost of a set when the thread's caches stay warm, beside the same fixtures' tracker steps run in
turn on one thread without the bus, the frames and the records (one fixture: its step alone), which
shows what stepping many fixtures' trackers costs each one's, and beside the same fixtures' cycles
handed the same frames directly on one thread (no bus, no other thread, no store): the set's
Python from its frames to its record, so that the cycle thread's CPU splits into the tracker step,
the cycle's own work and what python-can's bus, the threads and the store add.
"""

from __future__ import annotations

import argparse
import copy
import json
import queue
import tempfile
import threading
import time
import uuid
from collections import deque
from collections.abc import Callable
from pathlib import Path

import can
import numpy as np

from hexapod_model import Hexapod
from hexapod_model.analysis.sensitivity import SensitivityEvaluator
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.service import FixtureCycle, FixtureService, PoseSolver, config_from_dict, geometry_hash
from hexapod_model.service.service import bus_wait
from hexapod_model.service.sim.config import trajectory_sequence
from hexapod_model.service.threads import NamedThread
from hexapod_model.tracking.types import characteristic_length, predict

SETS = 2000  # one there-and-back of trajectory A, whatever the rate
IDLE_SOLVES = 400  # solves timed after an idle gap, per rate of one fixture
RAMP = 1.0  # s: a fed run's fixtures join the stream one after another over this time
WARM_UP = 1.5  # s: a fed run's warm-up, at least (the ramp, caches, each tracker's first samples) ...
WARM_UP_LIMIT = 5.0  # s: ... and then until the service has caught up with the stream, at most this


def readings_sequence(hexa: Hexapod, noise: float = 10e-6, seed: int = 0) -> np.ndarray:
    """(SETS, 6) noisy readings along trajectory A there and back (0.01 m per paper unit)."""
    poses = trajectory_sequence("A", hexa.home_pose, 0.01, SETS / 8.0, 8.0)
    out, guess = [], None
    for T in poses:
        guess = hexa.inverse(T, guess=guess)
        out.append(guess.lengths.copy())
    return np.array(out) + np.random.default_rng(seed).normal(0.0, noise, (len(out), 6))


def phases(fixtures: int, samples: int) -> list[int]:
    """Where each fixture starts on the readings sequence: evenly apart, each at a pose of its own."""
    return [(i * samples) // fixtures for i in range(fixtures)]


def fixture_readings(readings: np.ndarray, fixtures: int) -> np.ndarray:
    """(samples, fixtures, 6): each fixture's readings (m) at each sample.

    A (samples, fixtures, 6) array is returned as it is; a (samples, 6) sequence is played by
    every fixture from a point of its own (:func:`phases`).
    """
    if readings.ndim == 3:
        return readings
    return np.stack([np.roll(readings, -s, axis=0) for s in phases(fixtures, len(readings))], axis=1)


def rest_readings(hexa: Hexapod, fixtures: int, samples: int, noise: float = 1e-6, seed: int = 1) -> np.ndarray:
    """(samples, fixtures, 6): fixtures at rest, each at a pose of its own, readings (m) with ``noise`` m of noise.

    The poses are :func:`~hexapod_model.analysis.trajectories.box_poses` about home; the frames
    carry the readings as the layout's counts (1 um), so that a leg at rest repeats its count.
    """
    solved = hexa.inverse_batch(box_poses(hexa.home_pose, fixtures, seed=seed))
    if not np.all(solved.converged):
        raise SystemExit("a rest pose has no inverse kinematics: choose another seed")
    rng = np.random.default_rng(seed)
    return solved.lengths[None, :, :] + rng.normal(0.0, noise, (samples, fixtures, 6))


def drain(service: FixtureService, limit: float = 10.0) -> None:
    """Wait until the service has taken every frame sent (its count stops changing) or ``limit`` s."""
    end = time.monotonic() + limit
    while time.monotonic() < end:
        n = service.frames
        time.sleep(0.2)
        if service.frames == n:
            return


def thread_cpu(threads: list[threading.Thread]) -> float:
    """CPU seconds used so far by ``threads`` (Linux per-thread clocks)."""
    total = 0.0
    for t in threads:
        if t is not None and t.ident is not None and t.is_alive():
            total += time.clock_gettime(time.pthread_getcpuclockid(t.ident))
    return total


def cpu_by_thread_name(pid: int | str = "self") -> dict[str, float]:
    """CPU seconds used so far by the live threads of process ``pid``, summed by OS thread name.

    Read from outside the threads, as ``top -H`` does: ``/proc/PID/task/*/comm`` names each
    thread (the service's are ``hx-cycle``, ``hx-store``, ``hx-http``; the simulator's
    ``hx-sim``), ``schedstat`` gives its run time in ns.
    """
    out: dict[str, float] = {}
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            name = (task / "comm").read_text().strip()
            seconds = int((task / "schedstat").read_text().split()[0]) * 1e-9
        except (OSError, ValueError, IndexError):  # the thread ended meanwhile
            continue
        out[name] = out.get(name, 0.0) + seconds
    return out


SERVICE_THREADS = ("hx-cycle", "hx-store", "hx-http")


def make_config(fixtures: int, folder: Path):
    """A fresh virtual channel and a configuration of ``fixtures`` reference fixtures on it."""
    channel = f"bench-{uuid.uuid4().hex}"
    tables = [
        {"name": f"f{i:02d}", "hexapod": "reference", "can_ids": [0x100 + 8 * i + k for k in range(6)]}
        for i in range(fixtures)
    ]
    config = config_from_dict(
        {
            "bus": {"interface": "virtual", "channel": channel},
            "store": {"path": str(folder / f"{channel}.sqlite"), "samples": 100_000},
            "http": {"host": "127.0.0.1", "port": 0},
            "fixtures": tables,
        }
    )
    return channel, config


def capacity(hexa: Hexapod, readings: np.ndarray, fixtures: int, rate: float, sets: int, folder: Path) -> float:
    """Cycle-thread CPU (us) per set when the frames of ``sets`` periods are queued before they are read.

    No feeder thread and no idle gaps: the frames of a warm-up and of the measured sets are
    encoded first, stamped as ``rate`` sets per second per fixture from a moment just ahead of
    the clock (a frame stamped before the service began listening, or before a ``silent_leg``
    record it published meanwhile, would be late), and put in a queue of their own that then
    replaces the receiving bus's at once: the thread runs from a full queue, as it would under a
    sustained load. The thread's CPU clock is read by the subscriber (in the thread) at the last
    warm-up set's record and at the last measured set's; meanwhile no other thread of the
    process runs but the service's own (the fed runs' feeder is one more thread that takes the
    interpreter lock, and their sets wait for frames between bursts: their CPU per set is higher).
    """
    channel, config = make_config(fixtures, folder)
    bus = can.Bus(interface="virtual", channel=channel)
    service = FixtureService(config, bus=bus, hexapods={f.name: hexa for f in config.fixtures})
    warm = 200
    first, last = warm * fixtures, (warm + sets) * fixtures
    count, cpu, done = [0], [0.0, 0.0], threading.Event()

    def on_record(rec) -> None:  # runs in the cycle thread
        if rec.status == "silent_leg":
            return
        count[0] += 1
        if count[0] in (first, last):
            cpu[count[0] == last] = time.thread_time()
            if count[0] == last:
                done.set()

    service.subscribe(on_record)
    msgs = [(k, j, m) for k, _, j, m in frames_of(config, readings, warm + sets)]
    receiving = bus.queue
    service.start()  # warms the kernels up, then listens
    try:
        full: queue.Queue = queue.Queue()
        wall = time.time() + 0.5
        for k, j, m in msgs:
            m.timestamp = wall + k / rate + j * 130e-6
            full.put(m)
        bus.queue = full  # the thread's next read (within a tick) takes from the full queue
        done.wait(120.0)  # this thread sleeps throughout: no polling that takes the GIL from the cycle thread
    finally:
        service.stop()
        bus.queue = receiving
        bus.shutdown()
    if count[0] < last:
        raise RuntimeError(f"capacity: {count[0] - first} of {last - first} sets solved within 120 s")
    return 1e6 * (cpu[1] - cpu[0]) / (last - first)


def frames_of(config, readings: np.ndarray, periods: int) -> list[tuple[int, int, int, can.Message]]:
    """``(period, fixture, leg, frame)`` of ``periods`` sampling periods of every fixture of ``config``, in order.

    Each fixture plays ``readings`` from a point of its own (:func:`fixture_readings`); a
    period's frames are every fixture's six, fixture by fixture.
    """
    per = fixture_readings(readings, len(config.fixtures))
    n = len(per)
    return [
        (k, i, j, leg.message(float(per[k % n, i, j])))
        for k in range(periods)
        for i, fl in enumerate(f.legs for f in config.fixtures)
        for j, leg in enumerate(fl)
    ]


def cycles_by_hand(
    hexa: Hexapod, readings: np.ndarray, fixtures: int, rate: float, sets: int, folder: Path, paced: bool = False
) -> float:
    """CPU (us) a set of the fixtures' cycles handed their frames directly: no bus, no threads, no store.

    The frames of :func:`capacity`'s run (same configuration, readings and stamps) go to each
    fixture's :meth:`~hexapod_model.service.FixtureCycle.on_frame` in turn on this thread, as
    the cycle thread passes them on, each set solved when its last frame comes (a lock
    committed at once, as the store would): the set's work in the service's Python, from its
    frames to its record (tracker step included), without what python-can's bus, the other
    threads and the store add. ``sets`` periods are timed after a warm-up of 200.

    ``paced``: each timed period's frames are handed over at the period's time (``rate`` periods
    a second), the thread asleep in between, as a fed stream's cycle thread waits for its
    frames: the same work after the stream's idle gaps, its caches cold (only the CPU of the
    periods is counted, not the sleep).
    """
    warm = 200
    _, config = make_config(fixtures, folder)
    evaluator = SensitivityEvaluator(hexa, characteristic_length(hexa))  # one per hexapod, as the service's
    t0 = time.time()
    digest = geometry_hash(hexa)
    cycles = [FixtureCycle(f, hexa, digest, None, t0, evaluator) for f in config.fixtures]
    frames = [
        (cycles[i], j, m.data, t0 + 1.0 + k / rate + j * 130e-6)
        for k, i, j, m in frames_of(config, readings, warm + sets)
    ]

    def feed(part: list) -> int:
        """Hand ``part``'s frames to their cycles; the records published."""
        records = 0
        for cycle, j, data, stamp in part:
            if cycle.on_frame(j, data, stamp) is not None:
                records += 1
            if cycle.pending_lock is not None:  # the store's part, done at once
                episode, event = cycle.pending_lock
                cycle.pending_lock = None
                cycle.lock_stored(episode, event)
        return records

    first = len(frames) * warm // (warm + sets)  # every period has the same frames
    feed(frames[:first])
    if paced:
        per = 6 * fixtures  # a period's frames
        periods = [frames[k : k + per] for k in range(first, len(frames), per)]
        records, cpu, start = 0, 0.0, time.perf_counter()
        for k, part in enumerate(periods):
            wait = start + k / rate - time.perf_counter()
            if wait > 0.0:
                time.sleep(wait)
            c0 = time.thread_time()
            records += feed(part)
            cpu += time.thread_time() - c0
    else:
        c0 = time.thread_time()
        records = feed(frames[first:])
        cpu = time.thread_time() - c0
    if records != sets * fixtures:
        raise RuntimeError(f"cycles by hand: {records} records of {sets * fixtures} sets")
    return 1e6 * cpu / (sets * fixtures)


def solve_cost(
    hexa: Hexapod, readings: np.ndarray, rates: list[float], noise: float = 10e-6, resolution: float = 0.0
) -> tuple[float, float, dict[float, float]]:
    """CPU (us) a set of the tracker's step (solve, checks, uncertainty), of its solve alone, and of it after idle gaps.

    The solve alone is the one the tracker makes: ``forward`` from the motion model's
    prediction (its ``eq22`` predictor over the last two poses) with the Krawczyk proof of that
    short step, each timed by itself; then, per rate of ``rates`` (Hz), the same solve timed
    after the idle gap of a stream at that rate (:func:`solves_cost`).
    """
    solver = PoseSolver(hexa, noise, resolution=resolution)  # resolution: m a count, as a fixture's layout
    step_us = steps_cpu([solver], readings[:, None, :], len(readings) - 200)
    tol = solver.tracker.tol
    idle = {rate: solves_cost(hexa, readings, tol, 1.0 / rate, IDLE_SOLVES) for rate in rates}
    return step_us, solves_cost(hexa, readings, tol), idle


def steps_cpu(solvers: list[PoseSolver], per: np.ndarray, timed: int, warm: int = 200) -> float:
    """CPU (us) a set of ``solvers`` stepped in turn on ``per`` (samples, solvers, 6): ``warm`` sets, then ``timed``."""
    for k in range(warm):
        for i, solver in enumerate(solvers):
            solver.step(per[k % len(per), i], k)
    c0 = time.thread_time()
    for k in range(warm, warm + timed):
        for i, solver in enumerate(solvers):
            solver.step(per[k % len(per), i], k)
    return 1e6 * (time.thread_time() - c0) / (timed * len(solvers))


def steps_in_turn(
    hexa: Hexapod, readings: np.ndarray, fixtures: int, noise: float = 10e-6, resolution: float = 0.0
) -> float:
    """CPU (us) a set of the tracker's step when ``fixtures`` streams are stepped in turn on one thread.

    As the service's cycle thread steps its fixtures' trackers (one sensitivity evaluator shared,
    each fixture at a point of its own on ``readings``, :func:`fixture_readings`), without the
    bus, the frames and the records: what the other fixtures' steps cost each one's (their state
    no longer in the caches), beside :func:`solve_cost`'s one stream.
    """
    evaluator = SensitivityEvaluator(hexa, characteristic_length(hexa))
    solvers = [PoseSolver(hexa, noise, sensitivity=evaluator, resolution=resolution) for _ in range(fixtures)]
    return steps_cpu(solvers, fixture_readings(readings, fixtures), max(100, 2000 // fixtures))


def solves_cost(hexa: Hexapod, readings: np.ndarray, tol: float, gap: float = 0.0, timed: int = 0) -> float:
    """CPU (us) of the tracker's solve alone (see :func:`solve_cost`), the mean of ``timed`` (0: all but 200).

    ``gap`` (s): the thread sleeps that long before each timed solve, as the cycle thread waits
    between the sets of a stream: after an idle gap the caches are cold, and the same solve
    costs more CPU.
    """
    history, spent = deque([hexa.q_home], maxlen=2), 0.0
    last = len(readings) if not timed else min(len(readings), 200 + timed)
    for k in range(last):
        guess = predict(hexa.model, history, "eq22")
        if k >= 200 and gap > 0.0:
            time.sleep(gap)
        t = time.thread_time()
        sol = hexa.forward(readings[k], guess, tol=tol, max_iter=20, check=False)
        spent += time.thread_time() - t if k >= 200 else 0.0
        history.appendleft(sol.q)
    return 1e6 * spent / (last - 200)


def leg_by_leg(sets: list[list[can.Message]], deliver: Callable[[can.Message], None], due: float, gap: float) -> None:
    """Deliver a period's ``sets`` (each a fixture's frames, leg order) leg by leg: leg ``j`` at ``due + j * gap``.

    ``due``: the period's start on :func:`time.perf_counter`'s clock; every set's frame of a leg
    goes together. The thread sleeps between legs (a sleep ends after its time, never before).
    """
    for j in range(len(sets[0]) if sets else 0):
        wait = due + j * gap - time.perf_counter()
        if j and wait > 0.0:
            time.sleep(wait)
        for msgs in sets:
            deliver(msgs[j])


def wakeups(
    readings: np.ndarray, fixtures: int, rate: float, seconds: float, folder: Path, frame_gap: float = 0.0
) -> float:
    """CPU (us) a set of a thread that only takes a fed run's frames off the bus: the bus's wake-ups alone.

    The frames of ``fixtures`` fixtures' sets are delivered ``rate`` periods a second for
    ``seconds``, as :func:`run`'s feeder delivers them (``frame_gap``: leg by leg, that far
    apart); the thread waits for each frame as the
    service's loop does (python-can's ``recv`` with the service's wait, :func:`bus_wait`) and
    does nothing with it. Its CPU per set is what waiting for the stream's frames costs a
    served set before any of the service's work.
    """
    channel, config = make_config(fixtures, folder)
    bus = can.Bus(interface="virtual", channel=channel)
    period_frames = [m for _, _, _, m in frames_of(config, readings, 1)]
    sets = [period_frames[6 * i : 6 * i + 6] for i in range(fixtures)]  # each fixture's six, leg order
    stop, taken, cpu = threading.Event(), [0], [0.0]
    tick = bus_wait(config)

    def take() -> None:
        recv, c0 = bus.recv, time.thread_time()
        while not stop.is_set():
            if recv(tick) is not None:
                taken[0] += 1
        cpu[0] = time.thread_time() - c0

    receiver = threading.Thread(target=take, name="bench-recv")
    receiver.start()
    deliver, periods = bus.queue.put, max(1, int(seconds * rate))
    try:
        start = time.perf_counter()
        for k in range(periods):
            wait = start + k / rate - time.perf_counter()
            if wait > 0.0:
                time.sleep(wait)
            if frame_gap <= 0.0:
                for m in period_frames:
                    deliver(m)
            else:  # as run's feeder
                leg_by_leg(sets, deliver, start + k / rate, frame_gap)
        while taken[0] < periods * len(period_frames) and time.perf_counter() - start < seconds + 5.0:
            time.sleep(0.01)
    finally:
        stop.set()
        receiver.join()
        bus.shutdown()
    return 1e6 * cpu[0] / (periods * fixtures)


def caught_up(
    published: list[int], delivered: list[int], behind: int, least: float, limit: float
) -> tuple[float, bool]:
    """Wait until the records ``published[0]`` counts are within ``behind`` of the sets ``delivered[0]`` counts.

    Waits ``least`` first, at most ``limit`` in all; polls every 50 ms (a short hold of the
    interpreter lock). Returns the seconds waited and whether the records caught up.
    """
    t0 = time.monotonic()
    time.sleep(least)
    while not (done := delivered[0] - published[0] <= behind) and time.monotonic() - t0 < limit:
        time.sleep(0.05)
    return time.monotonic() - t0, done


def run(
    hexa: Hexapod,
    readings: np.ndarray,
    fixtures: int,
    rate: float,
    seconds: float,
    folder: Path,
    frame_gap: float = 0.0,
) -> dict:
    """One run: ``fixtures`` fixtures at ``rate`` sets per second each for ``seconds``, after the warm-up.

    ``frame_gap`` (s): 0 delivers a period's frames at once; else a set's frame of leg ``j`` is
    delivered ``j * frame_gap`` after the period's start (every fixture's frame of leg ``j``
    together), as a bus carries a set's frames one after another (a frame takes about 130 us
    on a 1 Mbit/s bus). The feeder sleeps between them: the gaps delivered are reported.

    One stream from start to end: the warm-up (caches, each tracker's first samples) goes on
    until the service has published a record for the sets sent (at least :data:`WARM_UP` s, at
    most :data:`WARM_UP_LIMIT`; the fixtures join over the first :data:`RAMP` s), and the
    measured phase follows it without a pause (a pause would leave every fixture's legs silent,
    and the measured phase would begin with the trackers re-anchoring after it: a restart, not
    the stream's steady state).
    """
    channel, config = make_config(fixtures, folder)
    legs = [f.legs for f in config.fixtures]
    names = [f.name for f in config.fixtures]
    per = fixture_readings(readings, fixtures)
    frames = [
        [[leg.message(float(per[k, i, j])) for j, leg in enumerate(fl)] for i, fl in enumerate(legs)]
        for k in range(len(per))
    ]
    # a message object per frame of each period of the run, made before the service starts: the
    # feeder only stamps and queues them (as a kernel delivers frames), so its own cost stays small,
    # and they are among the objects the service's start puts out of the cyclic collector's reach
    # (gc.freeze), as a kernel's buffers are out of the process's heap (made during the run, the
    # hundreds of thousands of them cost the cycle thread full collections of ~0.1 s each)
    periods = int((WARM_UP_LIMIT + seconds + 1.0) * rate)
    ahead = [[[copy.copy(m) for m in msgs] for msgs in frames[k % len(frames)]] for k in range(periods)]
    latencies: list[float] = []
    statuses: dict[str, int] = {}
    arrived: dict[tuple[str, float], float] = {}  # (fixture, t of its last frame) -> when it was on the bus
    published = [0]  # records of the sets sent (a fixture not yet in the stream publishes silent_leg)

    def on_record(rec: dict) -> None:  # runs in the cycle thread
        if rec.status != "silent_leg":
            published[0] += 1
        sent_at = arrived.get((rec.fixture, rec.t))
        if rec.pose is not None and sent_at is not None:  # a solved set of the measured phase
            latencies.append(time.time() - sent_at)
        statuses[rec.status] = statuses.get(rec.status, 0) + 1

    bus = can.Bus(interface="virtual", channel=channel)  # the service's receiving end
    service = FixtureService(config, bus=bus, hexapods={f.name: hexa for f in config.fixtures})
    service.subscribe(on_record)
    deliver = bus.queue.put  # straight into the receiving queue, as a kernel delivers frames: the
    # virtual bus's send (a deepcopy per frame, in this process and under its GIL) is not the service
    sent, delivered = [0], [0]  # periods sent in the measured phase; fixtures' sets sent in all
    stop = threading.Event()
    read = threading.Event()  # the feeder's CPU was read from outside: it may end

    # the fixtures join the stream one after another over the first second (fixture i at period
    # joins[i]), as a cell's fixtures come up: each tracker's first samples (a solve from home, the
    # settling) are spread out instead of queueing 50 fixtures' at once
    joins = [(i * int(RAMP * rate)) // fixtures for i in range(fixtures)]

    spans: list[float] = []  # with a frame gap: each period's time from its first frame to its last (s)

    def feed() -> None:  # the warm-up, then the measured phase
        period, k, start, wall = 1.0 / rate, 0, time.perf_counter(), time.time()
        while not stop.is_set() and k < len(ahead):
            wait = start + k * period - time.perf_counter()
            if wait > 0:
                time.sleep(wait)
            stamp = wall + k * period  # the sampling time, as an encoder's frame would carry it
            if frame_gap <= 0.0:  # every frame of the period at once
                for name, msgs, join in zip(names, ahead[k], joins):
                    if k < join:
                        continue
                    for j, m in enumerate(msgs):
                        m.timestamp = stamp + j * 130e-6
                        deliver(m)
                    arrived[(name, m.timestamp)] = time.time()  # the set's last frame is at the receiver
                    delivered[0] += 1
            else:  # leg by leg, frame_gap apart
                live = [(name, msgs) for name, msgs, join in zip(names, ahead[k], joins) if k >= join]
                for _, msgs in live:
                    for j, m in enumerate(msgs):
                        m.timestamp = stamp + j * 130e-6
                first = time.perf_counter()
                leg_by_leg([msgs for _, msgs in live], deliver, start + k * period, frame_gap)
                spans.append(time.perf_counter() - first)
                now = time.time()
                for name, msgs in live:
                    arrived[(name, msgs[-1].timestamp)] = now
                    delivered[0] += 1
            sent[0] += 1
            k += 1
        # alive until its thread's CPU is read (a read while the cycle thread holds the GIL can take
        # tens of milliseconds: an ended feeder's thread is gone from /proc)
        read.wait(10.0)

    service.start()  # compiles, then freezes what is alive: the frames above too
    try:
        threads = [service._thread, getattr(service.writer, "_thread", None)]
        if service.endpoint is not None:
            threads.append(service.endpoint._thread)
        feeder = NamedThread(target=feed, name="hx-sim")  # the stand-in for the simulator
        feeder.start()
        warm_up, warmed = caught_up(published, delivered, fixtures, WARM_UP, WARM_UP_LIMIT)
        arrived.clear()
        latencies.clear()
        statuses.clear()
        sent[0] = 0
        c0, p0, t0 = thread_cpu(threads), time.process_time(), time.perf_counter()
        k0, h0 = thread_cpu(threads[:1]), published[0]
        n0 = cpu_by_thread_name()
        time.sleep(seconds)
        stop.set()
        n1 = cpu_by_thread_name()  # before the feeder ends: its thread's time is read while it lives
        read.set()
        feeder.join()
        fed = time.perf_counter() - t0
        n1 |= {k: v for k, v in cpu_by_thread_name().items() if k != "hx-sim"}
        drain(service)  # a backlog is worked off (and its latency counted), up to 10 s
        c1, p1, k1 = thread_cpu(threads), time.process_time(), thread_cpu(threads[:1])
        # the sets handled meanwhile: those of the measured phase and, in a run still behind
        # after its warm-up, the warm-up's backlog, whose work is in the same CPU time
        handled = max(published[0] - h0, 1)
        # the service threads' CPU per set handled times the sets sent: their share of a core per second
        # of stream (a sustained run: about its CPU per second of stream; one that fell behind: what it needs)
        need = sent[0] * fixtures / handled
        n2 = cpu_by_thread_name()
        named = {k: n2.get(k, n1.get(k, 0.0)) - n0.get(k, 0.0) for k in set(n0) | set(n1) | set(n2)}
        named["hx-sim"] = n1.get("hx-sim", 0.0) - n0.get("hx-sim", 0.0)
    finally:
        service.stop()
        bus.shutdown()
    lat = np.array(latencies) * 1e3
    records = len(latencies)  # solved sets
    return {
        "fixtures": fixtures,
        "rate_hz": rate,
        "sets_sent": sent[0] * fixtures,
        "warm_up_s": warm_up,
        "caught_up": warmed,  # False: measured still behind after the warm-up's limit
        "records": records,
        "statuses": statuses,
        "latency_ms_median": float(np.median(lat)) if records else float("nan"),
        "latency_ms_p99": float(np.percentile(lat, 99)) if records else float("nan"),
        "sets_handled": handled,  # sets whose records the CPU time below paid for
        "service_cpu_pct": 100.0 * (c1 - c0) * need / fed,  # the share of a core the sets sent need
        "service_cpu_us_per_set": 1e6 * (c1 - c0) / handled,
        "cycle_cpu_us_per_set": 1e6 * (k1 - k0) / handled,  # the cycle thread alone
        # the service's threads as above; the feeder's and the other threads' per second of stream
        "process_cpu_pct": 100.0 * ((c1 - c0) * need + (p1 - p0) - (c1 - c0)) / fed,
        # the same split as read from outside, by OS thread name (/proc/PID/task/*/comm)
        "os_service_cpu_pct": 100.0 * sum(named.get(k, 0.0) for k in SERVICE_THREADS) * need / fed,
        "os_sim_cpu_pct": 100.0 * named.get("hx-sim", 0.0) / fed,
        "os_other_cpu_pct": 100.0
        * sum(v for k, v in named.items() if k not in SERVICE_THREADS and k != "hx-sim")
        / fed,
        "sustained": records >= 0.99 * sent[0] * fixtures and records > 0 and float(np.percentile(lat, 99)) < 10.0,
    } | gaps_of(frame_gap, spans, len(frames[0][0]))


def gaps_of(frame_gap: float, spans: list[float], legs: int) -> dict:
    """A run's frame gap asked and delivered (us; the median of its periods' spans over the gaps), or nothing."""
    if frame_gap <= 0.0:
        return {}
    delivered = float(np.median(spans)) / (legs - 1) if spans and legs > 1 else float("nan")
    return {"frame_gap_us": 1e6 * frame_gap, "frame_gap_delivered_us": 1e6 * delivered}


def split_of_fed(
    hexa: Hexapod,
    readings: np.ndarray,
    fixtures: int,
    rate: float,
    seconds: float,
    folder: Path,
    frame_gap: float = 0.0,
) -> dict:
    """What a fed run's set costs before the bus and threads: its cycles' work at the stream's pace, the bus's wake-ups.

    ``paced_by_hand_us``: the fixtures' cycles handed their frames at the stream's pace
    (:func:`cycles_by_hand` ``paced``), their caches cold after each idle gap, beside
    ``warm_by_hand_us``, the same handed back to back; ``wakeups_us``: a thread that only takes
    the stream's frames off the bus (:func:`wakeups`). All CPU us a set.
    """
    sets = max(200, int(seconds * rate))
    return {
        "paced_by_hand_us": cycles_by_hand(hexa, readings, fixtures, rate, sets, folder, paced=True),
        "warm_by_hand_us": cycles_by_hand(hexa, readings, fixtures, rate, sets, folder),
        "wakeups_us": wakeups(readings, fixtures, rate, seconds, folder, frame_gap),
    }


def line(r: dict) -> str:
    return (
        f"{r['fixtures']:3d} x {r['rate_hz']:6.0f} Hz  sets {r['sets_sent']:7d}  solved {r['records']:7d}  "
        f"latency median {r['latency_ms_median']:6.2f} ms  p99 {r['latency_ms_p99']:7.2f} ms  "
        f"CPU service {r['service_cpu_pct']:5.1f} %{backlog(r)} ({r['service_cpu_us_per_set']:4.0f} us a set "
        f"of {r['sets_handled']} handled, "
        f"cycle thread {r['cycle_cpu_us_per_set']:4.0f}; "
        f"{r['service_cpu_us_per_set'] / r['solve_us']:.1f}x the solve{idle_ratio(r)})  "
        f"process {r['process_cpu_pct']:5.1f} % (by OS thread name: service {r['os_service_cpu_pct']:.1f}, "
        f"hx-sim {r['os_sim_cpu_pct']:.1f}, other {r['os_other_cpu_pct']:.1f})  "
        f"{'sustained' if r['sustained'] else 'NOT sustained'}  {r['statuses']}  "
        f"(after a warm-up of {r['warm_up_s']:.1f} s{'' if r['caught_up'] else ': still behind'})"
        f"{paced(r)}"
    )


def paced(r: dict) -> str:
    """The fed run's set before the bus and threads (:func:`split_of_fed`), or empty."""
    if "paced_by_hand_us" not in r:
        return ""
    gap = (
        f"; a set's frames {r['frame_gap_us']:.0f} us apart (delivered {r['frame_gap_delivered_us']:.0f} us apart)"
        if "frame_gap_us" in r
        else ""
    )
    return (
        f"\n    its cycles handed their frames at the stream's pace, without the bus: {r['paced_by_hand_us']:.0f} us "
        f"a set (back to back: {r['warm_by_hand_us']:.0f}); the bus's wake-ups alone: {r['wakeups_us']:.0f} us a set"
        f"{gap}"
    )


def backlog(r: dict) -> str:
    """`` needed by the sets sent`` for a run that fell behind (empty else).

    Such a run's share of a core is its CPU per set handled times the sets sent a second: what
    the stream would need, which can exceed 100 %.
    """
    return "" if r["sustained"] else " needed by the sets sent"


def idle_ratio(r: dict) -> str:
    """``, Nx the solve after the same idle gap`` for a run of one fixture (empty for the others)."""
    if "solve_idle_us" not in r:
        return ""
    return f", {r['service_cpu_us_per_set'] / r['solve_idle_us']:.1f}x the solve after the same idle gap"


def rates_of(text: str) -> list[float]:
    """Set rates (Hz) from a comma-separated list (empty entries skipped)."""
    return [float(v) for v in text.split(",") if v]


def group(text: str) -> tuple[int, list[float]]:
    """``FIXTURES:RATES`` (``5:1000``, ``5:500,1000``) as ``(fixtures, rates)``, for ``--more``."""
    fixtures, _, rates = text.partition(":")
    try:
        out = int(fixtures), rates_of(rates)
    except ValueError:
        out = 0, []
    if out[0] < 1 or not out[1] or not all(0.0 < r < float("inf") for r in out[1]):  # NaN fails too
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected FIXTURES:RATES, e.g. 5:1000 (fixtures >= 1, rates > 0 Hz)"
        )
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=5.0, help="measured seconds per run")
    ap.add_argument("--one", default="250,500,1000,2000", help="set rates (Hz) for one fixture")
    ap.add_argument("--many", default="50,100,200", help="set rates (Hz) per fixture for --fixtures fixtures")
    ap.add_argument("--fixtures", type=int, default=20)
    ap.add_argument(
        "--more",
        action="append",
        default=[],
        type=group,
        metavar="FIXTURES:RATES",
        help="also FIXTURES fixtures at each of RATES (Hz, comma-separated), e.g. 5:1000 (repeatable)",
    )
    ap.add_argument(
        "--frame-gap",
        type=float,
        default=0.0,
        metavar="US",
        help="fed runs: deliver a set's frames leg by leg, US microseconds apart (0: at once; ~130 on a 1 Mbit/s bus)",
    )
    ap.add_argument("--json", help="also write the runs (and the capacity figures, kind 'capacity') as JSON")
    ap.add_argument(
        "--capacity", action="store_true", help="also the cycle thread's CPU per set from a full queue (no idle gaps)"
    )
    ap.add_argument(
        "--rest",
        action="store_true",
        help="also --fixtures fixtures at 100 Hz at rest, each at a pose of its own (fed, and with --capacity)",
    )
    args = ap.parse_args(argv)
    if not 0.0 <= args.frame_gap < 1e5:  # NaN too
        ap.error(f"--frame-gap {args.frame_gap}: expected 0 <= us < 100000")
    gap = 1e-6 * args.frame_gap
    hexa = Hexapod.from_preset("reference")
    readings = readings_sequence(hexa)
    one = rates_of(args.one)
    groups = [(1, one), (args.fixtures, rates_of(args.many)), *args.more]
    # the solve after the idle gap of every one-fixture run (--fixtures 1 and --more 1:RATES are some)
    alone = list(dict.fromkeys(rate for n, rates in groups if n == 1 for rate in rates))
    step_us, solve_us, idle = solve_cost(hexa, readings, alone)
    print(
        f"a set alone: tracker step {step_us:.0f} us CPU (solve, checks, uncertainty), of which the solve "
        f"(forward from the prediction, with its proof) {solve_us:.0f} us; "
        f"load average {Path('/proc/loadavg').read_text().split()[0]}",
        flush=True,
    )
    print(
        "the solve after the idle gap of a 1-fixture stream: "
        + ", ".join(f"{rate:.0f} Hz {us:.0f} us ({us / solve_us:.1f}x)" for rate, us in idle.items()),
        flush=True,
    )
    still = None
    if args.rest:  # each fixture's samples of the fed run and of the capacity run, at rest
        # the samples of a fed run (its warm-up and measured periods) and of a capacity run
        still = rest_readings(hexa, args.fixtures, max(500, 150 + int((args.seconds + 1.0) * 100.0)) + 50)
        counts = np.round(still[:, 0] / 1e-6) * 1e-6  # the first fixture's readings as the frames carry them
        rest_step_us, rest_solve_us, _ = solve_cost(hexa, counts, [], noise=1e-6, resolution=1e-6)
        print(
            f"a set at rest (1 um noise, 1 um counts): tracker step {rest_step_us:.0f} us CPU, of which the solve "
            f"{rest_solve_us:.0f} us",
            flush=True,
        )
    reports = []
    with tempfile.TemporaryDirectory() as tmp:
        for n, rates in groups:
            for rate in rates:
                extra = {"solve_us": solve_us} | ({"solve_idle_us": idle[rate]} if n == 1 else {})
                extra |= split_of_fed(hexa, readings, n, rate, args.seconds, Path(tmp), gap)
                reports.append(run(hexa, readings, n, rate, args.seconds, Path(tmp), gap) | extra)
                print(line(reports[-1]), flush=True)
        if still is not None:
            extra = {"solve_us": rest_solve_us, "motion": "rest"}
            extra |= split_of_fed(hexa, still, args.fixtures, 100.0, args.seconds, Path(tmp), gap)
            reports.append(run(hexa, still, args.fixtures, 100.0, args.seconds, Path(tmp), gap) | extra)
            print("at rest " + line(reports[-1]), flush=True)
        if args.capacity:
            runs = [(1, 1000.0, None), (args.fixtures, 100.0, None)]
            runs += [(n, r, None) for n, rates in args.more for r in rates]
            runs += [] if still is None else [(args.fixtures, 100.0, still)]
            for n, rate, at_rest in runs:
                us = capacity(hexa, readings if at_rest is None else at_rest, n, rate, int(3 * rate), Path(tmp))
                share = us * n * rate / 1e4  # percent of one core at that rate
                solve, step = (solve_us, step_us) if at_rest is None else (rest_solve_us, rest_step_us)
                if at_rest is None:
                    turn = step_us if n == 1 else steps_in_turn(hexa, readings, n)
                else:
                    turn = steps_in_turn(hexa, np.round(at_rest / 1e-6) * 1e-6, n, 1e-6, 1e-6)
                hand = cycles_by_hand(hexa, readings if at_rest is None else at_rest, n, rate, int(rate), Path(tmp))
                reports.append(
                    {"kind": "capacity", "fixtures": n, "rate_hz": rate, "cycle_cpu_us_per_set": us}
                    | {"solve_us": solve, "step_us": step, "steps_in_turn_us": turn, "cycles_by_hand_us": hand}
                    | ({} if at_rest is None else {"motion": "rest"})
                )
                print(
                    f"capacity {n:3d} x {rate:6.0f} Hz{' at rest' if at_rest is not None else ''}  "
                    f"cycle thread CPU {us:5.0f} us a set, {us / solve:.1f}x the solve "
                    f"({share:.0f} % of a core)"
                    f"  against the solve's {solve:.0f} us, the tracker step's {step:.0f} us"
                    f", the {n} fixtures' tracker steps in turn, without the bus: {turn:.0f} us"
                    f" and their cycles handed the frames, without the bus, the threads and the store: {hand:.0f} us"
                )
    for n in dict.fromkeys(n for n, rates in groups if rates):  # each fixture count run once, in order (moving)
        ok = [r["rate_hz"] for r in reports if r["fixtures"] == n and r.get("sustained") and "motion" not in r]
        print(f"highest sustained set rate, {n} fixture(s): {max(ok):.0f} Hz" if ok else f"{n} fixture(s): none")
    if args.json:
        Path(args.json).write_text(json.dumps(reports, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
