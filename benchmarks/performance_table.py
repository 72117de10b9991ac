"""Regenerate docs/performance.md: the benchmark scripts' quick runs as one table.

    python benchmarks/performance_table.py [-o docs/performance.md] [--full] [--only SCRIPT ...]

Runs each benchmark script below in a fresh process with its quick settings (``--full``: the
scripts' defaults, many minutes), reads the JSON it writes and puts one row per figure into a
table: figure, value, the command that measured it, the machine and the date. ``--only`` reruns
the named scripts and keeps the other scripts' rows (their load and date with them) from the page,
on the machine that measured them only (the page names one machine for all its rows). Nothing is
typed in by hand; rerun it after a change that moves a figure. The figures are those of the
machine that ran it, under its load at the time (the ``load`` column: the 1-minute load average
before each command).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import platform
import shlex
import subprocess
import sys
import tempfile
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent


def bench_rows(data: list[dict]) -> list[tuple[str, str]]:
    """``run_benchmarks.py``: median and p99 per solve of warm FK, cold FK and IK."""
    cases = (("warm_fk", "warm FK at 1 kHz"), ("cold_fk", "cold FK from home"), ("ik", "IK"))
    return [
        (
            f"{r['hexapod']}: {label}, time per solve",
            f"median {r[key]['median_us']:.0f} µs, p99 {r[key]['p99_us']:.0f} µs "
            f"({r[key]['iterations_mean']:.1f} steps)",
        )
        for r in data
        for key, label in cases
    ]


def robustness_rows(data: list[dict]) -> list[tuple[str, str]]:
    """``robustness.py``: poses returned as good that are another assembly than the sampled one."""
    rows = []
    for r, mode in itertools.product(data, ("cold", "warm")):
        c, n = r[mode], r["within_limits"]
        figure = f"{r['preset']}: {mode} solves beyond the box, wrong pose returned as good"
        rows.append((figure, f"{c['other_unexplained']} of {n} ({c['ok']} ok, median {c['median_us']:.0f} µs)"))
    return rows


def _after_idle(r: dict) -> str:
    """A one-fixture run's ratio to its solve timed after the stream's idle gap (cold caches), or nothing."""
    if "solve_idle_us" not in r:
        return ""
    us = r["solve_idle_us"]
    return f"; {r['service_cpu_us_per_set'] / us:.1f}x the solve after the same idle gap, {us:.0f} µs"


def _frame_gap(r: dict) -> str:
    """``, a set's frames 130 µs apart`` for a fed run with ``--frame-gap`` (else empty)."""
    return f", a set's frames {r['frame_gap_us']:.0f} µs apart" if "frame_gap_us" in r else ""


def _paced(r: dict) -> str:
    """A fed run's set before the bus and threads: its cycles' work at the stream's pace and the bus's wake-ups."""
    if "paced_by_hand_us" not in r:
        return ""
    return (
        f"; its cycles handed their frames at the stream's pace, without the bus: {r['paced_by_hand_us']:.0f} µs a set "
        f"(back to back: {r['warm_by_hand_us']:.0f} µs), the bus's wake-ups alone: {r['wakeups_us']:.0f} µs a set"
        + (f" (frames delivered {r['frame_gap_delivered_us']:.0f} µs apart)" if "frame_gap_us" in r else "")
    )


def _backlog(r: dict) -> str:
    """For a run that fell behind: its CPU per set handled times the sets sent a second (over 100 % is possible)."""
    return "" if r["sustained"] else " needed by the sets sent"


def service_rows(data: list[dict]) -> list[tuple[str, str]]:
    """``service.py``: CPU share and latency of the fixture pose service per stream, then its capacity."""
    runs = [r for r in data if r.get("kind") != "capacity"]
    rows = [
        (
            f"pose service, {r['fixtures']} fixture(s) × {r['rate_hz']:.0f} Hz{_at_rest(r)}{_frame_gap(r)}",
            f"{r['service_cpu_pct']:.0f} % of a core{_backlog(r)} ({r['service_cpu_us_per_set']:.0f} µs a set, "
            f"{r['service_cpu_us_per_set'] / r['solve_us']:.1f}x its solve's {r['solve_us']:.0f} µs{_after_idle(r)}), "
            "latency median "
            f"{r['latency_ms_median']:.2f} ms, p99 {r['latency_ms_p99']:.1f} ms, "
            f"{'sustained' if r['sustained'] else 'not sustained'}{_warm_up(r)}{_paced(r)}",
        )
        for r in runs
    ]
    rows += [
        (
            f"pose service, {r['fixtures']} fixture(s) × {r['rate_hz']:.0f} Hz{_at_rest(r)} from a full queue "
            "(`--capacity`)",
            f"cycle thread {r['cycle_cpu_us_per_set']:.0f} µs CPU a set, "
            f"{r['cycle_cpu_us_per_set'] / r['solve_us']:.1f}x its solve's {r['solve_us']:.0f} µs "
            f"(the tracker step alone: {r['step_us']:.0f} µs{_in_turn(r)}{_by_hand(r)})",
        )
        for r in data
        if r.get("kind") == "capacity"
    ]
    return rows


def _warm_up(r: dict) -> str:
    """How long the fed run's warm-up took to catch up with the stream, or that it had not (at its limit)."""
    if "warm_up_s" not in r:
        return ""
    if not r["caught_up"]:
        return f" (measured still behind after a warm-up of {r['warm_up_s']:.0f} s)"
    return f" (measured after a warm-up of {r['warm_up_s']:.1f} s)"


def _by_hand(r: dict) -> str:
    """``; the cycles handed their frames, without the bus, the threads and the store: X µs`` (or empty)."""
    if "cycles_by_hand_us" not in r:
        return ""
    return (
        f"; the cycles handed their frames, without the bus, the threads and the store: {r['cycles_by_hand_us']:.0f} µs"
    )


def _in_turn(r: dict) -> str:
    """``; the N fixtures' steps in turn: X µs`` for a capacity run of several fixtures, else empty."""
    if r["fixtures"] == 1 or "steps_in_turn_us" not in r:
        return ""
    return f"; the {r['fixtures']} fixtures' steps in turn, without the bus: {r['steps_in_turn_us']:.0f} µs"


def _at_rest(r: dict) -> str:
    """`` at rest (1 µm counts)`` for a run of fixtures at rest (``--rest``), else empty."""
    return " at rest (1 µm counts)" if r.get("motion") == "rest" else ""


def memory_rows(data: list[dict]) -> list[tuple[str, str]]:
    """``service_memory.py``: the pose service's peak memory per fixture count, and per extra fixture."""
    rows = [(f"pose service, {r['fixtures']} fixture(s): peak RSS", f"{r['peak_mb']:.0f} MB") for r in data]
    if len(data) > 1:
        lo, hi = data[0], data[-1]
        per = (hi["peak_mb"] - lo["peak_mb"]) / (hi["fixtures"] - lo["fixtures"])
        rows.append(("pose service: peak RSS per extra fixture", f"{per:.1f} MB"))
    return rows


def calibration_rows(data: dict) -> list[tuple[str, str]]:
    """``calibration_study.py``: held-out pose errors before and after calibration, and its time."""
    cells = {
        key: f"{data[key]['translation_mean_mm']:.3f} mm, {data[key]['rotation_mean_deg']:.3f}°"
        for key in ("before (nominal, frames fitted)", "after (calibrated)", "true geometry")
    }
    return [(f"simulated calibration, held-out mean error {key}", value) for key, value in cells.items()] + [
        ("simulated calibration, identification and k-fold validation", f"{data['seconds']:.1f} s wall")
    ]


def startup_rows(data: dict) -> list[tuple[str, str]]:
    """``startup.py``: a short job's start-up against ``import pinocchio, numpy``, the first compilation."""
    base, cmd = data["baseline"], data["command"]
    rows = [
        (
            f"start-up of `{cmd['label'].replace(str(ROOT) + '/', '')}`",
            f"{cmd['wall_s']:.2f} s wall, {cmd['peak_mb']:.0f} MB peak "
            f"(`import pinocchio, numpy`: {base['wall_s']:.2f} s, {base['peak_mb']:.0f} MB)",
        )
    ]
    if "urdf" in data:
        urdf = data["urdf"]
        rows.append(
            (
                f"`{urdf['label']} -o FILE` (imports only, compiles nothing), CPU against `import pinocchio, numpy`",
                f"{urdf['cpu_s']:.2f} s vs {base['cpu_s']:.2f} s ({urdf['cpu_s'] / base['cpu_s']:.2f}x)",
            )
        )
    if "cold" in data:
        c = data["cold"]
        rows.append(
            (
                "first compiled forward after installation (empty numba cache), CPU",
                f"{c['first_forward_cpu_s']:.1f} s, {c['first_forward_cpu_s'] / c['floor_compile_cpu_s']:.2f}x the "
                f"one-function floor's compile ({c['floor_compile_cpu_s']:.1f} s); then inverse "
                f"{c['first_inverse_cpu_s']:.1f} s, forward_batch {c['first_batch_cpu_s']:.1f} s",
            )
        )
        if "first_solver_cpu_s" in c:
            solver, body = c["first_solver_cpu_s"], c["first_body_check_cpu_s"]
            rows.append(
                (
                    "the first compiled forward split: its solver's kernels, then its body check's "
                    "(empty numba cache), CPU",
                    f"{solver:.1f} s without the body check ({solver / c['floor_compile_cpu_s']:.2f}x the floor's "
                    f"compile), then the body check's kernels {body:.1f} s",
                )
            )
        if "first_proven_cpu_s" in c:
            rows.append(
                (
                    "then the first warm forward, its Krawczyk proof compiling (empty numba cache), CPU",
                    f"{c['first_proven_cpu_s']:.1f} s",
                )
            )
        if "unannounced" in c:
            rows.append(
                (
                    "then a Tracker's first samples (empty numba cache), CPU; the compilations over 1 s "
                    "the package did not announce",
                    f"{c['first_tracker_cpu_s']:.1f} s; unannounced: {c['unannounced']}",
                )
            )
    return rows


def floor_rows(data: dict) -> list[tuple[str, str]]:
    """``floor_compare.py``: warm FK and batch throughput against the one-function floor."""
    w = data["warm_fk_us"]
    rows = [
        (
            "reference: warm FK against the floor, CPU per solve",
            f"{w['package']:.1f} µs vs {w['floor']:.1f} µs ({data['warm_fk_ratio']:.2f}x)",
        )
    ]
    if "warm_fk_proven_us" in data:
        p = data["warm_fk_proven_us"]
        rows.append(
            (
                "reference: warm FK with its Krawczyk proof (the default), CPU per solve",
                f"{p:.1f} µs vs the floor's {w['floor']:.1f} µs ({p / w['floor']:.2f}x)",
            )
        )
    if "warm_fk_proof_breakdown_us" in data:
        b = data["warm_fk_proof_breakdown_us"]
        rows.append(
            (
                "reference: warm FK's Krawczyk proof, where its time goes, CPU (medians)",
                f"{b['prove']:.1f} µs, of which the compiled call {b['compiled_call']:.1f} µs: the "
                f"residual's enclosure at the result {b['residual']:.1f}, the Jacobian's over the step's "
                f"box {b['jacobian']:.1f}, the per-leg blocks of Y J {b['blocks']:.1f}, two Krawczyk tests "
                f"{2.0 * b['test']:.1f}, three products Y v {3.0 * b['apply']:.1f} (the rest "
                f"{b['compiled_call'] - b['whole_test_parts']:.1f}); a preconditioner built afresh "
                f"{b['preconditioner']:.1f}; "
                f"the floor's whole solve {w['floor']:.1f} µs",
            )
        )
    rows += [
        (f"reference: {name} against the floor", f"{r['package']:.0f}/s vs {r['floor']:.0f}/s ({r['ratio']:.2f}x)")
        for name, r in data["batch"].items()
    ]
    return rows


def clearance_rows(data: dict) -> list[tuple[str, str]]:
    """``clearance.py``: the clearance query and the body check against a warm forward solve."""
    us = data["us"]

    def cell(name: str) -> str:
        return f"median {us[name]['median']:.1f} µs, p99 {us[name]['p99']:.1f} µs"

    bare, checked = us["trajectory A, check_body=False"], us["trajectory A, check_body=True"]
    query = f"{cell('clearance: Hexapod.clearance')} ({data['query_ratio']['trajectory A']:.2f}x the bare warm FK)"
    return [
        ("reference: clearance query (Hexapod.clearance), time per query", query),
        ("reference: clearance query, its compiled kernel call alone", cell("clearance: kernel call")),
        (f"reference: coal's distance on every pair ({data['pairs']} pairs)", cell("clearance: coal, every pair")),
        ("reference: body check of one answer (cones and collisions)", cell("body check: one call")),
        (
            "reference: warm FK along trajectory A, without / with the body check, CPU per solve",
            f"{bare['median']:.1f} µs / {checked['median']:.1f} µs ({data['check_ratio']['trajectory A']:.2f}x)",
        ),
    ]


def certificate_rows(data: dict) -> list[tuple[str, str]]:
    """``certificate.py``: the proof's proven fraction and its cost per warm step beside the floor's."""
    rows = []
    for t in data["trajectories"]:
        where = f"{t['preset']}: trajectory {t['trajectory']} at 1 kHz"
        rows.append((f"{where}, warm steps proven (Krawczyk)", f"{100 * t['proven_fraction']:.2f} % of {t['steps']}"))
        step = t["forward_proven_median_us"]
        value = f"{step:.0f} µs forward with its proof, {t['solve_median_us']:.0f} µs the solve alone (medians)"
        if not math.isnan(t["floor_median_us"]):  # NaN: the floor does not read this preset's legs
            value += f"; floor {t['floor_median_us']:.1f} µs ({step / t['floor_median_us']:.1f}x)"
        else:
            value += "; no floor for this preset"
        rows.append((f"{where}, warm step with its proof, time per step", value))
    for r in data.get("rest", []):
        where = f"{r['preset']}: at rest, {r['noise_m'] * 1e6:g} µm noise"
        value = (
            f"{100 * r['proven_fraction']:.2f} % proven, {100 * r['in_region_fraction']:.2f} % in a region; "
            f"{r['forward_proven_median_us']:.0f} µs forward with its proof (each step its own test: "
            f"{r['forward_own_test_median_us']:.0f} µs), {r['solve_median_us']:.0f} µs the solve alone (medians)"
        )
        if not math.isnan(r["floor_median_us"]):
            ratio = r["forward_proven_median_us"] / r["floor_median_us"]
            value += f"; floor {r['floor_median_us']:.1f} µs ({ratio:.1f}x)"
        rows.append((f"{where}, warm step with its proof (regions), time per step", value))
    for r in data.get("rest_streams", []):
        noise = f"{r['noise_m'] * 1e6:g} µm noise, {r['resolution_m'] * 1e6:g} µm counts"
        where = f"{r['preset']}: {r['fixtures']} fixtures at rest, {noise}, trackers stepped in turn"
        value = (
            f"{r['step_median_us']:.0f} µs a step (one fixture alone: {r['alone_step_median_us']:.0f} µs; medians); "
            f"{100 * r['proven_fraction']:.2f} % proven, {100 * r['in_region_fraction']:.2f} % in its region "
            f"(alone: {100 * r['alone_in_region_fraction']:.2f} %)"
        )
        rows.append((f"{where}, time per step", value))
    for r in data.get("tracker", []):
        where = f"{r['preset']}: trajectory A at 1 kHz, the tracker (eq22)"
        value = (
            f"{r['step_median_us']:.0f} µs a step; its solve from the prediction "
            f"{r['forward_proven_median_us']:.0f} µs with its proof, {r['solve_median_us']:.0f} µs alone (medians); "
            f"{100 * r['proven_fraction']:.2f} % proven, {100 * r['in_region_fraction']:.2f} % in a region"
        )
        rows.append((f"{where}, time per step", value))
    for r in data.get("far", []):
        rows.append(
            (
                f"{r['preset']}: warm FK from a far guess (random poses in turn, readings "
                f"{1e3 * r['median_reading_change_m']:.0f} mm apart), proven in steps",
                f"{r['forward_median_ms']:.1f} ms a solve, {r['median_steps']:g} proven steps, "
                f"{r['median_tests']:g} Krawczyk tests (medians); {r['tests_per_step']:.1f} tests a step; "
                f"{100 * r['converged_fraction']:.0f} % of {r['solves']} converged",
            )
        )
    return rows


def false_alarm_rows(data: list[dict]) -> list[tuple[str, str]]:
    """``false_alarm_hour.py``: the consistency test's false alarms on clean samples, beside the stated rate."""
    rows = []
    for c in data:
        lo, hi = c["ci95"]
        verdict = "consistent" if c["consistent"] else "NOT consistent"
        rows.append(
            (
                f"{c['preset']}: consistency test on clean samples at 100 Hz, {c['motion']}, false alarms",
                f"{c['alarms']} of {c['samples']} ({c['rate']:.2e}; 95 % interval {lo:.2e}–{hi:.2e}),"
                f" stated {c['alpha']:g}: {verdict}",
            )
        )
    return rows


def _python_before(r: dict) -> str:
    """`` (before solve_schur 7.2, ...)``: the tracker step's Python by where it runs, the largest first (or empty)."""
    if "python_before_us" not in r:
        return ""
    parts = sorted(r["python_before_us"].items(), key=lambda kv: -kv[1])
    return " (" + ", ".join(f"{'' if n == 'after the last' else 'before '}{n} {us:.1f}" for n, us in parts[:5]) + ")"


def tracker_kernel_rows(r: dict) -> list[tuple[str, str]]:
    """``tracker_kernels.py``: a moving tracker step's compiled kernels, the Python around them, and their floor."""
    parts = sorted(r["kernels_in_step_us"].items(), key=lambda kv: -kv[1])
    named = ", ".join(f"{name} {us:.1f}" for name, us in parts[:5])
    fused = (
        f", as one compiled call {r['fused_us']:.1f} µs (compiled in {r['fused_compile_s']:.1f} s CPU)"
        if "fused_us" in r
        else ""
    )
    return [
        (
            "reference: tracker step, moving at 1 kHz, where its CPU goes",
            f"{r['step_us']:.1f} µs: its {len(r['sequence'])} compiled kernels {r['kernels_in_step_total_us']:.1f} µs "
            f"inside the step ({named}, the rest less), the Python around them {r['python_in_step_us']:.1f} µs"
            f"{_python_before(r)}",
        ),
        (
            "reference: tracker step's compiled kernels without the Python between them, CPU a step",
            f"{r['replayed_us']:.1f} µs replayed from Python one after another{fused}; "
            f"{r['kernels_in_step_total_us']:.1f} µs inside the step",
        ),
    ]


#: (script and its quick arguments, its full arguments, the rows of its JSON)
BENCHMARKS: list[tuple[list[str], list[str], Callable[[Any], list[tuple[str, str]]]]] = [
    (["run_benchmarks.py", "reference", "--samples", "300"], ["run_benchmarks.py"], bench_rows),
    (["floor_compare.py", "--rounds", "2", "--samples", "300"], ["floor_compare.py"], floor_rows),
    (["startup.py", "--runs", "3", "--cold"], ["startup.py", "--cold"], startup_rows),
    (["robustness.py", "reference", "--poses", "300"], ["robustness.py"], robustness_rows),
    (
        ["calibration_study.py", "--poses", "60", "--folds", "3", "--hold", "*_axis.*"],
        ["calibration_study.py"],
        calibration_rows,
    ),
    (
        [
            "service.py",
            "--seconds",
            "2",
            "--one",
            "1000",
            "--many",
            "100",
            "--fixtures",
            "50",
            "--more",
            "5:1000",
            "--capacity",
            "--rest",
        ],
        ["service.py"],
        service_rows,
    ),
    (  # one fixture at 1 kHz on a bus that carries a set's frames one after another (1 Mbit/s)
        ["service.py", "--seconds", "2", "--one", "1000", "--many", "", "--frame-gap", "130"],
        ["service.py", "--one", "1000", "--many", "", "--frame-gap", "130"],
        service_rows,
    ),
    (["service_memory.py", "--fixtures", "1,20", "--sets", "100"], ["service_memory.py"], memory_rows),
    (["tracker_kernels.py", "--fused"], ["tracker_kernels.py", "--fused", "--steps", "5000"], tracker_kernel_rows),
    (["clearance.py", "--poses", "1000"], ["clearance.py"], clearance_rows),
    (["certificate.py", "--poses", "0"], ["certificate.py"], certificate_rows),  # every six-reading preset
    (["false_alarm_hour.py", "--seconds", "900"], ["false_alarm_hour.py"], false_alarm_rows),
]


def machine() -> str:
    """The machine in a few words: processor, cores, memory, Python."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = ""
    try:
        kb = int(Path("/proc/meminfo").read_text().split()[1])
        mem = f", {kb / 2**20:.0f} GB"
    except (OSError, ValueError, IndexError):
        pass
    return f"{cpu}, {os.cpu_count()} cores{mem}, Python {platform.python_version()}"


def page_machine(text: str) -> str | None:
    """The machine a page this script wrote names (None: it names none)."""
    for line in text.splitlines():
        if line.startswith("Machine: "):
            return line.removeprefix("Machine: ").removesuffix(".")
    return None


def page_rows(text: str) -> list[tuple[str, str, str, str, str]]:
    """The rows (figure, value, command, load, date) of a page this script wrote."""
    rows = []
    for line in text.splitlines():
        cells = line.removeprefix("| ").removesuffix(" |").split(" | ")
        if line.startswith("| ") and len(cells) == 5 and cells[2].startswith("`python benchmarks/"):
            rows.append((cells[0], cells[1], cells[2], cells[3], cells[4]))
    return rows


def measure(full: bool, only: set[str] | None = None, page_text: str = "") -> list[tuple[str, str, str, str, str]]:
    """Run every benchmark, or those named in ``only`` keeping the others' rows of ``page_text``.

    Returns:
        Rows of (figure, value, command, load, date), in the order of :data:`BENCHMARKS`.
    """
    rows = []
    kept = page_rows(page_text)
    with tempfile.TemporaryDirectory() as tmp:
        for quick, long, parse in BENCHMARKS:
            args = long if full else quick
            command = "`python benchmarks/" + " ".join(shlex.quote(a) for a in args) + "`"
            if only is not None and args[0] not in only:
                old = [r for r in kept if r[2] == command]
                if not old:
                    raise SystemExit(f"the page has no rows of {command}: name {args[0]} in --only too")
                rows += old
                continue
            out = Path(tmp) / "out.json"
            load = f"{os.getloadavg()[0]:.1f}"
            date = datetime.now(UTC).strftime("%Y-%m-%d")
            subprocess.run(
                [sys.executable, str(ROOT / "benchmarks" / args[0]), *args[1:], "--json", str(out)],
                cwd=ROOT,
                check=True,
                stdout=subprocess.DEVNULL,
            )
            rows += [(f, v, command, load, date) for f, v in parse(json.loads(out.read_text()))]
    return rows


def page(rows: list[tuple[str, str, str, str, str]], where: str) -> str:
    """docs/performance.md."""
    lines = [
        "# Performance",
        "",
        "Generated by `python benchmarks/performance_table.py` from the benchmark scripts' quick runs;",
        "do not edit by hand. Each figure is of the machine below, under its load at the time (the",
        "1-minute load average before the command). The scripts print more than this table: run one",
        "for its details, or with its default settings for more samples.",
        "",
        f"Machine: {where}.",
        "",
        "| figure | value | command | load | date |",
        "|---|---|---|---|---|",
    ]
    lines += [f"| {' | '.join(r)} |" for r in rows]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "docs" / "performance.md")
    ap.add_argument("--full", action="store_true", help="the scripts' default settings (many minutes)")
    ap.add_argument(
        "--only",
        nargs="+",
        metavar="SCRIPT",
        help="rerun these scripts only (e.g. startup.py); the others' rows are kept from the page as they are",
    )
    args = ap.parse_args(argv)
    only = None
    if args.only:
        if not args.output.is_file():
            ap.error(f"--only: {args.output} does not exist; run every script")
        only = set(args.only)
        unknown = sorted(only - {quick[0] for quick, _, _ in BENCHMARKS})
        if unknown:
            ap.error(f"--only {' '.join(unknown)}: not a script of the table")
    here, kept = machine(), args.output.read_text() if only else ""
    measured = page_machine(kept)
    if only and measured != here:  # the kept rows would be labelled with this machine
        raise SystemExit(f"--only: {args.output} was measured on {measured}, this machine is {here}: run every script")
    text = page(measure(args.full, only, kept), here)
    tmp = args.output.with_suffix(".tmp")
    tmp.write_text(text)
    tmp.replace(args.output)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
