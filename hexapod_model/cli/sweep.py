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
DIR/pareto.png the trade-off; a rerun computes only the candidates not yet done. With a
[placement] table, each candidate's redundant sensors (a measuring leg's anchors, an
inclinometer's mounting) are scored by the largest leg fault the consistency test may miss and
ranked into DIR/placement.csv."""


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
    placement = spec.placement
    figure = ""
    if placement is None or placement.workspace:
        from ..plots.sweep import plot_pareto

        png = Path(args.out) / "pareto.png"
        plot_pareto(rows, png)
        figure = f", figure {png}"
    invalid = [r for r in rows if r["status"] != "ok"]
    print(format_table(rows, list(spec.parameters), workspace=placement is None or placement.workspace))
    print(
        f"sweep: {len(rows)} candidates ({result['computed']} computed, {result['reused']} from earlier runs), "
        f"{len(invalid)} invalid; table {result['table']}{figure}"
    )
    if placement is not None and result["ranked"]:
        best = result["ranked"][0]
        worst_um = 1e6 * float(best["placement_worst_m"])
        print(
            f"placement: best {best['id']} (largest detectable leg fault {worst_um:.4g} um "
            f"over home +-{1e3 * placement.half_width:g} mm, {placement.grid}x{placement.grid} points); "
            f"ranked table {result['placement_table']}"
        )
    return 0


def _figure(value, scale: float = 1.0, digits: int = 4) -> str:
    """A table cell: ``value * scale`` to ``digits`` significant digits, ``-`` when missing."""
    try:
        return f"{float(value) * scale:.{digits}g}"
    except (TypeError, ValueError):
        return "-"


def format_table(rows: list[dict], parameters: list[str], workspace: bool = True) -> str:
    """The results table ``hexapod sweep`` prints: a line per candidate, ``*`` on the Pareto front.

    Columns: the id, the swept parameters (their units as in the spec), the workspace volume
    (cm^3), the largest leg force per unit force (N/N), the home condition number, the front
    mark; with a ``[placement]`` table, the placement score (um) and rank (1: best), and
    without the workspace figures when ``workspace`` is false; an invalid candidate shows its
    reason instead of figures.
    """
    placed = any("placement_worst_m" in r for r in rows)
    header = ["id", *parameters]
    if workspace:
        header += ["volume_cm3", "force_N_per_N", "home_kappa", "pareto"]
    if placed:
        header += ["worst_um", "rank"]
    body = []
    for r in rows:
        values = [str(r["id"]), *(_figure(r.get(p)) for p in parameters)]
        if r.get("status") != "ok":
            body.append([*values, f"{r.get('status')}: {r.get('reason')}"])
            continue
        if workspace:
            values += [_figure(r["volume_m3"], 1e6), _figure(r["force_per_force_max"]), _figure(r["home_kappa"])]
            values.append("*" if str(r.get("pareto")) == "True" else "")
        if placed:
            values += [_figure(r.get("placement_worst_m"), 1e6), str(r.get("placement_rank", "-"))]
        body.append(values)
    full = [line for line in [header, *body] if len(line) == len(header)]  # an invalid row ends on its reason
    width = [max(len(line[i]) for line in full) for i in range(len(header))]
    lines = []
    for line in [header, *body]:
        fixed = [c.rjust(width[i]) for i, c in enumerate(line) if len(line) == len(header) or i < len(line) - 1]
        lines.append("  ".join(fixed + ([] if len(line) == len(header) else [line[-1]])).rstrip())
    return "\n".join(lines)
