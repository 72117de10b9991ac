"""Start-up cost of a ``hexapod`` process against ``python -c "import pinocchio, numpy"``.

Runs the commands alternately in fresh processes: the baseline, the command (default ``hexapod fk``
on the example's rows) and ``hexapod urdf reference -o FILE`` (which compiles nothing: its cost is
what it imports; target: at most 3x the baseline's CPU), and prints, per command, the median wall
time, CPU time (user + sys, from ``os.wait4``), its ratio to the baseline's and the largest peak
RSS; ``--cold`` also runs
the command once with an empty numba cache (a temporary ``NUMBA_CACHE_DIR``: the first run after
installation, compiling every kernel it calls) and, each in a fresh process with an empty cache,
the CPU time of the first compiled solve (``Hexapod.from_preset("reference")``, then one
``forward``, then one ``inverse``, then a 3-row ``forward_batch``, then a warm ``forward`` whose
Krawczyk proof compiles, then a ``Tracker``'s first samples past settling; numba and the package
already imported) with the compilations over a second that the package did not announce (its
``hexapod_model.compile`` log line names each before it starts), that first forward split in
another such process (the solver's kernels alone, ``check_body=False``; then the body check's
kernels, a forward of a hexapod that checks it) beside the compilation of the
reference floor (``floor_newton.py``: the same iteration as one njit function, its first solve),
and their ratio. ``--phases`` also splits the first forward's and the floor's compile CPU by
numba pass (type inference, inlining, lowering) and LLVM (optimisation and machine code, under
numba's LLVM lock), and by compiled function (exclusive: what a function's own passes cost, its
callees not counted).

    python benchmarks/startup.py [--runs 7] [--cold] [--phases] [-- hexapod fk reference docs/examples/lengths.csv]
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASELINE = [sys.executable, "-c", "import pinocchio, numpy"]
COMMAND = [sys.executable, "-m", "hexapod_model", "fk", "reference", str(ROOT / "docs/examples/lengths.csv")]
#: writing a URDF (the output file is appended), and its target: CPU at most this many times the baseline's
URDF = [sys.executable, "-m", "hexapod_model", "urdf", "reference", "-o"]
URDF_TARGET = 3.0
FIRST_SOLVES = """
import sys, time
import logging
import numpy as np, numba
import numba.core.event as ev
import hexapod_model as hm
from hexapod_model.kinematics.newton import iteration
from hexapod_model.kinematics.newton.first_compile import ENTRIES, LOGGER
from hexapod_model.tracking.tracker import Tracker
said, unannounced = [], []  # the package's compile lines; compilations over 1 s no line named
class Said(logging.Handler):
    def emit(self, record):
        said.append(record.getMessage())
class Top(ev.Listener):  # each compilation started from Python (numba compiles its callees inside it)
    # announced: its own entry's line was said, or a line was said since the last one ended (the wait
    # that line announced goes on through the compilations that follow it without a line between)
    depth, heard = 0, 0
    def on_start(self, event):
        if self.depth == 0:
            self.name, self.t0 = event.data["dispatcher"].py_func.__name__, time.process_time()
            what = ENTRIES.get(self.name, ("?",))[0]
            self.told = len(said) > self.heard or any(f"({what})" in line for line in said)
        self.depth += 1
    def on_end(self, event):
        self.depth -= 1
        cpu = time.process_time() - self.t0
        if self.depth == 0:
            self.heard = len(said)
            if cpu > 1.0 and not self.told:
                unannounced.append(f"{self.name} {cpu:.1f} s")
logging.getLogger(LOGGER).addHandler(Said())
logging.getLogger(LOGGER).setLevel(logging.INFO)
ev.register("numba:compile", Top())
t0 = time.process_time()
h = hm.Hexapod.from_preset("reference")
s = h.forward(np.full(6, 0.01))
t1 = time.process_time()
b = h.inverse(s.pose)
t2 = time.process_time()
h.forward_batch(np.full((3, 6), 0.01))
t3 = time.process_time()
w = h.forward(np.full(6, 0.0101), s)  # a warm step: its Krawczyk proof (the default) compiles
t4 = time.process_time()
tracker = Tracker(h)
results = [tracker.step(np.full(6, 0.01 + 1e-6 * k)) for k in range(tracker.settings.settle_samples + 3)]
t5 = time.process_time()
assert s.converged and b.converged and w.proof is not None and w.proof.proven
assert results[-1].status == "ok" and "settling" not in results[-1].flags
print(t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4)
print("; ".join(unannounced) or "none")
"""
#: the first forward split: the solver's kernels alone (no body check), then the body check's kernels
#: (a hexapod that checks it, made before the clock starts: the solver's kernels are compiled by then)
FIRST_PARTS = """
import time
import numpy as np, numba
import hexapod_model as hm
from hexapod_model.kinematics.newton import iteration
t0 = time.process_time()
h = hm.Hexapod.from_preset("reference", check_body=False)
s = h.forward(np.full(6, 0.01))
t1 = time.process_time()
checked = hm.Hexapod.from_preset("reference")
t2 = time.process_time()
c = checked.forward(np.full(6, 0.01))
t3 = time.process_time()
assert s.converged and c.converged
print(t1 - t0, t3 - t2)
"""
FLOOR_SOLVE = """
import sys, time
import numpy as np, numba
import hexapod_model as hm
sys.path.insert(0, sys.argv[1])
import floor_newton as f
from hexapod_model.kinematics.newton.solver import MAX_STEP
h = hm.Hexapod.from_preset("reference")
tables = f.extract(h)
lengths, work = h.joints_of(np.full(6, 0.01)), (np.zeros((6, 42)), np.zeros((1, 1)))
R, p = h.home_pose[:3, :3].copy(), h.home_pose[:3, 3].copy()
t0 = time.process_time()
it, norm = f.fk_newton(np.zeros((6, 6)), R, p, lengths, *tables, 1e-12, 50, MAX_STEP, *work)
t1 = time.process_time()
assert norm <= 1e-12
print(t1 - t0)
"""

PHASES = """
import collections, json, sys, time
import numpy as np, numba
import numba.core.event as ev
import hexapod_model as hm
stack, passes, functions = [], collections.Counter(), collections.Counter()
class Timer(ev.Listener):
    def __init__(self, llvm):
        self.llvm = llvm
    def on_start(self, event):
        if self.llvm:
            key = ("LLVM", stack[-1][0][1] if stack else "?")
        else:
            key = (event.data["name"].split(" [")[0], event.data["qualname"].split(".")[-1])
        stack.append([key, time.process_time(), 0.0])
    def on_end(self, event):
        key, t0, inner = stack.pop()
        dt = time.process_time() - t0
        if stack:
            stack[-1][2] += dt
        passes[key[0]] += dt - inner
        functions[key[1]] += dt - inner
def first():
    if sys.argv[1] == "floor":
        sys.path.insert(0, sys.argv[2])
        import floor_newton as f
        from hexapod_model.kinematics.newton.solver import MAX_STEP
        h = hm.Hexapod.from_preset("reference")
        tables = f.extract(h)
        R, p = h.home_pose[:3, :3].copy(), h.home_pose[:3, 3].copy()
        f.fk_newton(np.zeros((6, 6)), R, p, h.joints_of(np.full(6, 0.01)), *tables, 1e-12, 50, MAX_STEP,
                    np.zeros((6, 42)), np.zeros((1, 1)))
    else:
        hm.Hexapod.from_preset("reference").forward(np.full(6, 0.01))
t0 = time.process_time()
with ev.install_listener("numba:run_pass", Timer(False)), ev.install_listener("numba:llvm_lock", Timer(True)):
    first()
print(json.dumps({"total": time.process_time() - t0, "passes": passes, "functions": functions}))
"""


def phases(env: dict) -> None:
    """Print the first forward's and the floor's compile CPU by numba pass and by compiled function."""
    bench = str(Path(__file__).resolve().parent)
    figures = {}
    for name in ("first forward", "floor"):
        cache = tempfile.mkdtemp(prefix="numba-cold-")
        try:
            cmd = [sys.executable, "-c", PHASES, name.split()[0], bench]
            out = subprocess.run(cmd, env=dict(env, NUMBA_CACHE_DIR=cache), capture_output=True, text=True)
        finally:
            shutil.rmtree(cache, ignore_errors=True)
        if out.returncode != 0:
            raise SystemExit(out.stderr[-800:])
        figures[name] = json.loads(out.stdout.splitlines()[-1])
    first, floor = figures["first forward"], figures["floor"]
    print(
        f"\ncompile CPU by phase (s, empty numba cache){'first forward':>16s}{'floor':>8s}\n"
        f"  {'all':42s}{first['total']:8.2f}{floor['total']:8.2f}"
    )
    for name, _ in collections.Counter(first["passes"]).most_common(8):
        print(f"  {name:42s}{first['passes'][name]:8.2f}{floor['passes'].get(name, 0.0):8.2f}")
    print("first forward by compiled function (s, its own passes and LLVM):")
    for name, cpu in collections.Counter(first["functions"]).most_common(10):
        print(f"  {name:42s}{cpu:8.2f}")


def run(cmd: list[str], env: dict | None = None) -> tuple[float, float, float]:
    """Wall time (s), CPU time (s) and peak RSS (MB) of one run of ``cmd``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {proc.stderr.read().decode()[-500:] if proc.stderr else ''}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def cold_run(code: str, env: dict, *args: str) -> list[str]:
    """The lines ``code`` prints, run in a fresh process with an empty numba cache."""
    cache = tempfile.mkdtemp(prefix="numba-cold-")
    try:
        out = subprocess.run(
            [sys.executable, "-c", code, *args], env=dict(env, NUMBA_CACHE_DIR=cache), capture_output=True, text=True
        )
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    if out.returncode != 0:
        raise SystemExit(out.stderr[-800:])
    return out.stdout.splitlines()


def cold_cpu(code: str, env: dict, *args: str) -> list[float]:
    """The figures ``code`` prints on its first line, run in a fresh process with an empty numba cache."""
    return [float(v) for v in cold_run(code, env, *args)[0].split()]


def median(values: list[float]) -> float:
    s = sorted(values)
    return s[len(s) // 2]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--cold", action="store_true", help="also time a first run with an empty numba cache")
    ap.add_argument("--phases", action="store_true", help="also split the first forward's compile CPU by phase")
    ap.add_argument("--json", type=Path, help="also write the figures as JSON")
    ap.add_argument("command", nargs="*", help="the command to time (default: hexapod fk reference lengths.csv)")
    args = ap.parse_args(argv)
    command = args.command or COMMAND
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    with tempfile.TemporaryDirectory(prefix="startup-") as tmp:
        commands = {"baseline": BASELINE, "command": command, "urdf": [*URDF, str(Path(tmp) / "reference.urdf")]}
        run(command, env)  # the numba cache is warm from here on
        results: dict[str, list[tuple[float, float, float]]] = {name: [] for name in commands}
        for _ in range(args.runs):  # alternate: the machine's load affects all alike
            for name, cmd in commands.items():
                results[name].append(run(cmd, env))
    base = [median([r[i] for r in results["baseline"]]) for i in range(2)]
    print(f"{'':34s}{'wall s':>9s}{'CPU s':>9s}{'peak MB':>9s}   (median of {args.runs}, alternating)")
    report: dict = {}
    labels = {"baseline": "python -c 'import pinocchio, numpy'", "command": " ".join(command[2:])}
    labels["urdf"] = " ".join(URDF[2:-1])
    for name, label in labels.items():
        wall, cpu = (median([r[i] for r in results[name]]) for i in range(2))
        rss = max(r[2] for r in results[name])
        target = f"   (target: x{URDF_TARGET:.0f} CPU)" if name == "urdf" else ""
        print(
            f"{label[:33]:34s}{wall:9.3f}{cpu:9.3f}{rss:9.0f}   x{wall / base[0]:.2f} wall, x{cpu / base[1]:.2f} CPU"
            + target
        )
        report[name] = {"label": label, "wall_s": wall, "cpu_s": cpu, "peak_mb": rss, "cpu_ratio": cpu / base[1]}
    if args.cold:
        cache = tempfile.mkdtemp(prefix="numba-cold-")
        try:
            wall, cpu, rss = run(command, dict(env, NUMBA_CACHE_DIR=cache))
        finally:
            shutil.rmtree(cache, ignore_errors=True)
        print(f"{'first run, empty numba cache':34s}{wall:9.3f}{cpu:9.3f}{rss:9.0f}")
        lines = cold_run(FIRST_SOLVES, env)
        forward, inverse, batch, proven, tracked = (float(v) for v in lines[0].split())
        solver, body = cold_cpu(FIRST_PARTS, env)
        (floor,) = cold_cpu(FLOOR_SOLVE, env, str(Path(__file__).resolve().parent))
        print("\nfirst compiled solves, empty numba cache (CPU s, numba and the package imported):")
        print(f"  Hexapod.from_preset + first forward {forward:8.2f}   x{forward / floor:.2f} the floor's compile")
        print(f"    (another process) without the body check {solver:8.2f}   x{solver / floor:.2f}")
        print(f"    then the body check's kernels     {body:8.2f}")
        print(f"  then first inverse                  {inverse:8.2f}")
        print(f"  then first forward_batch (3 rows)   {batch:8.2f}")
        print(f"  then first warm forward (its proof) {proven:8.2f}")
        print(f"  then a Tracker's first samples      {tracked:8.2f}")
        print(f"  compilations over 1 s that no line announced: {lines[1]}")
        print(f"  floor_newton.fk_newton first solve  {floor:8.2f}   (its compilation; target: first forward <= x1.5)")
        report["cold"] = {"first_forward_cpu_s": forward, "first_inverse_cpu_s": inverse, "first_batch_cpu_s": batch}
        report["cold"]["first_proven_cpu_s"] = proven
        report["cold"]["first_tracker_cpu_s"], report["cold"]["unannounced"] = tracked, lines[1]
        report["cold"]["first_solver_cpu_s"], report["cold"]["first_body_check_cpu_s"] = solver, body
        report["cold"]["floor_compile_cpu_s"] = floor
    if args.phases:
        phases(env)
    if args.json:
        args.json.write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
