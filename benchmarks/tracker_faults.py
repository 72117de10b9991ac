"""Fault-injection study of the stream tracker on trajectory B, and its per-sample cost.

python benchmarks/tracker_faults.py [PRESET ...] [--speeds 1 2 4 8] [--noise 10e-6 50e-6] [--json FILE]
python benchmarks/tracker_faults.py reference --hour [--rate 1000] [--hours 1] [--noise 10e-6] [--resolution 5e-6]

Per preset, speed and noise level (eq. 22 predictor, the tracker told the true noise):

* clean run: stream alarms (``jump``/``stuck``/``branch_uncertain``/late ``settling``/failed
  solve) in % of samples, of which false (the pose was right: error <= 10 noise or <= 5 of
  its own sigmas), failed solves, good samples in %, and the worst error of a good sample in
  noise units and in units of its stated sigma; ``wrong good`` counts good samples that are
  wrong (must be 0);
* stuck leg (legs 1 and 4 held for 100 samples from 20 % and 50 % of the run): samples until
  the first alarm and until ``stuck`` (1 = the first stuck sample), samples after the release
  until clean tracking (1 = at once), and wrong good samples;
* a 5 mm one-sample spike on leg 2 at 1/3 of the run: samples until clean again after it.

``--hour``: fault-free samples for ``--hours`` (default one hour) at ``--rate``, at rest and
moving slowly (0.2 mm/s), readings rounded to ``--resolution`` counts: the false ``jump`` and
``stuck`` alarms per hour measured, beside the rates :mod:`hexapod_model.tracking.false_alarms`
states for that rate, noise and resolution.

Timing (median of the whole ``Tracker.step`` along B at 1x, and of the near-singular figure
before (SVD of the 36-column constraint Jacobian, ``Solution.condition_number``) and after
(compiled elimination, :class:`~hexapod_model.analysis.sensitivity.SensitivityEvaluator`).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from hexapod_model import Hexapod
from hexapod_model.analysis.sensitivity import SensitivityEvaluator
from hexapod_model.analysis.trajectories import trajectory_poses
from hexapod_model.description.presets import PRESETS, get_preset
from hexapod_model.studies.track import true_readings
from hexapod_model.studies.track_faults import run_faults
from hexapod_model.tracking.false_alarms import false_alarm_rates
from hexapod_model.tracking.tracker import Tracker, characteristic_length

STUCK_SAMPLES = 100


def study(hexa: Hexapod, speed: float, noise: float) -> dict:
    length = characteristic_length(hexa)
    _, poses = trajectory_poses("B", hexa.home_pose, length / 50.0, 1000.0, speed)
    readings = true_readings(hexa, poses)
    n = len(poses)
    clean = run_faults(hexa, speed, noise, readings=readings)
    worst_noise, worst_sigma = clean.worst_good()
    row = {
        "speed": speed,
        "noise_um": noise * 1e6,
        "samples": n,
        "alarm_pct": 100.0 * clean.alarm.mean(),
        "false_alarm_pct": 100.0 * clean.false_alarm.mean(),
        "failed": int(np.sum(~np.isfinite(clean.sigma))),
        "good_pct": 100.0 * clean.good.mean(),
        "worst_good_noise": worst_noise,
        "worst_good_sigma": worst_sigma,
        "wrong_good": int(np.sum(clean.wrong & clean.good)),
        "stuck": [],
    }
    for leg, start in ((1, n // 5), (4, n // 2)):
        run = run_faults(hexa, speed, noise, ("stuck", leg, start, STUCK_SAMPLES), readings=readings)
        row["stuck"].append(
            {
                "leg": leg,
                "start": start,
                "first_alarm": run.first(run.alarm, start),
                "flagged_stuck": run.first(run.stuck, start),
                "clean_after_release": run.clean_again(start + STUCK_SAMPLES),
                "wrong_good": int(np.sum(run.wrong & run.good)),
            }
        )
    spike = run_faults(hexa, speed, noise, ("spike", 2, n // 3, 5e-3), readings=readings)
    row["spike_clean_after"] = spike.clean_again(n // 3 + 1)
    row["spike_flagged"] = bool(spike.alarm[n // 3])
    return row


def timing(hexa: Hexapod) -> dict:
    length = characteristic_length(hexa)
    _, poses = trajectory_poses("B", hexa.home_pose, length / 50.0, 1000.0, 1.0)
    readings = true_readings(hexa, poses)[0] + np.random.default_rng(0).normal(0, 10e-6, (len(poses), 6))
    tracker = Tracker(hexa, "eq22", initial=hexa.inverse(poses[0], check=False), length=length)
    res = [tracker.step(x) for x in readings]
    ev = SensitivityEvaluator(hexa, length)
    svd, elim = [], []
    for r in res[::10]:
        t0 = time.perf_counter()
        _ = r.solution.condition_number
        t1 = time.perf_counter()
        ev.evaluate(r.solution.q)
        svd.append(t1 - t0)
        elim.append(time.perf_counter() - t1)
    steps = np.array([r.solve_time for r in res])
    return {
        "step_median_us": float(np.median(steps) * 1e6),
        "step_p99_us": float(np.percentile(steps, 99) * 1e6),
        "svd_condition_median_us": float(np.median(svd) * 1e6),
        "compiled_sensitivity_median_us": float(np.median(elim) * 1e6),
    }


def hour(hexa: Hexapod, rate: float, hours: float, noise: float, resolution: float, speed: float, seed: int) -> dict:
    """False ``jump`` and ``stuck`` alarms per hour over ``hours`` of samples at ``rate`` Hz (no fault injected).

    Six legs on slow sines of peak rate ``speed`` (m/s; 0: at rest), Gaussian ``noise``, readings
    rounded to ``resolution`` counts, generated and tracked in blocks of 10,000 samples.
    """
    rng = np.random.default_rng(seed)
    tracker = Tracker(hexa, noise=noise, resolution=resolution)
    n, counts = int(round(rate * 3600.0 * hours)), {"jump": 0, "stuck": 0, "failed": 0}
    for start in range(0, n, 10_000):
        t = np.arange(start, min(n, start + 10_000))[:, None] / rate
        true = speed / (2 * np.pi * 0.5) * np.sin(2 * np.pi * 0.5 * t + np.arange(6)[None, :])
        block = true + rng.normal(0.0, noise, true.shape)
        if resolution > 0:
            block = np.round(block / resolution) * resolution
        for x in block:
            r = tracker.step(x)
            counts["failed"] += r.failed
            counts["jump"] += "jump" in r.flags
            counts["stuck"] += "stuck" in r.flags
    expected = false_alarm_rates(rate, noise, resolution, tracker.settings.jump_sigmas, tracker.settings.stuck_samples)
    per_hour = {k: v / hours for k, v in counts.items()}
    return {"rate_hz": rate, "hours": hours, "samples": n, "noise_um": noise * 1e6, "resolution_um": resolution * 1e6,
            "speed_mm_s": speed * 1e3, "measured_per_hour": per_hour, "expected_per_hour": expected}  # fmt: skip


def _save(report: list, path: str | None) -> int:
    """Write ``report`` as JSON to ``path`` (if given); the exit status 0."""
    if path:
        with open(path, "w") as fh:
            json.dump(report, fh, indent=2)
    return 0


def main_hour(args: argparse.Namespace) -> int:
    """``--hour``: measured and expected false alarms per hour, per preset, noise and speed."""
    report = []
    for name in args.presets:
        hexa = Hexapod.load(name)
        for noise in args.noise:
            for speed in (0.0, 2e-4):
                r = {"preset": name, **hour(hexa, args.rate, args.hours, noise, args.resolution, speed, args.seed)}
                report.append(r)
                m, e = r["measured_per_hour"], r["expected_per_hour"]
                print(
                    f"{name}: {r['samples']} samples ({args.hours:g} h at {args.rate:g} Hz), noise {noise * 1e6:g} um, "
                    f"counts {args.resolution * 1e6:g} um, {'at rest' if speed == 0 else f'{speed * 1e3:g} mm/s'}: "
                    f"jump {m['jump']:.1f}/h (expected {e['jump']:.1f}), stuck {m['stuck']:.1f}/h "
                    f"(expected <= {e['stuck']:.2g}; frozen run {e['stuck_run']:.0f}, p_repeat {e['p_repeat']:.3f}), "
                    f"failed {m['failed']:.0f}/h",
                    flush=True,
                )
    return _save(report, args.json)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=[n for n in PRESETS if not get_preset(n).redundant])  # six readings
    ap.add_argument("--speeds", nargs="+", type=float, default=[1, 2, 4, 8])
    ap.add_argument("--noise", nargs="+", type=float, default=[10e-6, 50e-6])
    ap.add_argument("--json")
    ap.add_argument("--hour", action="store_true", help="false alarms per hour over --hours of fault-free samples")
    ap.add_argument("--rate", type=float, default=1000.0, help="Hz, with --hour (default 1000)")
    ap.add_argument("--hours", type=float, default=1.0, help="simulated hours, with --hour (default 1)")
    ap.add_argument("--resolution", type=float, default=5e-6, help="m: encoder counts, with --hour (default 5e-6)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if args.hour:
        return main_hour(args)
    report = []
    print(
        f"{'preset':11s}{'speed':>6s}{'noise':>6s}{'alarm%':>8s}{'false%':>8s}{'failed':>7s}{'good%':>7s}"
        f"{'worst/noise':>12s}{'worst/sigma':>12s}{'wrong':>6s}  stuck: alarm,stuck,clean  spike"
    )
    for name in args.presets:
        hexa = Hexapod.load(name)
        for speed in args.speeds:
            for noise in args.noise:
                r = {"preset": name, **study(hexa, speed, noise)}
                report.append(r)
                stuck = " ".join(
                    f"{s['first_alarm']},{s['flagged_stuck']},{s['clean_after_release']}"
                    + (f"(wrong {s['wrong_good']})" if s["wrong_good"] else "")
                    for s in r["stuck"]
                )
                print(
                    f"{name:11s}{speed:6g}{noise * 1e6:6.0f}{r['alarm_pct']:8.3f}{r['false_alarm_pct']:8.3f}"
                    f"{r['failed']:7d}{r['good_pct']:7.1f}{r['worst_good_noise']:12.1f}{r['worst_good_sigma']:12.2f}"
                    f"{r['wrong_good']:6d}  {stuck:24s} {r['spike_clean_after']}",
                    flush=True,
                )
        t = timing(hexa)
        report.append({"preset": name, "timing": t})
        print(
            f"{name}: Tracker.step median {t['step_median_us']:.0f} us (p99 {t['step_p99_us']:.0f}); "
            f"near-singular figure: SVD {t['svd_condition_median_us']:.0f} us -> compiled "
            f"{t['compiled_sensitivity_median_us']:.0f} us",
            flush=True,
        )
    return _save(report, args.json)


if __name__ == "__main__":
    raise SystemExit(main())
