"""Wrong ``ok`` with and without redundant sensors: the fault cases of a single bad leg, and the false-alarm rate.

python benchmarks/redundancy_faults.py [PRESET ...] [--samples 500] [--clean 20000] [--rate 1000] [--json FILE]

Along a moving trajectory (the platform circling 20 mm around home at 1 turn per 2 s, tilting
5 deg, sampled at ``--rate``), readings with Gaussian noise of the geometry's sigmas, one leg
(leg 3) faulty:

* ``offset 0.1 mm`` / ``offset 0.3 mm``: a constant offset;
* ``creep``: the leg's reading drifts 1 um per sample;
* ``late 1`` / ``late 3``: the leg's reading is the one from 1 or 3 samples earlier.

For the presets without redundant sensors (``reference``) every solve is ``converged``:
"wrong ok" counts those whose pose is more than 10 um (or 50 urad) off. With redundant sensors
"wrong ok" counts ``converged`` samples whose fault exceeds twice the leg's minimal detectable
bias at that pose (missed with probability below 1e-6; a fault of once the bias is missed one
time in five, a smaller one may pass: the test does not claim to see it), and "named"
the ``inconsistent_readings`` samples that name leg 3 alone. ``--clean``: the false-alarm
rate over that many fault-free samples, with its 99 % binomial interval, against the stated
``alpha``.
"""

from __future__ import annotations

import argparse
import json

import numpy as np
import pinocchio as pin
from scipy.stats import binomtest

from hexapod_model import Hexapod

LEG = 2  # the faulty leg (leg 3)
POSE_BAD = (1e-5, 5e-5)  # m, rad: a six-leg pose this far off is a wrong ok


def trajectory(hexa: Hexapod, n: int, rate: float) -> list[np.ndarray]:
    """``n`` poses of the circling, tilting platform (base frame, m)."""
    out = []
    for k in range(n):
        a = 2 * np.pi * (k / rate) / 2.0
        v = np.array([0.02 * np.cos(a), 0.02 * np.sin(a), 0.0, 0.087 * np.sin(a), 0.087 * np.cos(a), 0.0])
        out.append(hexa.home_pose @ pin.exp6(v).homogeneous)
    return out


def clean_readings(hexa: Hexapod, six: Hexapod, poses: list[np.ndarray]) -> np.ndarray:
    extra = (lambda T: hexa.redundancy.extra_readings(T)) if hexa.redundancy is not None else (lambda T: np.zeros(0))
    return np.array([np.concatenate([six.inverse(T).lengths, extra(T)]) for T in poses])


def faulty(z: np.ndarray, case: str) -> np.ndarray:
    bad = z.copy()
    k = np.arange(len(z))
    if case.startswith("offset"):
        bad[:, LEG] += float(case.split()[1]) * 1e-3
    elif case == "creep":
        bad[:, LEG] += 1e-6 * (k + 1)
    else:
        lag = int(case.split()[1])
        bad[lag:, LEG] = z[:-lag, LEG]
    return bad


def pose_off(a: np.ndarray, b: np.ndarray) -> bool:
    rot = float(np.linalg.norm(pin.log3(a[:3, :3].T @ b[:3, :3])))
    return bool(np.abs(a[:3, 3] - b[:3, 3]).max() > POSE_BAD[0] or rot > POSE_BAD[1])


def run(name: str, samples: int, clean: int, rate: float) -> dict:
    hexa, six = Hexapod.from_preset(name), Hexapod.from_preset("reference")
    sig = hexa.redundancy.sigmas if hexa.redundancy is not None else np.full(6, hexa.geometry.encoder_sigma)
    rng = np.random.default_rng(0)
    poses = trajectory(six, samples, rate)
    z0 = clean_readings(hexa, six, poses)
    out: dict = {"preset": name, "samples": samples, "cases": {}}
    for case in ("offset 0.1", "offset 0.3", "creep", "late 1", "late 3"):
        z = faulty(z0, case) + rng.normal(0.0, 1.0, z0.shape) * sig
        wrong = named = flagged = 0
        for k, T in enumerate(poses):
            sol = hexa.forward(z[k], check=False)
            if hexa.redundancy is None:
                wrong += sol.converged and pose_off(sol.pose, T)
                continue
            bias = abs(z[k, LEG] - z0[k, LEG])
            flagged += sol.status == "inconsistent_readings"
            named += sol.consistency.isolated == f"leg{LEG + 1}"
            wrong += sol.converged and bias > 2.0 * sol.consistency.detectable[LEG]
        out["cases"][case] = {"wrong_ok": int(wrong), "flagged": int(flagged), "named": int(named)}
    if hexa.redundancy is not None and clean:
        alpha = 1e-3
        alarms = 0
        for k in range(clean):
            z = z0[k % len(poses)] + rng.normal(0.0, 1.0, len(sig)) * sig
            alarms += hexa.forward(z, check=False, alpha=alpha).status == "inconsistent_readings"
        ci = binomtest(alarms, clean, alpha).proportion_ci(0.99)
        out["false_alarms"] = {"samples": clean, "alarms": alarms, "alpha": alpha, "ci99": [ci.low, ci.high]}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=["reference", "reference7", "reference_tilt"])
    ap.add_argument("--samples", type=int, default=500, help="samples per fault case")
    ap.add_argument("--clean", type=int, default=20000, help="fault-free samples of the false-alarm rate")
    ap.add_argument("--rate", type=float, default=1000.0, help="samples per second (Hz)")
    ap.add_argument("--json", help="write the results as JSON")
    args = ap.parse_args()
    results = []
    for name in args.presets:
        r = run(name, args.samples, args.clean, args.rate)
        results.append(r)
        print(f"{name}: {args.samples} samples a case, leg {LEG + 1} faulty")
        for case, c in r["cases"].items():
            counts = f"wrong ok {c['wrong_ok']:5d}   flagged {c['flagged']:5d}   named leg{LEG + 1} {c['named']:5d}"
            print(f"  {case:12s} {counts}")
        fa = r.get("false_alarms")
        if fa:
            lo, hi = fa["ci99"]
            print(
                f"  clean: {fa['alarms']} alarms in {fa['samples']} samples, rate {fa['alarms'] / fa['samples']:.2e} "
                f"(99 % interval {lo:.2e} .. {hi:.2e}), stated {fa['alpha']:g}"
            )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=2)


if __name__ == "__main__":
    main()
