"""``hexapod sweep``: evaluate a family of candidate geometries on Dask, into one table and a Pareto figure."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..exceptions import InputError
from ..studies.cluster import dashboard_link
from ..studies.sweep import run_sweep
from ..studies.sweep_spec import load_spec
from ._common import note, stream_bar

DESCRIPTION = """\
Write every candidate geometry of SPEC.toml (a base geometry and the parameters to vary, as a
grid or a seeded random sample; docs/sweep.md) under DIR and evaluate it as `hexapod evaluate`
does (workspace volume for the tool cone, singular values and condition number over it), with
the largest leg force per unit wrench, the locked fixture's stiffness and the home conditioning.
Candidates run as Dask tasks: on a LocalCluster of this machine's cores, or on the cluster at
--scheduler. DIR/sweep.csv has one row per candidate (invalid ones with the reason),
DIR/pareto.png the trade-off; a rerun computes only the candidates not yet done."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``sweep``."""
    p = sub.add_parser("sweep", help="evaluate a family of candidate geometries on Dask", description=DESCRIPTION)
    p.add_argument("spec", metavar="SPEC.toml", help="the sweep's specification (docs/sweep.md)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created; a rerun resumes)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler, tcp://HOST:PORT")
    p.add_argument(
        "--workers", type=int, metavar="N", help="local worker processes without --scheduler (default: all cores)"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``hexapod sweep``."""
    if args.workers is not None and args.workers < 1:
        raise InputError("--workers", args.workers, "need at least 1")
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise InputError("--out", args.out, "is a file; name a folder")
    spec = load_spec(args.spec)
    try:
        Path(args.out).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError("--out", args.out, f"cannot create the folder: {exc.strerror or exc}") from None
    bar = stream_bar("sweep (candidates)", unit="candidate")

    def on_client(client) -> None:
        link = dashboard_link(client)
        note("sweep", f"Dask cluster {client.scheduler.address}" + (f", dashboard {link}" if link else ""))

    def on_progress(done: int, total: int) -> None:
        bar.total = total
        bar.n = done
        bar.refresh()

    try:
        result = run_sweep(spec, args.out, args.scheduler, args.workers, on_progress, on_client)
    except KeyboardInterrupt:
        note("sweep", f"interrupted; finished candidates saved, rerun with --out {args.out} to resume")
        return 130
    finally:
        bar.close()
    rows = result["rows"]
    from ..plots.sweep import plot_pareto

    png = Path(args.out) / "pareto.png"
    plot_pareto(rows, png)
    invalid = [r for r in rows if r["status"] != "ok"]
    print(
        f"sweep: {len(rows)} candidates ({result['computed']} computed, {result['reused']} from earlier runs), "
        f"{len(invalid)} invalid; table {result['table']}, figure {png}"
    )
    for r in invalid:
        print(f"  invalid {r['id']}: {r['reason']}")
    return 0
