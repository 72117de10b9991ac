"""``hexapod evaluate``: workspace volume and Jakobović and Jelenković's Table II figures over it, in parallel.

The grid (cubic cells of ``cell`` m, centred on the home pose, sized by
:func:`~hexapod_model.workspace.probe_extent`) is split into z-slices solved as Dask tasks
(:mod:`~hexapod_model.studies.cluster`: a LocalCluster over all cores, or a running cluster).
Each finished slice is saved in ``OUT/checkpoint/``
(``slice_NNN.npz`` next to a ``meta.json`` of the settings), so an interrupted run resumes
where it stopped; changing a setting starts afresh.
"""

from __future__ import annotations

import io
import json
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.jacobian import kinematic_evaluation
from ..analysis.workspace import WORST, SliceResult, compute_slice, cone_rotations, probe_extent
from ..files import atomic_write_bytes, atomic_write_text
from ..kinematics.hexapod import Hexapod

# Jakobović and Jelenković (2002) Tables I (volume) and II, in the paper's units (read as cm)
PAPER = {
    "seed002_model1": {"volume": 16919.0, "kappa": 1.835, "sigma_min": 1.022, "abs_det": 5.842},
    "seed002_model2": {"volume": 16677.0, "kappa": 2.655, "sigma_min": 1.225, "abs_det": 51.177},
}
PAPER_UNIT = 0.01  # m per paper length unit (our reading: cm)


@dataclass(frozen=True)
class Settings:
    """Evaluation settings.

    ``grid``: points along the longest side of the probed box; ``cone_deg``/``cone_samples``: the orientation
    cone; ``length_unit``: m per length unit of the Jacobian figures (None: the platform anchor radius, our
    reading of Jakobović and Jelenković (2002)).
    """

    grid: int = 21
    cone_deg: float = 20.0
    cone_samples: int = 8
    length_unit: float | None = None


def platform_radius(hexa: Hexapod) -> float:
    """Largest horizontal radius of the platform anchors (m); for a URDF, of the closure frames on the platform."""
    g = hexa.geometry
    if g is not None:
        return float(np.max(np.linalg.norm(g.platform_points()[:, :2], axis=1)))
    m = hexa.model
    pts = np.array([m.frames[leg.anchor_frame].placement.translation for leg in hexa.closed_loop.legs])
    return float(np.max(np.linalg.norm(pts[:, :2], axis=1))) or 0.1


def make_grid(hexa: Hexapod, grid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Axes ``xs, ys, zs`` (m) with cubic cells, symmetric about home in x and y, through home."""
    home = hexa.home_pose[:3, 3]
    box = probe_extent(hexa, step=max(float(np.ptp(hexa.stroke)) / 200.0, 1e-4))
    half = np.abs(box - home[:, None]).max(axis=1) * 1.15 + 1e-9
    longest = max(2 * half[0], 2 * half[1], 1.15 * (box[2, 1] - box[2, 0]))
    cell = longest / (grid - 1) if grid > 1 else longest
    cell = max(cell, 1e-6)
    axes = []
    for a in range(2):
        n = int(np.ceil(half[a] / cell))
        axes.append(home[a] + cell * np.arange(-n, n + 1))
    lo = int(np.floor((box[2, 0] - home[2]) * 1.15 / cell)) - 1
    hi = int(np.ceil((box[2, 1] - home[2]) * 1.15 / cell)) + 1
    zs = home[2] + cell * np.arange(lo, hi + 1)
    return axes[0], axes[1], zs[zs > 0], cell


#: Hexapods loaded by this process's tasks, by spec (a Dask worker keeps them between tasks)
_LOADED: dict[tuple[str, str | None], Hexapod] = {}
#: version of the checkpoint's slice files (meta.json): a change starts afresh
CHECKPOINT_VERSION = 3


def hexapod_payload(spec: str) -> tuple[str, str | None]:
    """What a task needs to load ``spec`` anywhere: ``(file name, its text)`` for a file, ``(preset, None)``."""
    path = Path(spec)
    return (path.name, path.read_text()) if path.is_file() else (str(spec), None)


def loaded(name: str, text: str | None) -> Hexapod:
    """The hexapod of a :func:`hexapod_payload`, loaded once per process.

    A file's text is written under its own name into a temporary folder and loaded from there: the same
    reading as ``Hexapod.load`` of the original, on a worker that cannot see the original.
    """
    key = (name, text)
    hexa = _LOADED.get(key)
    if hexa is None:
        if text is None:
            hexa = Hexapod.load(name)
        else:
            with tempfile.TemporaryDirectory() as tmp:
                (Path(tmp) / name).write_text(text)
                hexa = Hexapod.load(str(Path(tmp) / name))
        _LOADED[key] = hexa
    return hexa


def slice_task(payload: tuple[str, str | None], index: int, z: float, xs, ys, rotations, unit) -> SliceResult:
    """One z-slice of the hexapod of ``payload`` (:func:`hexapod_payload`): a Dask task."""
    return compute_slice(loaded(*payload), index, z, xs, ys, rotations, unit)


@dataclass(frozen=True)
class Plan:
    """The grid, the orientations and the length unit of one evaluation."""

    xs: np.ndarray
    ys: np.ndarray
    zs: np.ndarray
    cell: float
    rotations: np.ndarray
    unit: float


def plan_for(hexa: Hexapod, settings: Settings) -> Plan:
    """The :class:`Plan` of ``hexa`` under ``settings`` (the grid is probed from home)."""
    unit = settings.length_unit or platform_radius(hexa)
    xs, ys, zs, cell = make_grid(hexa, settings.grid)
    return Plan(xs, ys, zs, cell, cone_rotations(settings.cone_deg, settings.cone_samples), unit)


def evaluate_hexapod(hexa: Hexapod, settings: Settings = Settings(), spec: str = "") -> dict:
    """The report of :func:`run_evaluation`, every slice computed in this process, one after the other.

    The same slices, grid and arithmetic as :func:`run_evaluation`: the same figures (a sweep's task).
    """
    plan = plan_for(hexa, settings)
    done = {k: compute_slice(hexa, k, z, plan.xs, plan.ys, plan.rotations, plan.unit) for k, z in enumerate(plan.zs)}
    return summarise(hexa, spec or (hexa.geometry.name if hexa.geometry else "<hexapod>"), settings, plan, done, 0)


def _save_slice(ckpt: Path, r: SliceResult) -> None:
    buf = io.BytesIO()  # atomic: an interrupted write must not leave a broken slice
    limits = r.inside if r.inside_limits is None else r.inside_limits
    np.savez_compressed(
        buf,
        index=r.index,
        inside=r.inside,
        kappa=r.kappa,
        sigma_min=r.sigma_min,
        abs_det=r.abs_det,
        worst=r.worst,
        inside_limits=limits,
    )
    atomic_write_bytes(ckpt / f"slice_{r.index:03d}.npz", buf.getvalue())


def run_evaluation(
    spec: str,
    settings: Settings = Settings(),
    out: str | Path | None = None,
    workers: int | None = None,
    on_slice: Callable[[int, int], None] | None = None,
    scheduler: str | None = None,
    on_client: Callable[[Any], None] | None = None,
) -> dict:
    """Compute the workspace and its figures; returns the report dict (SI and chosen units).

    The z-slices are Dask tasks (:mod:`~hexapod_model.studies.cluster`): on the cluster at ``scheduler``,
    else on a LocalCluster of ``workers`` processes; ``workers=1`` without ``scheduler`` computes them
    in this process.

    Args:
        spec: preset name, URDF, MJCF or geometry file (its text travels with the tasks: workers need not
            see the file).
        settings: grid and orientation cone.
        out: folder of the resumable checkpoint (``None``: no checkpoint).
        workers: LocalCluster processes (default: all cores).
        on_slice: called as ``on_slice(done, total)`` after each finished z-slice (progress).
        scheduler: ``tcp://HOST:PORT`` of a running Dask scheduler.
        on_client: called with the ``distributed.Client`` once connected (e.g. to show the dashboard).

    Raises:
        InputError: no scheduler answering at ``scheduler``; dask.distributed not installed.
        KeyboardInterrupt: re-raised after the finished slices were saved; a rerun with the
            same ``out`` resumes.
    """
    hexa = Hexapod.load(spec)
    plan = plan_for(hexa, settings)
    xs, ys, zs, cell, unit = plan.xs, plan.ys, plan.zs, plan.cell, plan.unit
    meta = {
        "version": CHECKPOINT_VERSION,
        "spec": str(spec),
        "grid": settings.grid,
        "cone_deg": settings.cone_deg,
        "cone_samples": settings.cone_samples,
        "length_unit": unit,
        "nx": len(xs),
        "ny": len(ys),
        "nz": len(zs),
        "cell": cell,
    }
    done: dict[int, SliceResult] = {}
    ckpt = None
    if out is not None:
        ckpt = Path(out) / "checkpoint"
        ckpt.mkdir(parents=True, exist_ok=True)
        meta_path = ckpt / "meta.json"
        if meta_path.exists() and json.loads(meta_path.read_text()) == json.loads(json.dumps(meta)):
            for f in ckpt.glob("slice_*.npz"):
                d = np.load(f)
                done[int(d["index"])] = SliceResult(
                    int(d["index"]),
                    d["inside"],
                    d["kappa"],
                    d["sigma_min"],
                    d["abs_det"],
                    d["worst"],
                    d["inside_limits"],
                )
        else:
            for f in ckpt.glob("slice_*.npz"):
                f.unlink()
            atomic_write_text(meta_path, json.dumps(meta, indent=1))
    todo = [k for k in range(len(zs)) if k not in done]
    resumed = len(done)

    def finished(r: SliceResult) -> None:
        done[r.index] = r
        if ckpt is not None:
            _save_slice(ckpt, r)
        if on_slice is not None:
            on_slice(len(done), len(zs))

    if todo and scheduler is None and workers == 1:
        for k in todo:
            finished(compute_slice(hexa, k, zs[k], xs, ys, plan.rotations, unit))
    elif todo:
        from .cluster import dask_client

        payload = hexapod_payload(spec)
        with dask_client(scheduler, workers) as client:
            if on_client is not None:
                on_client(client)
            from distributed import as_completed

            futures = [
                client.submit(slice_task, payload, k, zs[k], xs, ys, plan.rotations, unit, pure=False) for k in todo
            ]
            try:
                for fut in as_completed(futures):
                    finished(fut.result())
            except KeyboardInterrupt:
                client.cancel(futures)
                raise
    return summarise(hexa, str(spec), settings, plan, done, resumed)


def summarise(
    hexa: Hexapod, spec: str, settings: Settings, plan: Plan, done: dict[int, SliceResult], resumed: int
) -> dict:
    """The report of the finished slices ``done`` (all of ``plan``'s z-slices)."""
    xs, ys, zs, cell, unit, rotations = plan.xs, plan.ys, plan.zs, plan.cell, plan.unit, plan.rotations
    stack = [done[k] for k in range(len(zs))]
    inside = np.array([s.inside for s in stack])
    figs = {name: np.array([getattr(s, name) for s in stack]) for name in ("kappa", "sigma_min", "abs_det")}
    worst = np.array([s.worst for s in stack])  # (nz, 5, ny, nx)
    n_in = int(inside.sum())
    n_limits = int(sum(int((s.inside if s.inside_limits is None else s.inside_limits).sum()) for s in stack))
    home = kinematic_evaluation(hexa, hexa.q_home, unit)
    g = hexa.geometry
    report = {
        "hexapod": str(spec),
        "name": g.name if g else str(spec),
        "length_unit_m": unit,
        "cell_m": cell,
        "grid": {
            "nx": len(xs),
            "ny": len(ys),
            "nz": len(zs),
            "x": [xs[0], xs[-1]],
            "y": [ys[0], ys[-1]],
            "z": [zs[0], zs[-1]],
        },
        "cone_deg": settings.cone_deg,
        "orientations": len(rotations),
        "points_inside": n_in,
        "resumed_slices": resumed,
        "volume_m3": n_in * cell**3,
        "volume_paper_units3": n_in * (cell / PAPER_UNIT) ** 3,
        "points_inside_limits": n_limits,
        "volume_limits_m3": n_limits * cell**3,
        "volume_limits_paper_units3": n_limits * (cell / PAPER_UNIT) ** 3,
        "body_checked": hexa.check_body,
        "average": {k: (float(np.nanmean(v[inside])) if n_in else float("nan")) for k, v in figs.items()},
        "worst": {
            name: (float(np.min(worst[:, i][inside]) if "_min" in name else np.max(worst[:, i][inside])))
            if n_in
            else float("nan")
            for i, name in enumerate(WORST)
        },
        "home": {
            "kappa": home.condition_number,
            "sigma_min": home.sigma_min,
            "abs_det": home.abs_det,
            "singular_values": home.singular_values.tolist(),
        },
        "paper": PAPER.get(g.name if g else ""),
    }
    report["_arrays"] = {"xs": xs, "ys": ys, "zs": zs, "inside": inside, **figs}
    return report
