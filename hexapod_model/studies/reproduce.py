"""``hexapod reproduce``: Bem et al.'s accuracy study (§5.2, Table 1, Figs.

4-7) in simulation or on measured data.

Simulation: poses are drawn as in Bem et al. (2026) §5.2 (home +- 50 mm, roll/pitch/yaw +- 25 deg,
:func:`~hexapod_model.trajectories.box_poses`); a pose whose inverse kinematics leaves a stroke
or a Cardan angle limit is discarded and redrawn. The ground truth is the Cardan-aware model
(the URDF with its loop closures); the simulated encoder readings are the true prismatic values
plus Gaussian noise (default sigma 10 um, the order of the LinACE encoder accuracy); the
"measured" reference pose (motion capture) is the true pose, optionally with Gaussian noise
(``--reference-noise`` sigma in metres on each position coordinate, and sigma / r radians on
each rotation-vector component, with r the RMS platform anchor radius).

Every set of readings is solved with the Cardan-aware model (``Hexapod.forward_batch``, cold
start from home, retried with ``Hexapod.forward`` from the standard model's pose if needed)
and with the standard spherical model (:mod:`hexapod_model.analysis.standard`, batch). Errors are
eqs. 26-27: ``||p_ref - p_est||`` and the rotation angle of ``R_ref^T R_est``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..analysis.full_formulation import ForwardComparison
from ..analysis.standard import StandardModel
from ..analysis.trajectories import box_poses
from ..exceptions import HexapodError, InputError
from ..io.tables import LENGTH_COLUMNS, open_table, poses_from_table, write_table
from ..kinematics.hexapod import Hexapod
from ..lie import exp3, matrix_to_quaternion, rotation_angle
from .paper_table import summarise

DEFAULT_ENCODER_NOISE = 10e-6  # m, Gaussian sigma on each reading
DATA_COLUMNS = LENGTH_COLUMNS + ["x", "y", "z", "qx", "qy", "qz", "qw"]


@dataclass(frozen=True)
class StudyInput:
    """Readings (N, 6) (m, zero at home) and reference poses (N, 4, 4) to compare against."""

    readings: np.ndarray
    reference: np.ndarray
    source: str


Progress = Callable[[Iterable, int, str], Iterable]


def _no_progress(iterable: Iterable, total: int, desc: str) -> Iterable:
    return iterable


def simulate(
    hexa: Hexapod, n: int, seed: int = 0, encoder_noise: float = DEFAULT_ENCODER_NOISE, reference_noise: float = 0.0
) -> StudyInput:
    """``n`` feasible box poses, their noisy readings and (noisy) reference poses.

    Args:
        hexa: the true hexapod.
        n: poses to draw (at least 2).
        seed: random seed.
        encoder_noise: Gaussian sigma added to each reading (m).
        reference_noise: Gaussian sigma on each reference position coordinate (m), and
            ``reference_noise / r`` rad on each rotation-vector component.
    """
    if n < 2:
        raise InputError("poses", n, "need at least 2 poses for statistics")
    for name, v in (("encoder noise", encoder_noise), ("reference noise", reference_noise)):
        if not (np.isfinite(v) and v >= 0):
            raise InputError(name, v, "must be a finite standard deviation >= 0 (metres)")
    rng = np.random.default_rng(seed)
    poses: list[np.ndarray] = []
    lengths: list[np.ndarray] = []
    drawn = 0
    while len(poses) < n:
        batch = box_poses(hexa.home_pose, max(16, int(1.3 * (n - len(poses)))), seed=int(rng.integers(2**63)))
        need = n - len(poses)
        good = np.flatnonzero((sol := hexa.inverse_batch(batch)).converged)[:need]  # each row from home
        poses.extend(batch[good])
        lengths.extend(sol.lengths[good])
        drawn += int(good[-1]) + 1 if good.size == need else len(batch)  # drawn until the n-th feasible one
        if drawn > 50 * n:
            raise InputError("poses", n, f"only {len(poses)} of {drawn} drawn poses lie inside the limits")
    truth = np.array(poses)
    readings = np.array(lengths) + rng.normal(0.0, encoder_noise, (n, 6)) if encoder_noise else np.array(lengths)
    reference = truth.copy()
    if reference_noise:
        sm = StandardModel.from_hexapod(hexa)
        radius = float(np.sqrt(np.mean(np.sum(sm.platform_points[:, :2] ** 2, axis=1))))
        reference[:, :3, 3] += rng.normal(0.0, reference_noise, (n, 3))
        reference[:, :3, :3] = exp3(rng.normal(0.0, reference_noise / radius, (n, 3))) @ reference[:, :3, :3]
    return StudyInput(readings, reference, f"simulation ({drawn - n} of {drawn} drawn poses rejected)")


def load_measured(path: str | Path) -> StudyInput:
    """Read a measured data set: columns ``l1..l6`` (m) and ``x,y,z,qx,qy,qz,qw`` (reference).

    Every row must be valid under the line rules of :mod:`hexapod_model.io.tables` (the cell
    count of the header, finite numbers within its magnitude limit, a unit quaternion within
    its tolerance): the first row that is not raises :class:`InputError` naming its line.
    """
    with open_table(path, DATA_COLUMNS) as table:
        rows = table.read(DATA_COLUMNS)
    if len(rows) < 2:
        raise InputError("data rows", len(rows), f"{path}: need at least 2 measured poses")
    reference, pose_errors = poses_from_table(DATA_COLUMNS[6:], rows.values[:, 6:])
    for k in range(len(rows)):
        why = rows.errors[k] or pose_errors[k]
        if why:
            raise InputError("data row", k + 1, f"{path}: line {rows.lines[k]}: {why}")
    return StudyInput(rows.values[:, :6], reference, f"measured data {path}")


def save_measured(path: str | Path, data: StudyInput) -> Path:
    """Write ``data`` in the ``--data`` format (inverse of :func:`load_measured`)."""
    q = matrix_to_quaternion(data.reference[:, :3, :3])
    rows = [
        [*map(float, data.readings[k]), *map(float, data.reference[k, :3, 3]), *map(float, q[k])]
        for k in range(len(data.readings))
    ]
    write_table(path, DATA_COLUMNS, rows)
    return Path(path)


def solve_cardan(
    hexa: Hexapod, readings: np.ndarray, fallback: np.ndarray, progress: Progress = _no_progress
) -> tuple[np.ndarray, np.ndarray]:
    """Cardan-aware direct kinematics of every row; returns (N, 4, 4) poses and an ok mask.

    Starts from home (one ``forward_batch``); a row that fails is retried from the IK
    configuration of ``fallback[k]`` (the standard model's pose).
    """
    cold = hexa.forward_batch(readings)  # each row from home, as forward() from home
    out, ok = cold.poses.copy(), cold.converged.copy()
    retry = np.flatnonzero(~ok & (cold.status != "invalid_input"))  # invalid readings fail from any start
    for k in progress(retry, len(retry), "Cardan-aware FK, retried rows"):
        try:
            sol = hexa.forward(readings[k], guess=hexa.inverse(fallback[k], check=False).q, check=False)
        except HexapodError:
            continue
        if sol.converged:
            out[k], ok[k] = sol.pose, True
    return out, ok


def pose_errors(reference: np.ndarray, estimate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 26-27: translation error (mm) and rotation error (deg) per pose."""
    dp = np.linalg.norm(reference[:, :3, 3] - estimate[:, :3, 3], axis=1) * 1e3
    return dp, np.degrees(rotation_angle(reference[:, :3, :3], estimate[:, :3, :3]))


def standard_traces(sm: StandardModel, readings: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """(times s, ||dx||) per Newton step of the standard model, one pose at a time."""
    out = []
    for lm in readings:
        times: list[float] = []
        norms: list[float] = []
        start = time.perf_counter()

        def record(k, idx, step, times=times, norms=norms, start=start):
            times.append(time.perf_counter() - start)
            norms.append(float(np.linalg.norm(step[0])))

        sm.forward(lm, callback=record)
        out.append((np.array(times), np.array(norms)))
    return out


@dataclass(frozen=True)
class StudyResult:
    """What :func:`run_study` measured.

    Attributes:
        report: the Table 1 numbers (see :func:`summarise`).
        solved: (N,) rows solved by both models (the others are left out of the statistics).
        errors_cardan, errors_standard: (translation mm, rotation deg) of the solved rows.
        positions_m: (M, 3) reference positions of the solved rows relative to home (m).
        seconds_per_pose: {"cardan": s, "standard": s} mean solve times.
        traces: convergence traces for Figs. 6-7 (``None`` when skipped), with per-formulation
            summaries under ``"summary"``.
    """

    report: dict
    solved: np.ndarray
    errors_cardan: tuple[np.ndarray, np.ndarray]
    errors_standard: tuple[np.ndarray, np.ndarray]
    positions_m: np.ndarray
    seconds_per_pose: dict
    traces: dict | None


def run_study(
    hexa: Hexapod, data: StudyInput, convergence_poses: int | None = None, progress: Progress = _no_progress
) -> StudyResult:
    """Solve ``data`` with both models and compare with its reference poses (Table 1, Figs. 4-7).

    Args:
        hexa: the Cardan-aware model (the standard model is derived from it).
        data: readings and reference poses (from :func:`simulate` or :func:`load_measured`).
        convergence_poses: rows used for the convergence and conditioning traces (Figs. 6-7;
            ``None``: all, 0: none).
        progress: ``progress(iterable, total, description)`` wrapper for long loops.

    Raises:
        InputError: fewer than 2 rows solved by both models.
    """
    sm = StandardModel.from_hexapod(hexa)
    sm.forward(data.readings[:2])  # compile / load the numba kernels before timing
    hexa.forward(np.zeros(6), check=False)
    t0 = time.perf_counter()
    std = sm.forward(data.readings)
    t_std = time.perf_counter() - t0
    t0 = time.perf_counter()
    card, ok = solve_cardan(
        hexa, data.readings, np.where(std.converged[:, None, None], std.poses, hexa.home_pose), progress
    )
    t_card = time.perf_counter() - t0
    ok &= std.converged
    if ok.sum() < 2:
        raise InputError("poses", int(ok.sum()), "fewer than 2 rows were solved by both models")
    err_c, err_s = pose_errors(data.reference[ok], card[ok]), pose_errors(data.reference[ok], std.poses[ok])
    n = len(data.readings)
    k = n if convergence_poses is None else min(convergence_poses, n)
    traces = None
    if k > 0:
        fc = ForwardComparison(hexa)
        full, red = [], []
        for j in progress(range(k), k, "full vs reduced"):
            f, r = fc.traces(data.readings[j])
            full.append(f)
            red.append(r)
        rows = {"full": fc.full.G.shape[0], "reduced": fc.reduced.G.shape[0], "standard": 6}
        summary = {
            name: {
                "rows": rows[name],
                "iterations": float(np.mean([t.iterations for t in tr])),
                "ms": 1e3 * float(np.mean([t.times[-1] for t in tr if t.times.size])),
                "condition_number": float(np.mean([t.conditions.mean() for t in tr if t.conditions.size])),
            }
            for name, tr in (("full", full), ("reduced", red))
        }
        traces = {
            "full": full,
            "reduced": red,
            "standard": standard_traces(sm, data.readings[: min(k, 200)]),
            "rows": rows,
            "summary": summary,
        }
    return StudyResult(
        summarise(err_c, err_s),
        ok,
        err_c,
        err_s,
        data.reference[ok, :3, 3] - hexa.home_pose[:3, 3],
        {"cardan": t_card / n, "standard": t_std / n},
        traces,
    )
