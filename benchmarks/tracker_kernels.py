"""Where a tracker step's CPU goes: its compiled kernels, the Python between them, and one compiled call.

    python benchmarks/tracker_kernels.py [--steps 1000] [--fused] [--json F]

A moving stream (:func:`service.readings_sequence`: the service benchmark's readings, 1 kHz)
through one :class:`~hexapod_model.service.PoseSolver`, as the service's cycle steps it:

1. the step's CPU (``PoseSolver.step``: the tracker's step and the service's outcome);
2. each compiled kernel the step calls, timed inside the step (the thread's CPU clock around each
   call); the rest of the step is the Python around them (checks, results, bookkeeping), split by
   where it runs: before each kernel (from the step's start or the last kernel's end) and after
   the last, in the shares of the recorded steps' gaps (recording slows the Python between the
   kernels: its shares are kept, its sum is the step's);
3. the same kernels with the same arguments, replayed step after step from Python without the
   step's other work: what they cost when no Python runs between them (whose objects would
   otherwise evict their code and data from the caches);
4. with ``--fused``, one compiled function that calls them in the step's order, replayed the
   same way, and the CPU its compilation takes (numba compiles the kernels it calls again into
   the function's own module).

(3) and (4) are the cost floor of a step whose Python runs as compiled code: the per-set
pipeline of the service's edge budget. The kernels are timed by wrapping the library's
``direct`` (the machine code a kernel ran, see :mod:`hexapod_model.kinematics.newton.entries`)
and the tracker's module-level kernels before the hexapod and the solver are made; the step
itself runs unchanged. What the wrappers cost (a Python function that does nothing, called and
timed the same way) is taken off the kernels' and the step's figures. The collector is frozen
after the warm-up, as the service freezes it once started. Only the steps that call the most
common sequence of kernels (a moving step: no stuck leg, no re-anchoring) are counted.
"""

from __future__ import annotations

import argparse
import gc
import json
import sys
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np

import hexapod_model.tracking.tracker as tracker_module
from hexapod_model import Hexapod
from hexapod_model.kinematics.newton import entries
from hexapod_model.service import PoseSolver

WARM = 300  # steps before the measured ones (the kernels compiled or loaded, the stream moving)
_DIRECT = entries.direct  # the library's, untimed: the replays call the machine code it gives


class _Timed:
    """A kernel (machine code or dispatcher) that, while :attr:`recording`, logs each call's arguments and CPU."""

    recording = False
    log: list[tuple[str, Callable, tuple, int, int]] = []  # name, dispatcher, arguments, CPU (ns), start (ns)

    def __init__(self, name: str, dispatcher: Callable, code: Callable):
        self.name, self.dispatcher, self.code = name, dispatcher, code

    def __call__(self, *args):
        if not _Timed.recording:
            return self.code(*args)
        t = time.thread_time_ns()
        out = self.code(*args)
        _Timed.log.append((self.name, self.dispatcher, args, time.thread_time_ns() - t, t))
        return out

    def __getattr__(self, name: str):  # signatures, the cache: what the library asks a dispatcher
        return getattr(self.dispatcher, name)


def intercept() -> None:
    """Time every kernel the library calls through ``direct``, and the tracker's module-level kernels."""

    def timed_direct(dispatcher, args):
        if isinstance(dispatcher, _Timed):  # one of the tracker's: its machine code from now on, timed
            return _Timed(dispatcher.name, dispatcher.dispatcher, _DIRECT(dispatcher.dispatcher, args))
        name = getattr(getattr(dispatcher, "py_func", dispatcher), "__name__", repr(dispatcher))
        return _Timed(name, dispatcher, _DIRECT(dispatcher, args))

    # the modules imported so far, and entries itself: a module imported later (the solver's, when the
    # hexapod is made) takes the timed one from there
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("hexapod_model") and vars(module).get("direct") is _DIRECT:
            module.direct = timed_direct
    for name, value in list(vars(tracker_module).items()):
        if isinstance(value, numba.core.registry.CPUDispatcher):
            setattr(tracker_module, name, _Timed(name, value, value))


def cpu_per_call(call: Callable[[], None], calls: int, rounds: int = 5) -> float:
    """The least thread CPU (us) a call of ``call`` took over ``rounds`` rounds of ``calls`` calls."""
    best = np.inf
    for _ in range(rounds):
        t = time.thread_time_ns()
        for _ in range(calls):
            call()
        best = min(best, (time.thread_time_ns() - t) / calls / 1e3)
    return float(best)


def _noop(*args) -> None:
    return None


def wrapper_cost(calls: int = 20000) -> tuple[float, float, float]:
    """CPU (us) a :class:`_Timed` adds to a call: not recording; while recording, inside its window and outside it."""
    timed, args = _Timed("noop", _noop, _noop), (np.zeros(6), 0.0)
    off = cpu_per_call(lambda: timed(*args), calls) - cpu_per_call(lambda: _noop(*args), calls)
    _Timed.log, _Timed.recording = [], True
    gc.disable()  # as while the steps are recorded
    t = time.thread_time_ns()
    for _ in range(calls):
        timed(*args)
    recorded = (time.thread_time_ns() - t) / calls / 1e3
    gc.enable()
    _Timed.recording = False
    inside = float(np.median([c[3] for c in _Timed.log]) / 1e3)
    _Timed.log = []
    bare = cpu_per_call(lambda: _noop(*args), calls)
    return max(off, 0.0), inside, max(recorded - inside - bare, 0.0)


def call_names(sequence: tuple[str, ...]) -> list[str]:
    """A name for each call of ``sequence``: the kernel's; its second and later calls in a step ``name 2``, ..."""
    return [
        name if name not in sequence[:i] else f"{name} {sequence[: i + 1].count(name)}"
        for i, name in enumerate(sequence)
    ]


def measure(steps: int, fused: bool) -> dict:
    """The figures of the module docstring, for ``steps`` steps after a warm-up of :data:`WARM`."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from service import readings_sequence

    intercept()
    hexa = Hexapod.from_preset("reference")
    readings = readings_sequence(hexa)
    solver = PoseSolver(hexa, 10e-6)
    n = len(readings)
    for k in range(WARM):
        solver.step(readings[k % n], k)
    gc.collect()
    gc.freeze()  # as the service does once started: what is alive now is out of the collector's reach
    k0 = [WARM]

    def step() -> None:
        k = k0[0]
        solver.step(readings[k % n], k)
        k0[0] = k + 1

    step_us = cpu_per_call(step, steps, rounds=1)
    recorded, bounds = [], []
    gc.disable()  # the records' tuples would trigger collections inside the timed calls
    for _ in range(steps):
        _Timed.log = []
        _Timed.recording = True
        t = time.thread_time_ns()
        step()
        bounds.append((t, time.thread_time_ns()))
        _Timed.recording = False
        recorded.append(_Timed.log)
    gc.enable()
    off, inside, outside = wrapper_cost()
    sequence, _ = Counter(tuple(c[0] for c in calls) for calls in recorded).most_common(1)[0]
    chosen = [i for i, calls in enumerate(recorded) if tuple(c[0] for c in calls) == sequence]
    moving = [recorded[i] for i in chosen]
    # less the timing's own cost inside the window (a Python function that does nothing, timed the same way)
    keys = call_names(sequence)
    in_step = {key: float(np.mean([c[i][3] for c in moving]) / 1e3) - inside for i, key in enumerate(keys)}
    kernels_us = sum(in_step.values())
    step_us -= off * len(sequence)  # the wrappers' cost outside their windows
    # the Python before each call (from the step's start or the last call's end) and after the last: the
    # recorded steps' CPU between the timed windows, less a recording wrapper's cost outside its window,
    # in shares of the Python around the kernels (recording slows the steps' Python: its shares, not its sum)
    gaps = []
    for i, calls in zip(chosen, moving, strict=True):
        ends = [bounds[i][0]] + [c[4] + c[3] for c in calls]
        gaps.append([c[4] - end for c, end in zip(calls, ends, strict=False)] + [bounds[i][1] - ends[-1]])
    between = np.mean(np.array(gaps, dtype=float), axis=0) / 1e3
    between[:-1] -= outside  # a recording wrapper's cost before its window (its part after it: small)
    between = np.maximum(between, 0.0) * (step_us - kernels_us) / max(float(np.sum(between)), 1e-9)
    python_before = {key: float(us) for key, us in zip([*keys, "after the last"], between, strict=True)}
    codes = [_DIRECT(dispatcher, args) for _, dispatcher, args, *_ in moving[0]]
    argsets = [[c[2] for c in calls] for calls in moving]
    at = [0]

    def replay() -> None:  # the kernels of the steps in order, one step a call
        for code, args in zip(codes, argsets[at[0] % len(argsets)], strict=True):
            code(*args)
        at[0] += 1

    replayed_us = cpu_per_call(replay, len(argsets))
    report = {
        "steps": len(moving),
        "of": steps,
        "sequence": list(sequence),
        "step_us": step_us,
        "kernels_in_step_us": in_step,
        "kernels_in_step_total_us": kernels_us,
        "python_in_step_us": step_us - kernels_us,
        "python_before_us": python_before,  # the Python before each call, and after the last (recorded steps)
        "replayed_us": replayed_us,
        "wrapper_us": {"outside": off, "inside": inside, "outside_recording": outside},
    }
    if fused:
        names = [f"a{i}" for i in range(len(sequence))]
        source = f"def fused({', '.join(names)}):\n" + "".join(f"    k{i}(*a{i})\n" for i in range(len(names)))
        scope: dict = {f"k{i}": dispatcher for i, (_, dispatcher, *_) in enumerate(moving[0])}
        exec(source + "    return 0\n", scope)  # noqa: S102 - a call of each kernel, generated for this sequence
        function = numba.njit(scope["fused"])
        t = time.process_time()
        function(*argsets[0])
        report["fused_compile_s"] = time.process_time() - t
        code = _DIRECT(function, argsets[0])
        at[0] = 0

        def replay_fused() -> None:
            code(*argsets[at[0] % len(argsets)])
            at[0] += 1

        report["fused_us"] = cpu_per_call(replay_fused, len(argsets))
    return report


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=1000, help="steps measured after a warm-up of 300")
    ap.add_argument("--fused", action="store_true", help="also the kernels as one compiled call (compiles ~7 s)")
    ap.add_argument("--json", help="also write the figures as JSON")
    args = ap.parse_args(argv)
    r = measure(args.steps, args.fused)
    print(f"tracker step (PoseSolver.step), moving at 1 kHz: {r['step_us']:.1f} us CPU")
    print(f"its compiled kernels, timed inside the step ({r['steps']} of {r['of']} steps call this sequence):")
    for name, us in r["kernels_in_step_us"].items():
        print(f"  {name:24s}{us:7.1f} us")
    print(
        f"  {'together':24s}{r['kernels_in_step_total_us']:7.1f} us; "
        f"the Python around them {r['python_in_step_us']:.1f} us"
    )
    print("the Python around them, before each kernel and after the last (shares of the recorded steps' gaps):")
    print("  " + ", ".join(f"{name} {us:.1f}" for name, us in r["python_before_us"].items()) + " us")
    print(f"the same kernels replayed step after step, no Python between them: {r['replayed_us']:.1f} us a step")
    if "fused_us" in r:
        print(
            f"as one compiled call, replayed the same way: {r['fused_us']:.1f} us a step "
            f"(its compilation: {r['fused_compile_s']:.1f} s CPU)"
        )
    if args.json:
        Path(args.json).write_text(json.dumps(r, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
