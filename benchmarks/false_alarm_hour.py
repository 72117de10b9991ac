"""The consistency test's false-alarm rate over an hour of simulated clean samples.

python benchmarks/false_alarm_hour.py [PRESET ...] [--seconds 3600] [--rate 100] [--motion moving rest]
    [--seed 0] [--progress 0] [--json FILE]

For each redundant preset (default ``reference7`` and ``reference_tilt``) and each motion, the
stream tracker (:class:`hexapod_model.tracking.tracker.Tracker`, as the fixture service solves
a set) is given ``--seconds`` of samples at ``--rate`` (an hour at 100 Hz: 360,000 sets), offline
(not in real time): the true readings of the pose plus independent Gaussian noise of each
reading's stated sigma (:attr:`hexapod_model.kinematics.redundant.RedundantSensing.sigmas`), no
fault. A sample flagged ``inconsistent_readings`` is a false alarm. Printed per case: the alarms,
the measured rate with its exact (Clopper-Pearson) binomial 95 % interval, and the stated rate
(the tracker's test runs at :data:`hexapod_model.kinematics.redundant.DEFAULT_ALPHA`, 1e-3);
``consistent`` when the stated rate lies inside the interval.

Motions: ``moving``, the platform circling 20 mm around home at one turn per 2 s while tilting
5 deg (the trajectory of ``benchmarks/redundancy_faults.py``); ``rest``, the platform at home.
The true readings of one period are computed once and repeated; the noise is fresh every sample,
its stream seeded by ``--seed`` and the motion (the two motions' alarms are independent counts).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import pinocchio as pin
from scipy.stats import binomtest

from hexapod_model import Hexapod
from hexapod_model.kinematics.redundant import DEFAULT_ALPHA
from hexapod_model.tracking.tracker import Tracker

MOTIONS = ("moving", "rest")
INCONSISTENT = "inconsistent_readings"


def period_poses(hexa: Hexapod, motion: str, rate: float) -> list[np.ndarray]:
    """One period of ``motion``'s poses at ``rate`` samples/s (base frame, m); one pose at rest."""
    if motion == "rest":
        return [hexa.home_pose.copy()]
    out = []
    for k in range(max(round(2.0 * rate), 1)):  # one turn per 2 s
        a = 2 * np.pi * (k / rate) / 2.0
        v = np.array([0.02 * np.cos(a), 0.02 * np.sin(a), 0.0, 0.087 * np.sin(a), 0.087 * np.cos(a), 0.0])
        out.append(hexa.home_pose @ pin.exp6(v).homogeneous)
    return out


def true_readings(hexa: Hexapod, poses: list[np.ndarray]) -> np.ndarray:
    """Every reading of each pose (m for legs, rad for tilts), reading order."""
    assert hexa.redundancy is not None
    return np.array([np.concatenate([hexa.inverse(T).lengths, hexa.redundancy.extra_readings(T)]) for T in poses])


def false_alarms(
    name: str, motion: str, seconds: float, rate: float = 100.0, seed: int = 0, progress: float = 0.0
) -> dict:
    """Alarms of the tracker over ``seconds`` of clean samples of preset ``name`` (module doc).

    ``progress`` > 0: print the counts so far every ``progress`` s of samples.

    Returns:
        ``preset``, ``motion``, ``samples``, ``alarms`` (``inconsistent_readings`` samples),
        ``failed`` (samples without a pose), ``alpha`` (the stated rate), ``rate`` (measured), ``ci95`` (its exact
        binomial interval), ``consistent`` (``alpha`` inside it) and ``seconds_cpu``.
    """
    hexa = Hexapod.from_preset(name)
    if hexa.redundancy is None:
        raise SystemExit(f"{name}: no redundant sensors (expected a preset such as reference7)")
    z0 = true_readings(hexa, period_poses(hexa, motion, rate))
    sig = hexa.redundancy.sigmas
    n = round(seconds * rate)
    rng = np.random.default_rng([seed, MOTIONS.index(motion)])  # the motions' noise independent
    tracker = Tracker(hexa, "eq22", initial=hexa.inverse(period_poses(hexa, motion, rate)[0]), noise=sig[0])
    alpha, alarms, failed = DEFAULT_ALPHA, 0, 0
    t0 = time.process_time()
    for k in range(n):
        r = tracker.step(z0[k % len(z0)] + rng.normal(0.0, 1.0, len(sig)) * sig)
        failed += r.failed
        alarms += INCONSISTENT in r.flags
        if progress > 0 and (k + 1) % max(round(progress * rate), 1) == 0:
            print(f"  {name} {motion}: {alarms} alarms in {k + 1} samples so far", flush=True)
    ci = binomtest(alarms, n, alpha).proportion_ci(0.95)
    return {
        "preset": name,
        "motion": motion,
        "samples": n,
        "alarms": alarms,
        "failed": failed,
        "alpha": alpha,
        "rate": alarms / n,
        "ci95": [ci.low, ci.high],
        "consistent": bool(ci.low <= alpha <= ci.high),
        "seconds_cpu": time.process_time() - t0,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=["reference7", "reference_tilt"])
    ap.add_argument("--seconds", type=float, default=3600.0, help="s of samples per case (an hour by default)")
    ap.add_argument("--rate", type=float, default=100.0, help="samples per second (Hz)")
    ap.add_argument("--motion", nargs="+", choices=MOTIONS, default=list(MOTIONS))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--progress", type=float, default=0.0, help="s of samples between progress lines (0: none)")
    ap.add_argument("--json", help="write the results as JSON")
    args = ap.parse_args()
    results = []
    for name in args.presets:
        for motion in args.motion:
            r = false_alarms(name, motion, args.seconds, args.rate, args.seed, args.progress)
            results.append(r)
            lo, hi = r["ci95"]
            print(
                f"{name:15s} {motion:7s} {r['alarms']:6d} alarms in {r['samples']} samples: rate {r['rate']:.3e} "
                f"(95 % interval {lo:.3e} .. {hi:.3e}), stated {r['alpha']:g}: "
                f"{'consistent' if r['consistent'] else 'NOT consistent'}; {r['failed']} without a pose; "
                f"{r['seconds_cpu']:.0f} s CPU",
                flush=True,
            )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=2)


if __name__ == "__main__":
    main()
