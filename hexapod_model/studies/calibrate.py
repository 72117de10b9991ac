"""``hexapod calibrate``: identification from measured poses, k-fold validation, and the simulated study.

Simulated study (``--simulate``): the *true* hexapod is the nominal one with documented random
errors, drawn uniformly within (:class:`Errors`): Cardan centres +-0.5 mm per coordinate,
fixed axis directions +-0.3 deg (tilt and turn), axis offsets +-0.5 mm, encoder zeros +-1 mm.
The measuring device sits at an unknown pose (rotation up to 30 deg about a random axis,
translation up to 0.5 m per coordinate) and tracks a marker frame at an unknown pose on the
platform (rotation up to 20 deg, 30-100 mm above the plate, +-50 mm sideways). Poses are drawn
in the +-50 mm / +-25 deg box around home (the test box of Bem, Ude and Nemec 2026) and kept
when the true hexapod reaches them within its stroke and joint limits. Readings get 10 um
Gaussian noise, measured poses 0.1 mm per coordinate and 0.05 deg per rotation component.

A geometry with extra sensors (measuring legs, an inclinometer) gets their errors too:
anchors +-0.5 mm per coordinate, encoder zeros +-1 mm, the inclinometer's mounting rotation
+-0.3 deg per axis; every row carries their readings (after the six legs', in the geometry's
reading order) and the leg encoders' noise is the geometry's ``encoder_sigma``, the tilts'
the inclinometer's ``sigma`` (the noise the least-squares solve states).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..analysis.trajectories import box_poses
from ..calibration.frames import Noise, pose_errors, predict
from ..calibration.gauge import regauge
from ..calibration.identify import Identification, MeasuredPoses, identify
from ..calibration.parameters import ParameterSet
from ..calibration.sensors import reading_sigmas
from ..calibration.validation import Validation, cross_validate
from ..description.geometry import HexapodGeometry
from ..description.geometry_toml import save_geometry
from ..description.urdf_geometry import geometry_of_urdf
from ..exceptions import InputError
from ..files import atomic_write_text
from ..io.calibration_csv import load_poses as load_poses  # the calibration CSV, read here by the CLI
from ..io.calibration_csv import save_poses
from ..kinematics.hexapod import Hexapod, load_hexapod
from ..lie import exp3

Progress = Callable[[Iterable, int, str], Iterable]


def _no_progress(iterable: Iterable, total: int, desc: str) -> Iterable:
    return iterable


@dataclass(frozen=True)
class Errors:
    """Half-widths of the uniform errors of the simulated true geometry (SI)."""

    centre_m: float = 0.5e-3
    axis_rad: float = math.radians(0.3)
    offset_m: float = 0.5e-3
    encoder_zero_m: float = 1e-3
    encoder_scale: float = 0.0


@dataclass(frozen=True)
class Simulation:
    """A simulated calibration experiment: the truth and what the instruments report.

    Attributes:
        nominal: the geometry the user believes in.
        true_geometry: the geometry the readings come from.
        measuring_frame, marker_frame: the true frame transforms (4x4).
        data: noisy readings and noisy measured poses.
        true_poses: (N, 4, 4) true platform poses (base frame).
    """

    nominal: HexapodGeometry
    true_geometry: HexapodGeometry
    measuring_frame: np.ndarray
    marker_frame: np.ndarray
    data: MeasuredPoses
    true_poses: np.ndarray = field(repr=False)


def _random_rotation(rng: np.random.Generator, max_deg: float) -> np.ndarray:
    axis = rng.normal(size=3)
    return pin.exp3(axis / np.linalg.norm(axis) * math.radians(rng.uniform(0, max_deg)))


def simulate(
    nominal: HexapodGeometry,
    n: int,
    seed: int = 0,
    errors: Errors = Errors(),
    encoder_noise: float | None = None,
    noise: Noise = Noise(),
    truth: Simulation | None = None,
) -> Simulation:
    """Draw a true hexapod, frames and ``n`` reachable poses (see the module doc).

    With ``truth``, measure ``n`` new poses of that simulation's hexapod and frames instead.
    ``encoder_noise``: sigma of each leg reading (m); ``None``: 10 um, or the geometry's
    ``encoder_sigma`` when it has extra sensors.
    """
    if encoder_noise is None:
        encoder_noise = nominal.encoder_sigma if nominal.redundant else 10e-6
    if n < 2:
        raise InputError("poses", n, "need at least 2 poses")
    rng = np.random.default_rng(seed)
    if truth is None:
        true_geometry, T_mb, T_pm = _draw_truth(nominal, rng, errors)
    else:
        true_geometry, T_mb, T_pm = truth.true_geometry, truth.measuring_frame, truth.marker_frame
    hexa = Hexapod.from_geometry(true_geometry)
    poses: list[np.ndarray] = []
    readings: list[np.ndarray] = []
    drawn = 0
    while len(poses) < n:
        for T in box_poses(hexa.home_pose, max(16, 2 * (n - len(poses))), seed=int(rng.integers(2**63))):
            drawn += 1
            sol = hexa.inverse(T, check=False)
            if sol.converged and len(poses) < n:
                poses.append(T)
                readings.append(sol.lengths)
        if drawn > 50 * n:
            raise InputError("poses", n, f"only {len(poses)} of {drawn} drawn poses lie inside the limits")
    P = np.array(poses)
    measured = predict(T_mb, P, T_pm)
    measured[:, :3, 3] += rng.normal(0.0, noise.position_m, (n, 3))
    measured[:, :3, :3] = exp3(rng.normal(0.0, noise.rotation_rad, (n, 3))) @ measured[:, :3, :3]
    noisy = np.array(readings) + rng.normal(0.0, encoder_noise, (n, 6))
    if hexa.redundancy is not None:  # the extra sensors' readings follow the six legs'
        sigmas = reading_sigmas(true_geometry)
        sigmas[: len(true_geometry.measuring_legs)] = encoder_noise
        extra = np.array([hexa.redundancy.extra_readings(T) for T in P])
        noisy = np.hstack([noisy, extra + rng.normal(0.0, 1.0, extra.shape) * sigmas])
    data = MeasuredPoses(noisy, measured, f"simulation (seed {seed}, {n} poses)")
    return Simulation(nominal, true_geometry, T_mb, T_pm, data, P)


def _draw_truth(
    nominal: HexapodGeometry, rng: np.random.Generator, errors: Errors
) -> tuple[HexapodGeometry, np.ndarray, np.ndarray]:
    """A true geometry (nominal + uniform errors) and true frames (see the module doc)."""
    ps = ParameterSet(nominal, encoder_scale=errors.encoder_scale > 0, sensors=True)
    half = {"centre": errors.centre_m, "axis": errors.axis_rad, "offset": errors.offset_m}
    half |= {"encoder_zero": errors.encoder_zero_m, "encoder_scale": errors.encoder_scale}
    half |= {"measuring_base": errors.centre_m, "measuring_platform": errors.centre_m, "mount": errors.axis_rad}
    half |= {"measuring_zero": errors.encoder_zero_m, "measuring_scale": errors.encoder_scale}
    width = np.array([half[next(k for k in half if k in p.kind)] for p in ps.parameters])
    delta = rng.uniform(-1, 1, ps.size) * width
    nominal_values = ps.nominal_values()
    offsets = np.array(["offset" in p.kind for p in ps.parameters])
    delta[offsets] = np.maximum(delta[offsets], -nominal_values[offsets])  # an offset stays >= 0
    T_mb, T_pm = np.eye(4), np.eye(4)
    T_mb[:3, :3], T_mb[:3, 3] = _random_rotation(rng, 30.0), rng.uniform(-0.5, 0.5, 3)
    T_pm[:3, :3] = _random_rotation(rng, 20.0)
    T_pm[:3, 3] = [*rng.uniform(-0.05, 0.05, 2), rng.uniform(0.03, 0.1)]
    return ps.geometry(delta, name=f"{nominal.name}_true"), T_mb, T_pm


@dataclass(frozen=True)
class CalibrationResult:
    """Everything ``hexapod calibrate`` reports.

    Attributes:
        identification: the fit on all poses (written as the calibrated geometry).
        validation: held-out errors before and after (k-fold).
        data: the poses used.
        simulation: the simulated truth (``--simulate``), else ``None``.
        true_errors: errors of the true geometry and frames on the same data (simulation only).
        truth: the true corrections in the calibration's frame convention (simulation only).
        seconds: wall time of the identification and validation.
    """

    identification: Identification
    validation: Validation
    data: MeasuredPoses
    simulation: Simulation | None = None
    true_errors: tuple[np.ndarray, np.ndarray] | None = None
    truth: np.ndarray | None = None
    seconds: float = 0.0


def run_calibration(
    nominal: HexapodGeometry,
    data: MeasuredPoses,
    noise: Noise = Noise(),
    folds: int = 5,
    seed: int = 0,
    simulation: Simulation | None = None,
    progress: Progress = _no_progress,
    **identify_options,
) -> CalibrationResult:
    """Identify on all poses, validate by ``folds``-fold cross-validation, compare with the truth of a simulation."""
    start = time.perf_counter()
    ident = identify(nominal, data, noise, **identify_options)
    validation = cross_validate(nominal, data, noise, folds, seed, progress, **identify_options)
    seconds = time.perf_counter() - start
    true_errors = truth = None
    if simulation is not None:
        # the true geometry and frames given the same (noisy) readings: the floor any model can reach,
        # solved from the six legs as the validation's predictions are (no consistency test to fail)
        six = replace(simulation.true_geometry, measuring_legs=(), inclinometer=None)
        hexa = Hexapod.from_geometry(six)
        P = np.array([hexa.forward(r[:6]).pose for r in data.readings])
        true_errors = pose_errors(predict(simulation.measuring_frame, P, simulation.marker_frame), data.measured)
        geom, _, _ = regauge(
            ident.parameters, simulation.true_geometry, simulation.measuring_frame, simulation.marker_frame
        )
        truth = ident.parameters.delta_of(geom)
    return CalibrationResult(ident, validation, data, simulation, true_errors, truth, seconds)


def nominal_geometry(spec: str) -> HexapodGeometry:
    """The nominal geometry named by a preset, geometry file or URDF (read back off the URDF)."""
    hexa = load_hexapod(spec)
    if hexa.geometry is not None:
        return hexa.geometry
    return geometry_of_urdf(hexa.closed_loop)


def save_simulation(sim: Simulation, folder: str | Path) -> list[Path]:
    """Write a simulation's data and its truth into ``folder``.

    ``simulated_measured.csv`` (:mod:`hexapod_model.io.calibration_csv`: the ``--data``
    format, with the extra sensors' columns), ``true_geometry.toml`` and ``true_frames.json``.
    """
    folder = Path(folder)
    names = sim.nominal.reading_names[: sim.data.readings.shape[1]]
    paths = [save_poses(folder / "simulated_measured.csv", sim.data, names)]
    paths.append(save_geometry(sim.true_geometry, folder / "true_geometry.toml", "simulated true geometry"))
    frames = {"measuring_frame": sim.measuring_frame.tolist(), "marker_frame": sim.marker_frame.tolist()}
    paths.append(atomic_write_text(folder / "true_frames.json", json.dumps(frames, indent=2) + "\n"))
    return paths
