"""``hexapod evaluate``: workspace volume and Jakobović and Jelenković's Table II figures over it, in parallel.

The grid (cubic cells of ``cell`` m, centred on the home pose, sized by
:func:`~hexapod_model.workspace.probe_extent`) is split into z-slices solved by a
``ProcessPoolExecutor`` over all cores. Each finished slice is saved in ``OUT/checkpoint/``
(``slice_NNN.npz`` next to a ``meta.json`` of the settings), so an interrupted run resumes
where it stopped; changing a setting starts afresh.
"""

from __future__ import annotations

import io
import json
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..analysis.jacobian import kinematic_evaluation
from ..analysis.workspace import SliceResult, compute_slice, cone_rotations, probe_extent
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


_WORKER: dict = {}


def _init(spec: str) -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's: it saves and stops
    _WORKER["hexa"] = Hexapod.load(spec)


def _task(index: int, z: float, xs, ys, rotations, unit) -> SliceResult:
    return compute_slice(_WORKER["hexa"], index, z, xs, ys, rotations, unit)


def run_evaluation(
    spec: str,
    settings: Settings = Settings(),
    out: str | Path | None = None,
    workers: int | None = None,
    on_slice: Callable[[int, int], None] | None = None,
) -> dict:
    """Compute the workspace and its figures; returns the report dict (SI and chosen units).

    Args:
        spec: preset name, URDF file or geometry file (each worker process loads it).
        settings: grid and orientation cone.
        out: folder of the resumable checkpoint (``None``: no checkpoint).
        workers: processes (default: all cores).
        on_slice: called as ``on_slice(done, total)`` after each finished z-slice (progress).

    Raises:
        KeyboardInterrupt: re-raised after the finished slices were saved; a rerun with the
            same ``out`` resumes.
    """
    hexa = Hexapod.load(spec)
    unit = settings.length_unit or platform_radius(hexa)
    xs, ys, zs, cell = make_grid(hexa, settings.grid)
    rotations = cone_rotations(settings.cone_deg, settings.cone_samples)
    meta = {
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
                    int(d["index"]), d["inside"], d["kappa"], d["sigma_min"], d["abs_det"]
                )
        else:
            for f in ckpt.glob("slice_*.npz"):
                f.unlink()
            atomic_write_text(meta_path, json.dumps(meta, indent=1))
    todo = [k for k in range(len(zs)) if k not in done]
    resumed = len(done)
    workers = workers or os.cpu_count() or 1
    if todo:
        with ProcessPoolExecutor(
            max_workers=min(workers, len(todo)),
            initializer=_init,
            initargs=(str(Path(spec).resolve()) if Path(spec).exists() else spec,),
        ) as pool:
            futures = [pool.submit(_task, k, zs[k], xs, ys, rotations, unit) for k in todo]
            try:
                for fut in as_completed(futures):
                    r = fut.result()
                    done[r.index] = r
                    if ckpt is not None:
                        buf = io.BytesIO()  # atomic: an interrupted write must not leave a broken slice
                        np.savez_compressed(
                            buf,
                            index=r.index,
                            inside=r.inside,
                            kappa=r.kappa,
                            sigma_min=r.sigma_min,
                            abs_det=r.abs_det,
                        )
                        atomic_write_bytes(ckpt / f"slice_{r.index:03d}.npz", buf.getvalue())
                    if on_slice is not None:
                        on_slice(len(done), len(zs))
            except KeyboardInterrupt:
                pool.shutdown(wait=False, cancel_futures=True)
                raise
    stack = [done[k] for k in range(len(zs))]
    inside = np.array([s.inside for s in stack])
    figs = {name: np.array([getattr(s, name) for s in stack]) for name in ("kappa", "sigma_min", "abs_det")}
    n_in = int(inside.sum())
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
        "average": {k: (float(np.nanmean(v[inside])) if n_in else float("nan")) for k, v in figs.items()},
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
