"""Wrong ``ok`` with and without redundant sensors: the fault cases of a single bad leg, and the false-alarm rate.

python benchmarks/redundancy_faults.py [PRESET ...] [--samples 500] [--clean 20000] [--rate 1000] [--json FILE]
python benchmarks/redundancy_faults.py --service [PRESET ...] [--samples 550] [--json FILE]

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

``--service``: the same question asked of ``hexapod serve`` (:func:`service_faults`): a
:class:`~hexapod_model.service.FixtureService` on a virtual bus, fed by the
:class:`~hexapod_model.service.Simulator` playing trajectory A (scale 2 mm, 100 sets/s, the
geometry's noise) with leg 3 faulty from the start: ``offset 0.1`` / ``offset 0.3`` (mm),
``creep`` (1 um per set), ``late 1`` / ``late 3`` (its readings 1 or 3 sets old with fresh
stamps), ``replay`` (a device on its CAN id replaying its readings of 100 sets before), and
``clean`` (no fault: its inconsistent sets are false alarms, at the stated rate 1e-3; printed
with their binomial 95 % interval: 2 in 550 is well inside it). Per
case: records ``ok``, "wrong ok" (an ``ok`` pose more than 10 um or 50 urad off the truth),
"wrong ok above" (of those, the sets whose fault exceeds twice the leg's minimal detectable
bias at that pose: with redundant sensors these must be 0), and the records
``inconsistent_readings`` and naming leg 3 (``isolated:leg3``).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
import uuid
from pathlib import Path

import can
import numpy as np
import pinocchio as pin
from scipy.stats import binomtest

from hexapod_model import Hexapod
from hexapod_model.kinematics.consistency import minimal_detectable_bias
from hexapod_model.service import FixtureService, Simulator, config_from_dict, simulation_from_dict

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


SERVICE_CASES: dict[str, dict | None] = {  # the simulator's fault on leg 3 (sim.toml's [[fixtures.faults]])
    "clean": None,  # no fault: its inconsistent sets are false alarms (stated rate 1e-3)
    "offset 0.1": {"kind": "step", "size": 1e-4},
    "offset 0.3": {"kind": "step", "size": 3e-4},
    "creep": {"kind": "creep", "size": 1e-4},  # m/s: 1 um per set at 100 sets/s
    "late 1": {"kind": "late_reading", "sets": 1},
    "late 3": {"kind": "late_reading", "sets": 3},
    "replay": {"kind": "replay", "sets": 100},
}
SERVICE_RATE = 100.0  # sets per second
SERVICE_SCALE = 0.002  # m per unit of trajectory A: legs up to about 0.06 m/s
IN_FLIGHT = 3  # sets sent ahead of the service's records


def _fault_bias(case: dict | None, truth: list, k: int) -> float:
    """The fault's size on leg 3's reading of set ``k`` (m), from the true readings."""
    if case is None:
        return 0.0
    kind, z = case["kind"], truth[k].readings[LEG]
    if kind == "step":
        return abs(case["size"])
    if kind == "creep":
        return abs(case["size"] * truth[k].t_sim)
    sets = case["sets"]
    return abs(truth[max(k - sets, 0)].readings[LEG] - z)


def service_faults(name: str, samples: int, cases: tuple[str, ...] = tuple(SERVICE_CASES)) -> dict:
    """Wrong ``ok`` of the service on the virtual bus for each fault case (module doc), preset ``name``."""
    hexa = Hexapod.from_preset(name)
    legs = sum(n.startswith("leg") for n in hexa.reading_names)
    sigma = hexa.geometry.encoder_sigma
    out: dict = {"preset": name, "samples": samples, "service": True, "cases": {}}
    for case in cases:
        with tempfile.TemporaryDirectory() as folder:
            out["cases"][case] = _service_case(name, hexa, legs, sigma, SERVICE_CASES[case], samples, Path(folder))
    return out


def _service_case(
    name: str, hexa: Hexapod, legs: int, sigma: float, fault: dict | None, samples: int, folder: Path
) -> dict:
    fixture = {
        "name": "f",
        "hexapod": name,
        "can_ids": [0x181 + k for k in range(legs)],
        "noise": sigma,
        "encoder": {"metres_per_count": 1e-7},  # rounding well below the noise
    }
    if "tilt_x" in hexa.reading_names:
        fixture["inclinometer"] = {"can_id": 0x1A0}
    data = {
        "bus": {"interface": "virtual", "channel": f"faults-{uuid.uuid4().hex}"},
        "store": {"path": str(folder / "store.sqlite"), "samples": 0},
        "http": {"host": "127.0.0.1", "port": 0},
        "fixtures": [fixture],
    }
    config = config_from_dict(data, "faults.toml", folder)
    tilt = hexa.redundancy.layout.tilt_sigma if "tilt_x" in hexa.reading_names else 2e-5
    sim_fixture = {"name": "f", "rate": SERVICE_RATE, "trajectory": "A", "scale": SERVICE_SCALE}
    sim_fixture |= {"noise": sigma, "tilt_noise": tilt}
    sim_fixture["faults"] = [] if fault is None else [{**fault, "leg": LEG + 1, "start": 0.0}]
    sim = simulation_from_dict({"seed": 7, "fixtures": [sim_fixture]}, config)
    records: list = []
    service = FixtureService(config, hexapods={"f": hexa})
    service.subscribe(records.append)
    service.start()
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    try:
        simulator = Simulator(config, sim, bus, hexapods={"f": hexa})
        wall = time.time()
        truth = []
        for k in range(samples):
            truth.append(simulator.send_set(0, k / SERVICE_RATE, wall + k / SERVICE_RATE, stall_check=False))
            end = time.monotonic() + 10.0
            while len(records) < k + 1 - IN_FLIGHT and time.monotonic() < end:
                time.sleep(0.001)
        end = time.monotonic() + 10.0
        while len(records) < samples and time.monotonic() < end:
            time.sleep(0.01)
    finally:
        bus.shutdown()
        service.stop()
    counts = {"records": 0, "ok": 0, "wrong_ok": 0, "wrong_ok_above": 0, "flagged": 0, "named": 0}
    for rec in records:
        k = round((rec.t - wall) * SERVICE_RATE)
        if rec.status in ("no_data",) or not 0 <= k < len(truth):
            continue
        counts["records"] += 1
        counts["flagged"] += rec.status == "inconsistent_readings"
        counts["named"] += f"isolated:leg{LEG + 1}" in rec.flags
        if rec.status != "ok":
            continue
        counts["ok"] += 1
        if not pose_off(rec.transform, truth[k].pose):
            continue
        counts["wrong_ok"] += 1
        if hexa.redundancy is not None:
            A = hexa.redundancy.whitened_jacobian(truth[k].pose)
            mdb = minimal_detectable_bias(A, hexa.redundancy.sigmas)[LEG]
            counts["wrong_ok_above"] += _fault_bias(fault, truth, k) > 2.0 * mdb
        else:
            counts["wrong_ok_above"] += 1
    return counts


def hexapod_redundant(name: str) -> bool:
    """True when preset ``name`` has sensors beside its six legs."""
    return Hexapod.from_preset(name).redundancy is not None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=["reference", "reference7", "reference_tilt"])
    ap.add_argument("--service", action="store_true", help="through the service on the virtual bus (module doc)")
    ap.add_argument("--samples", type=int, default=500, help="samples per fault case")
    ap.add_argument("--clean", type=int, default=20000, help="fault-free samples of the false-alarm rate")
    ap.add_argument("--rate", type=float, default=1000.0, help="samples per second (Hz)")
    ap.add_argument("--json", help="write the results as JSON")
    args = ap.parse_args()
    results = []
    if args.service:
        for name in args.presets:
            r = service_faults(name, args.samples)
            results.append(r)
            print(f"{name}: {args.samples} sets a case through the service, leg {LEG + 1} faulty")
            for case, c in r["cases"].items():
                print(
                    f"  {case:12s} ok {c['ok']:5d}   wrong ok {c['wrong_ok']:5d}   above detectable "
                    f"{c['wrong_ok_above']:5d}   inconsistent {c['flagged']:5d}   named leg{LEG + 1} {c['named']:5d}"
                )
                if case == "clean" and hexapod_redundant(name) and c["records"]:
                    ci = binomtest(c["flagged"], c["records"], 1e-3).proportion_ci(0.95)
                    print(
                        f"  {'':12s} false alarms: rate {c['flagged'] / c['records']:.2e} "
                        f"(95 % interval {ci.low:.2e} .. {ci.high:.2e}), stated 0.001"
                    )
        if args.json:
            with open(args.json, "w") as fh:
                json.dump(results, fh, indent=2)
        return
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
