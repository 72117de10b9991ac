"""What the assembly check of direct kinematics costs and how often it refuses, per preset.

    python benchmarks/certificate.py [PRESET ...] [--poses N] [--seed S] [--warm-offset M] [--trajectory-samples K]
        [--rest-samples R] [--far-guesses F] [--json FILE]

For ``N`` random poses per preset (home +- 50 mm, roll/pitch/yaw +- 25 deg, within the limits),
the readings are solved cold (from home) and warm (from the pose moved by ``warm-offset`` m) by

* the plain Newton iteration (``NewtonSolver.iterate`` without the check), and
* the checked first attempt (``certified_forward``: the same iteration with the contraction
  and determinant-sign checks), then ``Hexapod.forward`` as a whole.

It prints per preset and mode the median time of each, and the *refusals*: solves whose
checked first attempt fails (the readings path is then followed in substeps), and those whose
final status is not ``converged``. The check is a heuristic (docs/solver.md): these figures
measure its cost and how often it declines, not what it proves.

Then the **proof** (which ``Hexapod.forward`` runs on every warm step, the Krawczyk test of
:mod:`hexapod_model.kinematics.newton.krawczyk`) along trajectories A and B
(:func:`hexapod_model.analysis.trajectories.trajectory_poses`, scaled to the preset, sampled at
1 kHz, the first ``K`` samples): per preset and trajectory the fraction of warm steps proven,
the median subdivisions, the median time of the warm ``forward`` with its proof (the default)
and of the solve alone (``prove=False``), of the proof by itself (the per-leg test, and beside it
the dense reference test on the same solves, with its proven fraction), each kind of call in
passes of its own along the trajectory (what a proof keeps for the next step, a region or its
preconditioner, is then the stream's own, as a caller's), and the
floor (``floor_newton.fk_newton``, the reference Newton iteration in one njit function, on the
offset-Cardan presets whose legs it reads) on the same readings.

Then a fixture **at rest** (``R`` samples of one pose with 1 um of noise on each reading): the
proven fraction, the fraction proven in a region an earlier step proved, and the warm
``forward`` with its proof beside the same with every step proven by its own test.

Then **fixtures at rest stepped in turn**: trackers of 5 fixtures at rest, each at a pose of its
own, their readings encoder counts (1 um of noise, 1 um counts: a leg repeats its count often),
stepped in turn on one thread as the service's cycle steps a cell's fixtures (each keeps its
region and preconditioner apart), beside one fixture's tracker stepped alone.

Then the **tracker** (:class:`hexapod_model.tracking.tracker.Tracker`, its default predictor) along
trajectory A at 1 kHz: the proven fraction of its samples, the median step, and the solve it
makes (from the prediction) with its proof and alone.

Then **far guesses**: ``F`` random poses (as above) solved in turn, each warm from the one before (a
guess about 0.1 m and 0.2 rad away): the whole step cannot be proven by one test, so ``forward``
follows it in proven steps (:func:`hexapod_model.kinematics.connected.connected_chain`): the
median time of such a ``forward``, its proven steps and Krawczyk tests, and the tests per step.

``--json`` also writes the figures (``benchmarks/performance_table.py`` reads it); ``--poses 0``
measures the proof alone.
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter, deque
from pathlib import Path

import numpy as np

from hexapod_model import Hexapod
from hexapod_model.analysis.trajectories import box_poses, trajectory_poses
from hexapod_model.description.presets import PRESETS, get_preset
from hexapod_model.kinematics.newton.solver import MAX_STEP
from hexapod_model.tracking.tracker import Tracker, predict


def run(name: str, n: int, seed: int, offset: float) -> dict:
    """Median times (us) and refusal counts of cold and warm solves of preset ``name``."""
    hexa = Hexapod.load(name)
    solver = hexa.engine.solver(hexa.engine.held_forward)
    rng = np.random.default_rng(seed + 1)
    hexa.forward(np.zeros(6))  # compile / warm up
    out: dict = {"preset": name}
    times: dict[str, dict[str, list[float]]] = {
        m: {"plain": [], "checked": [], "forward": []} for m in ("cold", "warm")
    }
    counts = {"cold": Counter(), "warm": Counter()}
    for T in box_poses(hexa.home_pose, n, seed, 0.05, 25.0):
        truth = hexa.inverse(T, check=False)
        if not truth.converged:
            continue
        d = rng.normal(size=3)
        moved = T.copy()
        moved[:3, 3] += offset * d / np.linalg.norm(d)
        near = hexa.inverse(moved, check=False)
        starts = {"cold": None}
        if near.converged:
            starts["warm"] = near
        for mode, guess in starts.items():
            joints = hexa.joints_of(truth.lengths)
            start = hexa.engine.start(guess)
            sign = solver.home_sign if guess is None else guess.det_sign
            q0 = start.copy()
            q0[hexa.closed_loop.prismatic_q] = joints
            t0 = time.perf_counter()
            solver.iterate(q0, 1e-12, 20)
            t1 = time.perf_counter()
            attempt = solver.certified_forward(start, joints, 1e-12, 20, sign)
            t2 = time.perf_counter()
            sol = hexa.forward(truth.lengths, guess, check=False)
            t3 = time.perf_counter()
            times[mode]["plain"].append(t1 - t0)
            times[mode]["checked"].append(t2 - t1)
            times[mode]["forward"].append(t3 - t2)
            counts[mode]["solves"] += 1
            counts[mode]["first_attempt_refused"] += len(attempt) != 6
            counts[mode]["not_converged"] += sol.status != "converged"
    for mode in ("cold", "warm"):
        out[mode] = dict(counts[mode])
        for key, values in times[mode].items():
            out[mode][f"{key}_median_us"] = float(np.median(values) * 1e6) if values else float("nan")
    return out


def floor_times(hexa: Hexapod, readings: np.ndarray) -> list[float]:
    """Per-step times (s) of the floor's warm Newton solve along ``readings``, or [] where it does not apply."""
    try:
        import floor_newton as floor

        tables = floor.extract(hexa)
    except (AssertionError, ImportError, KeyError):
        return []
    theta, R, p = np.zeros((6, 6)), hexa.home_pose[:3, :3].copy(), hexa.home_pose[:3, 3].copy()
    J, G = np.zeros((6, 42)), np.zeros((1, 1))
    joints = hexa.joints_of(readings)
    floor.fk_newton(theta, R, p, joints[0], *tables, 1e-12, 50, MAX_STEP, J, G)
    out = []
    for x in joints[1:]:
        t0 = time.perf_counter()
        floor.fk_newton(theta, R, p, x, *tables, 1e-12, 50, MAX_STEP, J, G)
        out.append(time.perf_counter() - t0)
    return out


def limited_readings(hexa: Hexapod, which: str, samples: int) -> tuple[np.ndarray, int | None]:
    """Readings of trajectory ``which`` at 1 kHz (its first ``samples``) up to the first pose outside the limits.

    Returns the (n, 6) readings (m) and the index of that first pose (None when all are inside).
    """
    _, poses = trajectory_poses(which, hexa.home_pose, hexa.base_radius / 50.0, 1000.0)
    ik = hexa.inverse_batch(poses[:samples])
    inside = np.asarray(ik.converged, dtype=bool)
    if inside.all():
        return ik.lengths, None
    stop = int(np.argmin(inside))
    return ik.lengths[:stop], stop


def trajectory_proofs(name: str, which: str, samples: int, rounds: int = 2) -> dict:
    """Proven fractions and per-step medians (us) of warm solves along trajectory ``which`` at 1 kHz.

    Each kind of call runs in passes of its own over the whole trajectory, as a stream of warm
    steps that a caller makes: what a proof keeps from one step for the next (a region it
    proved, the preconditioner it built, the last step's readings) and the caches are the
    stream's own, never those of another kind of call between two steps. ``rounds`` passes
    each, alternating, of ``forward`` with its proof (the default), chained from its own
    results, and of the solve alone (``prove=False``); then ``StepProver.prove`` on the steps
    of the first proven pass, in order, as ``forward`` calls it (the per-leg test), and the
    dense reference test on the same steps.
    """
    hexa = Hexapod.load(name)
    prover = hexa.engine.prover
    readings, outside_from = limited_readings(hexa, which, samples)
    sol = hexa.forward(readings[0], check=False)
    first = hexa.forward(readings[1], sol, check=False)  # compile / warm up
    hexa.forward(readings[1], sol, check=False, prove=False)
    if prover is not None:
        prover.prove(hexa.engine.start(sol), first.q, structured=False)

    def stream(prove: bool) -> tuple[list[float], list[tuple]]:
        """One pass of warm steps along the readings, each from the last result that closed.

        Returns the times and, per step, ``(proven, subdivisions, start, q)`` (``q`` None when
        the step did not close); no result is kept (kept, the collector's passes over them
        grew with the stream and were timed with it).
        """
        times, steps, last = [], [], sol
        for x in readings[1:]:
            t0 = time.perf_counter()
            nxt = hexa.forward(x, last, check=False, prove=prove)
            times.append(time.perf_counter() - t0)
            proof = nxt.proof
            proven = proof is not None and proof.proven
            steps.append((proven, proof.subdivisions if proven else 0, last.q, nxt.q if nxt.closed else None))
            last = nxt if nxt.closed else last
        return times, steps

    solve_t: list[float] = []
    proof_t: list[float] = []
    steps: list[tuple] = []
    for _ in range(rounds):
        times, results = stream(True)
        proof_t += times  # with the solve: forward as a caller gets it
        steps = steps or results
        solve_t += stream(False)[0]
    proven = sum(p for p, _, _, _ in steps)
    parts = [k for p, k, _, _ in steps if p]
    blocks_t, dense_t, dense_proven = [], [], 0
    if prover is not None:
        pairs = [(start, q) for _, _, start, q in steps if q is not None]
        for structured in (True, False):
            for start, q in pairs:
                t0 = time.perf_counter()
                proof = prover.prove(start, q, structured=structured)
                (blocks_t if structured else dense_t).append(time.perf_counter() - t0)
                dense_proven += not structured and proof.proven
    floor = floor_times(hexa, readings)
    n = len(steps)
    return {
        "steps": n,
        "outside_from": outside_from,
        "proven_fraction": proven / n if n else float("nan"),
        "dense_proven_fraction": dense_proven / n if n else float("nan"),
        "median_subdivisions": float(np.median(parts)) if parts else float("nan"),
        "solve_median_us": float(np.median(solve_t) * 1e6),
        "forward_proven_median_us": float(np.median(proof_t) * 1e6),
        "blocks_proof_median_us": float(np.median(blocks_t) * 1e6) if blocks_t else float("nan"),
        "dense_proof_median_us": float(np.median(dense_t) * 1e6) if dense_t else float("nan"),
        "floor_median_us": float(np.median(floor) * 1e6) if floor else float("nan"),
    }


def rest_proofs(name: str, samples: int, noise: float = 1e-6, block: int = 50) -> dict:
    """Per-step medians (us) of warm solves of a fixture at rest: readings with ``noise`` m of noise.

    Side by side, in alternating blocks of ``block`` steps of the same noise: ``forward``
    with its proof as it runs (regions: the steps whose readings lie in a region an earlier step
    proved test only their end box) and with every step proven by its own test
    (``StepProver.regions`` False); the solve alone; the floor on the same readings.
    """
    hexa = Hexapod.load(name)
    prover = hexa.engine.prover
    pose = hexa.home_pose.copy()
    pose[:3, 3] += np.array([0.2, 0.0, 0.4]) * hexa.base_radius / 10.0  # a pose off home
    rest = hexa.inverse(pose, check=False)
    readings = rest.lengths + np.random.default_rng(7).normal(scale=noise, size=(samples, 6))
    first = hexa.forward(readings[0], rest, check=False)
    times: dict[bool, list[float]] = {True: [], False: []}
    solve_t, in_region, proven = [], 0, 0
    for k, start in enumerate(range(1, samples, block)):
        regions = k % 2 == 0  # the two alternate, block by block
        if prover is not None:
            prover.regions = regions
        sol = first
        for x in readings[start : start + block]:
            t0 = time.perf_counter()
            checked = hexa.forward(x, sol, check=False)
            times[regions].append(time.perf_counter() - t0)
            if regions:
                proven += checked.proof is not None and checked.proof.proven
                in_region += checked.proof is not None and checked.proof.in_region
                t1 = time.perf_counter()
                hexa.forward(x, sol, check=False, prove=False)
                solve_t.append(time.perf_counter() - t1)
            sol = checked
    if prover is not None:
        prover.regions = True
    floor = floor_times(hexa, readings)
    n = len(times[True])
    return {
        "steps": n + len(times[False]),
        "noise_m": noise,
        "proven_fraction": proven / n,
        "in_region_fraction": in_region / n,
        "solve_median_us": float(np.median(solve_t) * 1e6),
        "forward_proven_median_us": float(np.median(times[True]) * 1e6),
        "forward_own_test_median_us": float(np.median(times[False]) * 1e6),
        "floor_median_us": float(np.median(floor) * 1e6) if floor else float("nan"),
    }


def rest_streams(
    name: str, fixtures: int = 5, samples: int = 400, noise: float = 1e-6, resolution: float = 1e-6
) -> dict:
    """Trackers of ``fixtures`` fixtures at rest, each at a pose of its own, stepped in turn on one thread.

    As the service's cycle steps the fixtures of a cell: each tracker keeps its proof state
    (region, preconditioner) apart from the others' (:class:`~hexapod_model.kinematics.newton.proof.ProofState`).
    The readings are encoder counts (``noise`` m of noise, rounded to ``resolution`` m, the
    trackers told it): at rest a leg repeats its count often, and the tracker's stuck test runs.
    Beside it, ``fixtures`` steps at a time between the turns, one tracker of the first pose
    stepped alone. Medians (us) of a step, fractions proven and proven in a region.
    """
    hexa = Hexapod.load(name)
    rng = np.random.default_rng(9)
    rests = []
    for i in range(fixtures):
        pose = hexa.home_pose.copy()
        pose[:3, 3] += np.array([np.cos(i), np.sin(i), 0.5 * (-1) ** i]) * 0.3 * hexa.base_radius / 10.0
        rests.append(hexa.inverse(pose, check=False).lengths)

    def counts(rest: np.ndarray, n: int) -> np.ndarray:  # n noisy readings of ``rest`` as the encoders count them
        return np.round((rest + rng.normal(scale=noise, size=(n, 6))) / resolution) * resolution

    series = [counts(r, samples) for r in rests]
    alone_series = counts(rests[0], samples * fixtures)  # as many steps as the turns take
    trackers = [Tracker(hexa, noise=noise, resolution=resolution) for _ in series]
    alone = Tracker(hexa, noise=noise, resolution=resolution)
    skip = min(20, samples // 2)
    t_turn, t_alone, proven, in_region, alone_in = [], [], 0, 0, 0
    for k in range(samples):
        for tracker, readings in zip(trackers, series):
            t0 = time.perf_counter()
            result = tracker.step(readings[k])
            if k >= skip:
                t_turn.append(time.perf_counter() - t0)
                proof = result.solution.proof
                proven += proof is not None and proof.proven
                in_region += proof is not None and proof.in_region
        for j in range(fixtures):  # as many steps of one fixture alone, between the turns
            t0 = time.perf_counter()
            result = alone.step(alone_series[k * fixtures + j])
            if k >= skip:
                t_alone.append(time.perf_counter() - t0)
                alone_in += result.solution.proof is not None and result.solution.proof.in_region
    return {
        "fixtures": fixtures,
        "noise_m": noise,
        "resolution_m": resolution,
        "steps": len(t_turn),
        "proven_fraction": proven / len(t_turn),
        "in_region_fraction": in_region / len(t_turn),
        "step_median_us": float(np.median(t_turn) * 1e6),
        "alone_step_median_us": float(np.median(t_alone) * 1e6),
        "alone_in_region_fraction": alone_in / len(t_alone),
    }


def tracker_proofs(name: str, samples: int) -> dict:
    """The tracker (its default predictor, ``eq22``) along trajectory A at 1 kHz: proven fraction, medians (us).

    Each sample's step as :meth:`Tracker.step` runs it; then the solve it makes, from the
    prediction (:func:`hexapod_model.tracking.tracker.predict` over the last two results), with
    its proof (the default) and alone (``prove=False``), side by side. The proof's path runs
    from the prediction: a short step while the readings move, so no region is built about it.
    """
    hexa = Hexapod.load(name)
    readings, _ = limited_readings(hexa, "A", samples)
    skip = min(20, len(readings) // 2)  # the first samples: the history fills, the first steps load
    tracker = Tracker(hexa)
    step_t, proven, in_region = [], 0, 0
    for k, x in enumerate(readings):
        t0 = time.perf_counter()
        result = tracker.step(x)
        if k >= skip:
            step_t.append(time.perf_counter() - t0)
            proof = result.solution.proof
            proven += proof is not None and proof.proven
            in_region += proof is not None and proof.in_region
    history: deque[np.ndarray] = deque([hexa.q_home], maxlen=3)
    solve_t, proof_t = [], []
    for k, x in enumerate(readings):
        guess = predict(hexa.model, history, "eq22")
        t0 = time.perf_counter()
        hexa.forward(x, guess, tol=tracker.tol, max_iter=20, check=False, prove=False)
        t1 = time.perf_counter()
        sol = hexa.forward(x, guess, tol=tracker.tol, max_iter=20, check=False)
        if k >= skip:
            solve_t.append(t1 - t0)
            proof_t.append(time.perf_counter() - t1)
        history.appendleft(sol.q)
    return {
        "steps": len(step_t),
        "proven_fraction": proven / len(step_t),
        "in_region_fraction": in_region / len(step_t),
        "step_median_us": float(np.median(step_t) * 1e6),
        "forward_proven_median_us": float(np.median(proof_t) * 1e6),
        "solve_median_us": float(np.median(solve_t) * 1e6),
    }


def far_guess_proofs(name: str, poses: int, seed: int = 12) -> dict:
    """Warm ``forward`` of random poses in turn, each from the one before: medians (ms), steps and tests.

    The guesses lie about 0.1 m and 0.2 rad away: each result is proven along its readings path
    in steps (:meth:`hexapod_model.kinematics.engine.SolveEngine.proven_warm`).
    """
    hexa = Hexapod.load(name)
    sols = [hexa.inverse(T, check=False) for T in box_poses(hexa.home_pose, poses + 1, seed=seed)]
    sols = [s for s in sols if s.converged]
    hexa.forward(sols[1].lengths, sols[0], check=False)  # the proof's kernels load
    times, steps, tests, converged = [], [], [], 0
    pairs = list(zip(sols, sols[1:]))
    for before, after in pairs:
        t0 = time.perf_counter()
        sol = hexa.forward(after.lengths, before, check=False)
        times.append(time.perf_counter() - t0)
        converged += sol.converged
        steps.append(sol.proof.subdivisions if sol.proof is not None else 0)
        tests.append(sol.proof.tests if sol.proof is not None else 0)
    return {
        "solves": len(times),
        "converged_fraction": converged / len(times),
        "forward_median_ms": float(np.median(times) * 1e3),
        "median_steps": float(np.median(steps)),
        "median_tests": float(np.median(tests)),
        "tests_per_step": float(np.sum(tests) / max(np.sum(steps), 1)),
        "median_reading_change_m": float(np.median([np.abs(b.lengths - a.lengths).max() for a, b in pairs])),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=[n for n in PRESETS if not get_preset(n).redundant])  # six readings
    ap.add_argument("--poses", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--warm-offset", type=float, default=1e-4, help="m (default 1e-4: a 1 kHz sample at 0.1 m/s)")
    ap.add_argument("--trajectory-samples", type=int, default=4001, help="1 kHz samples of A and B (4001: all)")
    ap.add_argument("--rest-samples", type=int, default=2001, help="samples of the fixture at rest")
    ap.add_argument("--far-guesses", type=int, default=30, help="random poses solved in turn, each from the one before")
    ap.add_argument("--json", type=Path, help="also write the figures as JSON")
    args = ap.parse_args(argv)
    report: dict = {"trajectories": [], "solves": []}
    for name in args.presets:
        for which in ("A", "B"):
            t = trajectory_proofs(name, which, args.trajectory_samples)
            report["trajectories"].append({"preset": name, "trajectory": which, **t})
            ratio = t["forward_proven_median_us"] / t["floor_median_us"]
            print(
                f"{name:12s} trajectory {which} at 1 kHz: {t['steps']} warm steps"
                + (f" (sample {t['outside_from']} onwards outside the limits)" if t["outside_from"] is not None else "")
                + f", proven {100 * t['proven_fraction']:.2f} % (dense test {100 * t['dense_proven_fraction']:.2f} %; "
                f"median {t['median_subdivisions']:g} sub-intervals); warm forward with its proof "
                f"{t['forward_proven_median_us']:.1f} us (the solve alone {t['solve_median_us']:.1f} us; "
                f"StepProver.prove: per-leg {t['blocks_proof_median_us']:.1f} us, "
                f"dense {t['dense_proof_median_us']:.1f} us); "
                f"floor {t['floor_median_us']:.1f} us (medians); with the proof / floor {ratio:.1f}x",
                flush=True,
            )
    for name in args.presets:
        r = rest_proofs(name, args.rest_samples)
        report["rest"] = [*report.get("rest", []), {"preset": name, **r}]
        print(
            f"{name:12s} at rest (1 um noise): {r['steps']} warm steps, proven {100 * r['proven_fraction']:.2f} % "
            f"({100 * r['in_region_fraction']:.2f} % in a region); warm forward with its proof "
            f"{r['forward_proven_median_us']:.1f} us "
            f"(each step its own test: {r['forward_own_test_median_us']:.1f} us; "
            f"the solve alone {r['solve_median_us']:.1f} us); floor {r['floor_median_us']:.1f} us (medians)",
            flush=True,
        )
    for name in args.presets:
        r = rest_streams(name, samples=max(args.rest_samples // 5, 40))
        report["rest_streams"] = [*report.get("rest_streams", []), {"preset": name, **r}]
        print(
            f"{name:12s} {r['fixtures']} fixtures at rest (1 um noise, 1 um counts), trackers stepped in turn: "
            f"a step {r['step_median_us']:.1f} us (one fixture alone: {r['alone_step_median_us']:.1f} us; medians), "
            f"proven {100 * r['proven_fraction']:.2f} %, in its region {100 * r['in_region_fraction']:.2f} % "
            f"(alone: {100 * r['alone_in_region_fraction']:.2f} %)",
            flush=True,
        )
    for name in args.presets:
        r = tracker_proofs(name, args.trajectory_samples)
        report["tracker"] = [*report.get("tracker", []), {"preset": name, **r}]
        print(
            f"{name:12s} tracker (eq22) along trajectory A at 1 kHz: {r['steps']} steps, proven "
            f"{100 * r['proven_fraction']:.2f} % ({100 * r['in_region_fraction']:.2f} % in a region); a step "
            f"{r['step_median_us']:.1f} us; its solve from the prediction with its proof "
            f"{r['forward_proven_median_us']:.1f} us, alone {r['solve_median_us']:.1f} us (medians)",
            flush=True,
        )
    for name in args.presets:
        if args.far_guesses <= 0:
            break
        r = far_guess_proofs(name, args.far_guesses)
        report["far"] = [*report.get("far", []), {"preset": name, **r}]
        apart = 1e3 * r["median_reading_change_m"]
        print(
            f"{name:12s} far guesses (random poses in turn, readings {apart:.0f} mm apart): "
            f"{r['solves']} warm solves, {100 * r['converged_fraction']:.0f} % converged; forward with its proof "
            f"{r['forward_median_ms']:.1f} ms, {r['median_steps']:g} proven steps, "
            f"{r['median_tests']:g} tests (medians); {r['tests_per_step']:.1f} tests a step",
            flush=True,
        )
    for name in args.presets:
        if args.poses <= 0:
            break
        r = run(name, args.poses, args.seed, args.warm_offset)
        report["solves"].append(r)
        for mode in ("cold", "warm"):
            c = r[mode]
            print(
                f"{name:12s} {mode}: {c.get('solves', 0)} solves; plain Newton {c['plain_median_us']:.1f} us, "
                f"checked first attempt {c['checked_median_us']:.1f} us, forward {c['forward_median_us']:.1f} us "
                f"(medians); first attempt refused {c.get('first_attempt_refused', 0)}, "
                f"not converged {c.get('not_converged', 0)}",
                flush=True,
            )
    if args.json:
        args.json.write_text(json.dumps(report, indent=1))  # NaN where a figure does not apply
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
