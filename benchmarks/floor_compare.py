"""The package's compiled direct kinematics against the reference floor (``floor_newton.py``), in one process.

Alternating rounds (the machine is shared: the load affects both alike), CPU time
(``time.thread_time_ns``):

* warm FK: ``Hexapod.forward`` along trajectory A at 1 kHz, each solve from the previous one,
  against ``floor_newton.fk_newton`` called from Python on the same readings (its state carried);
  microseconds per solve (median, p95) and the ratio (target: at most 1.5x the floor), the solve
  alone (``prove=False``), then with the Krawczyk proof every warm ``converged`` carries by default;
* ``forward_batch`` of box poses from home (cold) and of trajectory A (``warm=True``) against
  ``fk_batch_cold`` / ``fk_batch_warm``: solves per CPU second and the ratio (target: at least
  0.85x the floor), the solve alone (``prove=False``); then the warm rows with the Krawczyk
  proof each carries by default, beside it. Each side's call is timed right after a call of its
  own (:func:`steady_rate`): the throughput, not the caches' refill after the other work.

Both solve to ``BENCH_TOL``. The package solves without the body check (cones, clearance) unless
``--check-body``: the floor checks neither. Then where the package's time goes beside the floor's: the warm
solve's compiled call alone (the iteration, and the finish a ``Solution`` needs: Jacobian, pose,
limit check) and the Python around it; the warm step's Krawczyk proof and its compiled parts
(:func:`proof_breakdown`: the two interval enclosures and the per-leg algebra of one test); the rows
of the box whose certified first attempt fails (the certificate then follows the readings path,
:mod:`hexapod_model.kinematics.certificate`), how many of them fail at the attempt's first step,
and each part's throughput and Newton steps per row beside the floor's. The
figures of the first solves (compilation) are in ``startup.py --cold``.

    python benchmarks/floor_compare.py [--rounds 5] [--samples 1000]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import floor_newton as floor
import numpy as np
from compiled_newton import per_solve, rate

from hexapod_model import Hexapod
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics.newton.entries import plain
from hexapod_model.kinematics.newton.solver import MAX_STEP
from hexapod_model.studies.bench import BENCH_TOL, trajectory_readings

MAX_ITER = 50


def call_breakdown(hexa: Hexapod, readings: np.ndarray, first) -> dict[str, float]:
    """Median CPU microseconds of the warm solve's compiled call along ``readings``, with and without its finish.

    The call :meth:`Hexapod.forward` makes (the stroke check and the certified attempt, into new output arrays), from
    the previous solve's configuration; ``finish`` off leaves the Jacobian, pose and limit
    check out (the iteration alone).
    """
    solver = hexa.engine.solver(hexa.engine.held_forward)
    starts = [first]
    for x in readings[:-1]:
        starts.append(hexa.forward(x, starts[-1], tol=BENCH_TOL))
    times: dict[str, list[float]] = {"compiled_call": [], "iteration": []}
    for x, start in zip(readings, starts):
        for key, finish in (("compiled_call", 1.0), ("iteration", 0.0)):
            settings = solver._readings_settings.copy()  # the stroke held, as forward's call (attempt_readings)
            settings[:3], settings[5] = (BENCH_TOL, MAX_ITER, start.det_sign), finish
            outputs = solver._outputs()  # new arrays, as a Solution keeps them
            t0 = time.thread_time_ns()
            solver._kernel(start.q, x, settings, outputs)
            times[key].append((time.thread_time_ns() - t0) / 1e3)
    return {key: float(np.median(t)) for key, t in times.items()}


def _proof_kernels():
    """Loops of the warm step's proof's compiled parts, each ``n`` calls (compiled here, on first use)."""
    from numba import njit

    from hexapod_model.kinematics.newton.enclosure import enclose_into
    from hexapod_model.kinematics.newton.krawczyk_blocks import apply, krawczyk_blocks, setup, transform

    @njit
    def residual(n, tables, T0, x, l, work):  # F at the result, its rounding bounded (a point enclosure)
        placements, motions, closure, held, rows = tables
        V, Jm, Jr, _, H, _, ew = work
        for _ in range(n):
            enclose_into(placements, motions, closure, held, rows, T0, x, V[4], l, H[1], False, V[0], V[1], Jm, Jr, ew)

    @njit
    def jacobian(n, tables, T0, x, rho, hm, hr, work):  # F and the Jacobian over a box and the readings path
        placements, motions, closure, held, rows = tables
        V, Jm, Jr, _, _, _, ew = work
        for _ in range(n):
            enclose_into(placements, motions, closure, held, rows, T0, x, rho, hm, hr, True, V[2], V[3], Jm, Jr, ew)

    @njit
    def algebra(n, which, rows, rho, work):  # the per-leg preconditioner, Y J's blocks, the test, one Y v
        V, Jm, Jr, _, _, blocks, _ = work
        for _ in range(n):
            if which == 0:
                setup(Jm, rows, blocks)
            elif which == 1:
                transform(Jm, rows, blocks)
            elif which == 2:
                krawczyk_blocks(V[7], V[8], Jr, rows, blocks, rho, V[11], V[12])
            else:
                apply(blocks, rows, V[0], V[1], V[7], V[8])

    return residual, jacobian, algebra


def proof_breakdown(hexa: Hexapod, readings: np.ndarray, first, reps: int = 50) -> dict[str, float]:
    """Median CPU microseconds of the warm step's Krawczyk proof along ``readings`` and of its compiled parts.

    ``prove``: :meth:`StepProver.prove` as :meth:`Hexapod.forward` calls it (from the previous
    result), with the Python around its compiled call; ``compiled_call`` that call alone. The
    parts, each timed over ``reps`` calls on the step's own box (its radius 1.5 times the step
    in each unknown, the readings over the step): the residual's enclosure at the result (a
    point), the residual's and the Jacobian's over the box, the per-leg preconditioner from the
    Jacobian's midpoint, the per-leg blocks of ``Y J`` over the box, the Krawczyk test on them,
    and one product ``Y v``. A whole-path test runs the two enclosures, the blocks, two tests
    (the path's box, the end box) and three products, and the preconditioner only when the one
    held from the last step does not prove.
    """
    prover = hexa.engine.prover
    residual, jacobian, algebra = _proof_kernels()
    rows = prover.tables[4]
    steps = [first]
    for x in readings:
        steps.append(hexa.forward(x, steps[-1], tol=BENCH_TOL, prove=False))
    keys = ("residual", "jacobian", "preconditioner", "blocks", "test", "apply")
    times: dict[str, list[float]] = {k: [] for k in ("prove", *keys)}
    for a, b in zip(steps[:-1], steps[1:]):
        t0 = time.thread_time_ns()
        prover.prove(a.q, b.q)
        times["prove"].append((time.thread_time_ns() - t0) / 1e3)
    floats, ints, spec = prover.buffers()
    entry = prover._entry  # the compiled call that prove makes (set by its first call)
    times["compiled_call"] = []
    for a, b in zip(steps[:-1], steps[1:]):
        args = (floats, ints, spec, rows, prover.platform_q, plain(a.q), plain(b.q), True, True)
        t0 = time.thread_time_ns()
        entry(*args)
        times["compiled_call"].append((time.thread_time_ns() - t0) / 1e3)
    work = prover.work()[0]  # the thread's arrays (what they hold for the next proof is dropped)

    def per_call(kernel, *args) -> float:
        kernel(1, *args)  # compiled on its first use
        t0 = time.thread_time_ns()
        kernel(reps, *args)
        return (time.thread_time_ns() - t0) / 1e3 / reps

    for a, b in zip(steps[:-1], steps[1:]):
        T0 = prover.platform(b.q)
        x0, x1 = prover.unknowns(a.q, T0), prover.unknowns(b.q, T0)
        l0, l1 = a.q[prover.held_q], b.q[prover.held_q]
        rho = 1.5 * np.abs(x1 - x0) + 1e-12 * (1.0 + np.abs(x1))
        times["residual"].append(per_call(residual, prover.tables, T0, x1, l1, work))
        times["jacobian"].append(
            per_call(jacobian, prover.tables, T0, x1, rho, 0.5 * (l0 + l1), 0.5 * np.abs(l1 - l0), work)
        )
        for which, key in enumerate(("preconditioner", "blocks", "test", "apply")):
            times[key].append(per_call(algebra, which, rows, rho, work))
    prover.work()  # the arrays' region and preconditioner were overwritten: dropped
    out = {key: float(np.median(t)) for key, t in times.items()}
    # a whole-path test runs the two enclosures, the blocks, two tests (the path's box, the end box), three products
    out["whole_test_parts"] = (
        sum(out[k] for k in ("residual", "jacobian", "blocks")) + 2 * out["test"] + 3 * out["apply"]
    )
    return out


def uncertified_attempts(hexa: Hexapod, readings: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which rows' certified first attempt from home fails (the certificate follows their readings path).

    Returns:
        ``(failed, at_first)``: the rows whose attempt failed, and those whose attempt failed at
        its first Newton step (the step's own checks: no step taken, the whole attempt spent).
    """
    solver = hexa.engine.solver(hexa.engine.held_forward)
    home = hexa.closed_loop.q_home
    attempts = [solver.certified_forward(home, x, BENCH_TOL, MAX_ITER, solver.home_sign) for x in readings]
    failed = np.array([len(a) != 6 for a in attempts], dtype=bool)
    return failed, np.array([f and a[1] == 0 for f, a in zip(failed, attempts)], dtype=bool)


def steady_rate(call, n: int) -> float:
    """Solves per CPU second of ``call()`` run right after a call of its own (:func:`rate` of the second).

    The first call after other work (the warm FK's runs, the other side's call) refills the
    caches, which costs the same milliseconds whatever the call: on a call of a few
    milliseconds that would measure the refill, more for the side that runs first.
    """
    call()
    return rate(call, n)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--json", type=Path, help="also write the figures as JSON")
    ap.add_argument(
        "--check-body",
        action="store_true",
        help="judge every answer against the cones and collision bodies (default: off, the bare solve)",
    )
    args = ap.parse_args(argv)
    hexa = Hexapod.from_preset("reference", check_body=args.check_body)
    tables = floor.extract(hexa)
    _, warm = trajectory_readings(hexa)
    box = hexa.inverse_batch(box_poses(hexa.home_pose, args.samples, seed=0))
    cold = box.lengths[box.converged]
    Rh, ph = hexa.home_pose[:3, :3].copy(), hexa.home_pose[:3, 3].copy()
    J, G = np.zeros((6, 42)), np.zeros((1, 1))
    first = hexa.forward(warm[0], tol=BENCH_TOL)

    warm_steps = {"package": 0, "floor": 0}  # Newton steps of the last round's solves

    def package_warm(prove: bool = False) -> np.ndarray:
        """The warm solve alone (``prove=False``), or with the Krawczyk proof that every warm ``converged`` carries."""
        warm_steps["package"] = 0

        def solve(x, previous):
            sol = hexa.forward(x, previous or first, tol=BENCH_TOL, prove=prove)
            warm_steps["package"] += sol.iterations
            return sol

        return per_solve(solve, warm[1:])

    def floor_warm() -> np.ndarray:
        theta, R, p = np.zeros((6, 6)), Rh.copy(), ph.copy()
        floor.fk_newton(theta, R, p, hexa.joints_of(warm[0]), *tables, BENCH_TOL, MAX_ITER, MAX_STEP, J, G)
        settings, warm_steps["floor"] = (BENCH_TOL, MAX_ITER, MAX_STEP, J, G), 0

        def solve(x, _):
            warm_steps["floor"] += floor.fk_newton(theta, R, p, x, *tables, *settings)[0]

        return per_solve(solve, hexa.joints_of(warm[1:]))

    def floor_batch(rows: np.ndarray, warm_start: bool) -> np.ndarray:
        n, joints = len(rows), hexa.joints_of(rows)
        out = (np.empty((n, 3, 3)), np.empty((n, 3)), np.empty(n, dtype=np.int64))
        if warm_start:
            floor.fk_batch_warm(joints, np.zeros((6, 6)), Rh, ph, *tables, BENCH_TOL, MAX_ITER, MAX_STEP, *out)
        else:
            floor.fk_batch_cold(joints, *tables, Rh, ph, BENCH_TOL, MAX_ITER, MAX_STEP, *out)
        return out[2]  # Newton steps per row

    cases = {
        "forward_batch, box poses from home": (
            lambda: hexa.forward_batch(cold, tol=BENCH_TOL, prove=False),  # from home: no row is proven
            lambda: floor_batch(cold, False),
            len(cold),
        ),
        "forward_batch, trajectory A warm": (
            lambda: hexa.forward_batch(warm, warm=True, tol=BENCH_TOL, prove=False),
            lambda: floor_batch(warm, True),
            len(warm),
        ),
        "forward_batch, trajectory A warm, each row with its proof (the default)": (
            lambda: hexa.forward_batch(warm, warm=True, tol=BENCH_TOL),
            lambda: floor_batch(warm, True),
            len(warm),
        ),
    }
    steps = {}  # mean Newton steps per row: the package's certificate follows some rows' readings path
    for name, (package, reference, _) in cases.items():  # compile (or load) everything before timing
        steps[name] = (float(np.mean(package().iterations)), float(np.mean(reference())))
    fk: dict[str, list[np.ndarray]] = {"package": [], "floor": [], "proven": []}
    rates: dict[str, dict[str, list[float]]] = {name: {"package": [], "floor": []} for name in cases}
    package_warm(True)  # compile (or load) the proof
    for _ in range(args.rounds):
        fk["package"].append(package_warm())
        fk["floor"].append(floor_warm())
        fk["proven"].append(package_warm(True))
        for name, (package, reference, n) in cases.items():
            rates[name]["package"].append(steady_rate(package, n))
            rates[name]["floor"].append(steady_rate(reference, n))
    print(f"reference preset, tol {BENCH_TOL:g}: {args.rounds} alternating rounds, CPU time")
    best = {k: min(runs, key=np.median) for k, runs in fk.items()}
    print(f"{'warm FK, trajectory A (us/solve)':38s}{'median':>9s}{'p95':>9s}")
    for k in ("package", "floor"):
        print(f"  {k:36s}" + "".join(f"{np.percentile(best[k], q):9.1f}" for q in (50, 95)))
    ratio = np.median(best["package"]) / np.median(best["floor"])
    print(f"  ratio package / floor {ratio:.2f}x (target <= 1.5x; the solve alone, forward(prove=False))")
    proven = float(np.median(best["proven"]))
    print(
        f"  {'package with its Krawczyk proof':36s}"
        + "".join(f"{np.percentile(best['proven'], q):9.1f}" for q in (50, 95))
    )
    print(f"  ratio with the proof / floor {proven / np.median(best['floor']):.2f}x (the default forward)")
    a, b = (warm_steps[k] / (len(warm) - 1) for k in ("package", "floor"))
    print(f"  Newton steps per solve: package {a:.2f} (the certificate's), floor {b:.2f}")
    report: dict = {
        "warm_fk_us": {k: float(np.median(best[k])) for k in ("package", "floor")},
        "warm_fk_ratio": float(ratio),
        "warm_fk_proven_us": proven,
        "batch": {},
    }
    for name, r in rates.items():
        pkg, ref = max(r["package"]), max(r["floor"])
        label = f"{name} (solves/s)"
        target = "" if "proof" in name else " (target >= 0.85x)"  # the proof is counted beside the solve
        print(f"{label:38s} package {pkg:8.0f}  floor {ref:8.0f}  ratio {pkg / ref:.2f}x{target}")
        a, b = steps[name]
        per_step = (pkg * a) / (ref * b)
        print(f"{'':38s} Newton steps per row: package {a:.2f}, floor {b:.2f}; steps/s ratio {per_step:.2f}x")
        report["batch"][name] = {"package": pkg, "floor": ref, "ratio": pkg / ref}
    parts = call_breakdown(hexa, warm[1 : 1 + args.samples], first)
    python = report["warm_fk_us"]["package"] - parts["compiled_call"]
    print(f"warm FK, where the package's time goes (median us): compiled call {parts['compiled_call']:.1f}", end="")
    print(f" (iteration {parts['iteration']:.1f}, finish {parts['compiled_call'] - parts['iteration']:.1f});", end="")
    print(f" Python around it {python:.1f}")
    proof = proof_breakdown(hexa, warm[1 : 1 + min(args.samples, 200)], first)
    whole = proof["whole_test_parts"]
    call = proof["compiled_call"]
    print(f"warm FK's Krawczyk proof (median us): {proof['prove']:.1f}, its compiled call {call:.1f}: the", end="")
    print(f" residual at the result {proof['residual']:.1f}, the Jacobian over the step's box", end="")
    print(
        f" {proof['jacobian']:.1f}, Y J's per-leg blocks {proof['blocks']:.1f}, 2 tests {2.0 * proof['test']:.1f},",
        end="",
    )
    print(f" 3 products Y v {3.0 * proof['apply']:.1f} (sum {whole:.1f}; the rest, the step's unknowns and", end="")
    print(
        f" the path's term, {call - whole:.1f}); a preconditioner built afresh {proof['preconditioner']:.1f};", end=""
    )
    print(f" the floor's whole solve {report['warm_fk_us']['floor']:.1f}")
    report["warm_fk_proof_breakdown_us"] = proof
    failed, at_first = uncertified_attempts(hexa, cold)
    print(f"box poses from home: the certified first attempt fails on {failed.sum()} of {len(cold)} rows", end="")
    print(f" ({at_first.sum()} at its first step; the certificate follows their readings path);", end="")
    print(" forward_batch of each part against the floor, and its Newton steps per row:")
    report["warm_fk_breakdown_us"] = {**parts, "python": python}
    report["box_rows_following_the_path"] = int(failed.sum())
    for label, part in (("certified at once", cold[~failed]), ("following the path", cold[failed])):
        if not len(part):
            continue
        pkg_rates, ref_rates = [], []
        for _ in range(args.rounds):
            pkg_rates.append(steady_rate(lambda part=part: hexa.forward_batch(part, tol=BENCH_TOL), len(part)))
            ref_rates.append(steady_rate(lambda part=part: floor_batch(part, False), len(part)))
        pkg, ref = max(pkg_rates), max(ref_rates)
        a, b = (
            float(np.mean(hexa.forward_batch(part, tol=BENCH_TOL).iterations)),
            float(np.mean(floor_batch(part, False))),
        )
        print(f"  {label:36s} package {pkg:8.0f}  floor {ref:8.0f}  ratio {pkg / ref:.2f}x;", end="")
        print(f" steps per row: package {a:.2f}, floor {b:.2f}")
        report["batch"]["forward_batch, box poses from home"][label] = {
            "package": pkg,
            "floor": ref,
            "steps": {"package": a, "floor": b},
        }
    report["box_rows_failing_at_the_first_step"] = int(at_first.sum())
    if args.json:
        args.json.write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
