"""``hexapod serve`` (the fixture pose service) and ``hexapod simulate-encoders``."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import gc
import logging
import os
import signal
import sys
import threading
import time

from ..exceptions import InputError
from ..extras import require_extra
from ._common import note

# python-can and the service are imported when a command runs: `hexapod --help` stays fast.

SERVE_DESCRIPTION = """\
Run the pose service of every fixture of FIXTURE.toml: read the encoder frames from the CAN bus,
track each fixture's pose, publish records (GET /fixtures, /fixtures/NAME/pose, /health on the
[http] address; JSON lines on stdout with --jsonl; ROS 2 topics and tf with a [ros] table,
docs/ros2.md), store lock poses in the SQLite store and recover them at the next start. Ctrl-C
(or SIGTERM) stops it cleanly. Format: docs/service.md."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``serve`` and ``simulate-encoders``."""
    p = sub.add_parser(
        "serve", help="run the fixture pose service (CAN in, poses over HTTP)", description=SERVE_DESCRIPTION
    )
    p.add_argument("config", metavar="FIXTURE.toml", help="the service configuration")
    p.add_argument("--simulate", metavar="SIM.toml", help="simulated encoders on a virtual bus (no hardware)")
    p.add_argument(
        "--plan",
        metavar="PLAN.json",
        help="with --simulate: play this changeover plan, monitored for coupling_mismatch (docs/planning.md §7)",
    )
    p.add_argument("--jsonl", action="store_true", help="also write every record as a JSON line on stdout")
    p.add_argument("--view", action="store_true", help="show the served poses in a local meshcat view")
    p.add_argument("--fixture", help="the fixture --view shows (default: the first)")
    p.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="stop S seconds after the start, the kernels' warm-up included (default: until Ctrl-C)",
    )
    p.add_argument("--log-level", default="INFO", choices=("DEBUG", "INFO", "WARNING", "ERROR"))
    p.set_defaults(func=run_serve)

    p = sub.add_parser("simulate-encoders", help="send simulated encoder frames on the configured bus")
    p.add_argument("config", metavar="FIXTURE.toml", help="the service configuration (bus, layouts, CAN ids)")
    p.add_argument("sim", metavar="SIM.toml", help="the simulation")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: until Ctrl-C)")
    p.set_defaults(func=run_simulate)


class _OneLine(logging.Formatter):
    """Log lines without tracebacks: an exception is its type and message on the same line."""

    def format(self, record: logging.LogRecord) -> str:
        if record.exc_info and record.exc_info[1] is not None:
            exc = record.exc_info[1]
            record = logging.makeLogRecord({**record.__dict__, "exc_info": None, "exc_text": None})
            record.msg, record.args = f"{record.getMessage()}: {type(exc).__name__}: {exc}", None
        return super().format(record)


@contextlib.contextmanager
def _logging(command: str, level: str):
    """The package's (and the HTTP server's) log records as ``hexapod COMMAND: LEVEL message`` lines on stderr."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_OneLine(f"hexapod {command}: %(levelname)s %(message)s"))
    saved = []
    for name, lvl in (("hexapod_model", level), ("uvicorn", "WARNING" if level != "DEBUG" else level)):
        logger = logging.getLogger(name)
        saved.append((logger, logger.handlers[:], logger.level, logger.propagate))
        logger.handlers[:] = [handler]
        logger.setLevel(lvl)
        logger.propagate = False
    try:
        yield
    finally:
        for logger, handlers, old_level, propagate in saved:
            logger.handlers[:] = handlers
            logger.setLevel(old_level)
            logger.propagate = propagate


def _stop_on_sigterm(stop: threading.Event) -> None:
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, lambda *_: stop.set())


def simulated(config):
    """``config`` with its bus replaced by a virtual one (same channel name): frames stay in this process."""
    from ..service.config.settings import BusConfig

    return dataclasses.replace(config, bus=BusConfig("virtual", config.bus.channel))


def run_serve(args: argparse.Namespace) -> int:
    """``hexapod serve``."""
    with _logging("serve", args.log_level):
        return _serve(args)


def _serve(args: argparse.Namespace) -> int:
    require_extra("service")
    from ..service import FixtureService, load_config

    config = load_config(args.config)
    if args.plan and not args.simulate:
        raise InputError("--plan", args.plan, "plays in the simulator only: give --simulate SIM.toml")
    sim_config = None
    if args.simulate:  # every input is read before the service starts: its errors are said at once
        config = simulated(config)
        sim_config = _load_simulation(args.simulate, config, args.plan)
    stop = threading.Event()
    _stop_on_sigterm(stop)
    service = FixtureService(config)
    if args.jsonl:
        service.subscribe(_jsonl_writer(stop, service.json_of))
    bridge = _ros_bridge(service)
    sim_bus = sim = None
    error: BaseException | None = None
    try:
        service.start(wait=False)  # HTTP answers 503 "starting" while the kernels compile
        deadline = None if args.duration is None else time.monotonic() + args.duration
        while not service.ready:
            if service.failure is not None:
                raise service.failure
            if stop.wait(0.05) or (deadline is not None and time.monotonic() >= deadline):
                return 0
        if bridge is not None:
            bridge.start()
        note("serve", f"fixtures {', '.join(service.names())}; Ctrl-C stops")
        dashboard = _dashboard(service)
        if dashboard is not None:
            note("serve", dashboard)
        if sim_config is not None:
            sim, sim_bus = _start_simulator(config, sim_config, service)
            if bridge is not None and sim_config.plan is not None:  # the played plan on ROS 2 too
                bridge.publish_plan(sim_config.plan.plan)
        if args.view:
            _view(args, service, stop, deadline)
        else:
            while not stop.wait(0.2):
                if deadline is not None and time.monotonic() >= deadline:
                    break
    except KeyboardInterrupt:
        pass
    except BaseException as exc:
        error = exc
        raise
    finally:
        if sim is not None:
            sim.stop()
        if sim_bus is not None:
            sim_bus.shutdown()
        if bridge is not None:
            bridge.stop()
        service.stop()
        if service.preparing:  # stopped while the kernels compile: a compile cannot be interrupted
            _exit_while_starting(error)
    note("serve", f"stopped; store {config.store.path}")
    gc.freeze()  # the process ends: the collector's last pass over numba's and pinocchio's objects took 1-5 s
    return 0


def _exit_while_starting(error: BaseException | None) -> None:
    """End the process while the background preparation still compiles (it cannot be interrupted).

    A stop (Ctrl-C, SIGTERM, ``--duration``) exits 0; an error is said in one line and exits 2
    (a ``HexapodError``) or 1 (anything else, with its type).
    """
    from ..exceptions import HexapodError, SolverError

    if error is None:
        note("serve", "stopped while starting")
        code = 0
    elif isinstance(error, HexapodError):
        note("serve", f"error: {error}")
        code = 1 if isinstance(error, SolverError) else 2
    else:
        note("serve", f"error: {type(error).__name__}: {error}")
        code = 1
    sys.stderr.flush()
    sys.stdout.flush()
    os._exit(code)


def _dashboard(service) -> str | None:
    """Where the dashboard is, and where its token goes when the service has one (None without HTTP)."""
    if service.endpoint is None:
        return None
    http = service.config.http
    url = service.endpoint.url + "/"
    where = " (this computer's address in place of the host)" if http.host in ("0.0.0.0", "::") else ""
    if http.token is None:
        return f"dashboard {url}{where}"
    return f"dashboard {url}#token=TOKEN{where}, TOKEN the content of {http.token_file} (kept in the browser tab)"


def _ros_bridge(service):
    """The ROS 2 publisher of ``[ros]`` (None without the table or with ``enabled = false``)."""
    ros = service.config.ros
    if ros is None or not ros.enabled:
        return None
    from ..ros.dds import RosBridge

    return RosBridge(service, ros)


def _load_simulation(path: str, config, plan: str | None = None):
    from ..service import load_simulation

    return load_simulation(path, config, plan)


def _start_simulator(config, sim_config, service):
    import can

    from ..service import Simulator

    sim_bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    follow = service.changeover.followed  # fixtures with a scripted changeover move to their targets
    monitor = None
    if sim_config.plan is not None:  # the plan's coupled phases checked against every record
        monitor = sim_config.plan.monitor(config)
        service.watch(monitor)
        note("serve", f"playing {sim_config.plan.file}: {sim_config.plan.plan.total_time:.2f} s")
    sim = Simulator(config, sim_config, sim_bus, truth=1, hexapods=service.hexapods, targets=follow, monitor=monitor)
    sim.start()
    return sim, sim_bus


def _view(args: argparse.Namespace, service, stop: threading.Event, deadline: float | None) -> None:
    from ..service import ServiceError
    from .live import live_view

    name = args.fixture or service.names()[0]
    if service.record(name) is None:
        raise ServiceError(f"--fixture {name!r}: not a fixture of {args.config}")
    live_view(service.hexapods[name], lambda: service.record(name), stop, deadline)


def _jsonl_writer(stop: threading.Event, json_of):
    def write(record: dict) -> None:
        try:
            sys.stdout.write(json_of(record) + "\n")
            sys.stdout.flush()
        except (BrokenPipeError, ValueError):  # the reader went away: stop the service
            stop.set()

    return write


def run_simulate(args: argparse.Namespace) -> int:
    """``hexapod simulate-encoders``."""
    with _logging("simulate-encoders", "INFO"):
        return _simulate(args)


def _simulate(args: argparse.Namespace) -> int:
    require_extra("service")
    from ..service import Simulator, load_config, load_simulation, open_bus

    config = load_config(args.config)
    sim_config = load_simulation(args.sim, config)
    b = config.bus
    if b.interface == "virtual":
        note("simulate-encoders", "the 'virtual' interface reaches buses of this process only")
    bus = open_bus(config, receive=False)
    stop = threading.Event()
    _stop_on_sigterm(stop)
    sim = Simulator(config, sim_config, bus, truth=1)
    try:
        sim.start(args.duration)
        while sim.running and not stop.wait(0.1):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        sim.stop()
        bus.shutdown()
    note("simulate-encoders", f"sent {sim.frames_sent} frames on {b.interface}/{b.channel}")
    return 0
