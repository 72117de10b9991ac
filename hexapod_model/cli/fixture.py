"""`hexapod fixture status`, `history` (what the store holds); `acknowledge`, `target`, `recipe`, `locate`."""

from __future__ import annotations

import argparse
import datetime as dt
import math
import sys

import numpy as np

from ..exceptions import InputError
from ..extras import require_extra
from ..files import atomic_write_text, check_output_path
from ..io.tables import LENGTH_COLUMNS, POSE_COLUMNS
from .acknowledge import register_action

LOCK_COLUMNS = ["fixture", "t", "time", *POSE_COLUMNS, *LENGTH_COLUMNS, "status", "geometry_hash"]
LOCK_COLUMNS += ["target_id", "recipe"]  # the changeover target the lock met (empty: none)


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``fixture status``, ``history``, ``acknowledge``, ``target``, ``recipe`` and ``locate``."""
    p = sub.add_parser("fixture", help="stored lock poses and sample log of the pose service; targets and recipes")
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    s = actions.add_parser("status", help="the last stored lock pose of every fixture")
    s.add_argument("config", metavar="FIXTURE.toml")
    s.set_defaults(func=run_status)
    h = actions.add_parser("history", help="stored lock events (or the sample log) as CSV, or both as a ROS 2 bag")
    h.add_argument("config", metavar="FIXTURE.toml")
    h.add_argument("--since", metavar="T", help="from time T: Unix seconds or ISO 8601 (local time unless it says)")
    h.add_argument("--fixture", help="only this fixture")
    h.add_argument("--samples", action="store_true", help="the sample log instead of the lock events")
    h.add_argument("-o", "--output", metavar="LOG.csv", help="write the CSV here (default: stdout)")
    h.add_argument(
        "--mcap", metavar="OUT.mcap", help="write the sample log and lock events as a ROS 2 bag (MCAP) instead"
    )
    h.set_defaults(func=run_history)
    register_action(actions)
    from .changeover import register_actions

    register_actions(actions)


def parse_time(text: str) -> float:
    """Unix seconds of ``text`` (a number or an ISO 8601 date-time); :class:`InputError` otherwise."""
    try:
        return float(text)
    except ValueError:
        pass
    try:
        return dt.datetime.fromisoformat(text).timestamp()
    except ValueError:
        raise InputError(
            "--since", text, "expected Unix seconds or an ISO 8601 date-time such as 2026-05-01T12:00"
        ) from None


def iso(t: float) -> str:
    """Local ISO 8601 time of Unix seconds ``t`` (milliseconds)."""
    return dt.datetime.fromtimestamp(t).astimezone().isoformat(timespec="milliseconds")


def _open(args: argparse.Namespace):
    require_extra("service")
    from ..service import Store, load_config

    config = load_config(args.config)
    return config, Store(config.store.path, create=False)


def _rpy_deg(quaternion) -> np.ndarray:
    from ..lie import matrix_to_rpy, quaternion_to_matrix

    return np.degrees(matrix_to_rpy(quaternion_to_matrix(np.asarray(quaternion))))


def run_status(args: argparse.Namespace) -> int:
    """``hexapod fixture status``."""
    from ..service import geometry_hash

    config, store = _open(args)
    try:
        print(
            f"{'fixture':12s} {'locked at':29s} {'x (m)':>10s} {'y (m)':>10s} {'z (m)':>10s} "
            f"{'roll':>8s} {'pitch':>8s} {'yaw (deg)':>9s}  geometry"
        )
        for f in config.fixtures:
            e = store.last_lock(f.name)
            if e is None:
                print(f"{f.name:12s} no lock pose stored")
                continue
            same = e.geometry_hash == geometry_hash(f.load_hexapod())
            r = _rpy_deg(e.quaternion)
            print(
                f"{f.name:12s} {iso(e.t):29s} {e.position[0]:10.6f} {e.position[1]:10.6f} {e.position[2]:10.6f} "
                f"{r[0]:8.3f} {r[1]:8.3f} {r[2]:9.3f}  {'same' if same else 'CHANGED (pose not used)'}"
            )
    finally:
        store.close()
    return 0


def _fmt(v) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    if isinstance(v, float):
        return repr(float(v))  # round-trips: Unix times need 16 digits
    s = str(v)
    return '"' + s.replace('"', '""') + '"' if ("," in s or '"' in s) else s


def run_history(args: argparse.Namespace) -> int:
    """``hexapod fixture history``."""
    since = None if args.since is None else parse_time(args.since)
    if args.mcap:
        return _history_mcap(args, since)
    if args.output:
        check_output_path(args.output, args.config)
    config, store = _open(args)
    try:
        if args.fixture is not None and args.fixture not in [f.name for f in config.fixtures]:
            raise InputError("--fixture", args.fixture, f"not a fixture of {args.config}")
        if args.samples:
            from ..service.store.fixture_store import SAMPLE_COLUMNS

            header = list(SAMPLE_COLUMNS)
            rows = [list(r) for r in store.samples(args.fixture, since)]
        else:
            header = LOCK_COLUMNS
            rows = [
                [
                    e.fixture,
                    e.t,
                    iso(e.t),
                    *e.position,
                    *e.quaternion,
                    *_rpy_deg(e.quaternion),
                    *e.readings,
                    e.status,
                    e.geometry_hash,
                    e.target_id,
                    e.recipe,
                ]
                for e in store.locks(args.fixture, since)
            ]
    finally:
        store.close()
    text = "\n".join(",".join(_fmt(v) for v in row) for row in [header, *rows]) + "\n"
    if args.output:
        atomic_write_text(args.output, text)
        print(f"hexapod fixture history: wrote {len(rows)} rows to {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _history_mcap(args: argparse.Namespace, since: float | None) -> int:
    """``hexapod fixture history --mcap``: the store as a ROS 2 bag (hexapod_model.ros.bag)."""
    if args.output or args.samples:
        option = "-o" if args.output else "--samples"
        raise InputError(option, args.output or True, "--mcap writes the sample log and the lock events: leave it out")
    check_output_path(args.mcap, args.config)
    try:
        import cyclonedds  # noqa: F401 - the messages' CDR
        import mcap  # noqa: F401
        import rosbags  # noqa: F401 - the ROS 2 message definitions
    except ImportError as exc:
        raise InputError("--mcap", args.mcap, f"needs {exc.name}: pip install 'hexapod_model[ros]'") from None
    from ..ros.bag import messages, write_mcap
    from ..ros.names import FixtureNames

    config, store = _open(args)
    try:
        if args.fixture is not None and args.fixture not in [f.name for f in config.fixtures]:
            raise InputError("--fixture", args.fixture, f"not a fixture of {args.config}")
        namespace = config.ros.namespace if config.ros is not None else "hexapod"
        names = {
            f.name: FixtureNames.of(f.name, namespace, f.load_hexapod())
            for f in config.fixtures
            if args.fixture in (None, f.name)
        }
        items = messages(store.samples(args.fixture, since), store.locks(args.fixture, since), names)
    finally:
        store.close()
    count = write_mcap(args.mcap, items)
    print(f"hexapod fixture history: wrote {count} messages to {args.mcap}", file=sys.stderr)
    return 0
