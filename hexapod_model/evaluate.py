"""``hexapod evaluate``: workspace volume and seed 002's Table II figures over it, in parallel.

The grid (cubic cells of ``cell`` m, centred on the home pose, sized by
:func:`~hexapod_model.workspace.probe_extent`) is split into z-slices solved by a
``ProcessPoolExecutor`` over all cores. Each finished slice is saved in ``OUT/checkpoint/``
(``slice_NNN.npz`` next to a ``meta.json`` of the settings), so an interrupted run resumes
where it stopped; changing a setting starts afresh.
"""

from __future__ import annotations

import json
import os
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .hexapod import Hexapod
from .jacobian import kinematic_evaluation
from .workspace import SliceResult, compute_slice, cone_rotations, probe_extent

# seed 002 Tables I (volume) and II, in the paper's units (read as cm)
PAPER = {
    "seed002_model1": {"volume": 16919.0, "kappa": 1.835, "sigma_min": 1.022, "abs_det": 5.842},
    "seed002_model2": {"volume": 16677.0, "kappa": 2.655, "sigma_min": 1.225, "abs_det": 51.177},
}
PAPER_UNIT = 0.01  # m per paper length unit (our reading: cm)


@dataclass(frozen=True)
class Settings:
    """Evaluation settings. ``grid``: points along the longest side of the probed box;
    ``cone_deg``/``cone_samples``: the orientation cone; ``length_unit``: m per length unit of
    the Jacobian figures (None: the platform anchor radius, our reading of seed 002)."""

    grid: int = 21
    cone_deg: float = 20.0
    cone_samples: int = 8
    length_unit: float | None = None


def load_spec(spec: str) -> Hexapod:
    """Preset name, URDF file, or geometry file (``.toml``, ``.json``, ``.yaml``)."""
    if str(spec).lower().endswith((".toml", ".json", ".yaml", ".yml")):
        from .geometry import load_geometry

        return Hexapod.from_geometry(load_geometry(spec))
    return Hexapod.from_urdf(spec)


def platform_radius(hexa: Hexapod) -> float:
    """Largest horizontal radius of the platform anchors (m); for a URDF, of the closure
    frames on the platform."""
    g = hexa.geometry
    if g is not None:
        return float(np.max(np.linalg.norm(g.platform_points()[:, :2], axis=1)))
    m = hexa.model.model
    pts = np.array([m.frames[leg.anchor_frame].placement.translation for leg in hexa.model.legs])
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
    _WORKER["hexa"] = load_spec(spec)


def _task(index: int, z: float, xs, ys, rotations, unit) -> SliceResult:
    return compute_slice(_WORKER["hexa"], index, z, xs, ys, rotations, unit)


def run_evaluation(spec: str, settings: Settings = Settings(), out: str | Path | None = None,
                   workers: int | None = None, show_progress: bool = False) -> dict:
    """Compute the workspace and its figures; returns the report dict (SI and chosen units)."""
    hexa = load_spec(spec)
    unit = settings.length_unit or platform_radius(hexa)
    xs, ys, zs, cell = make_grid(hexa, settings.grid)
    rotations = cone_rotations(settings.cone_deg, settings.cone_samples)
    meta = {"spec": str(spec), "grid": settings.grid, "cone_deg": settings.cone_deg,
            "cone_samples": settings.cone_samples, "length_unit": unit, "nx": len(xs), "ny": len(ys),
            "nz": len(zs), "cell": cell}
    done: dict[int, SliceResult] = {}
    ckpt = None
    if out is not None:
        ckpt = Path(out) / "checkpoint"
        ckpt.mkdir(parents=True, exist_ok=True)
        meta_path = ckpt / "meta.json"
        if meta_path.exists() and json.loads(meta_path.read_text()) == json.loads(json.dumps(meta)):
            for f in ckpt.glob("slice_*.npz"):
                d = np.load(f)
                done[int(d["index"])] = SliceResult(int(d["index"]), d["inside"], d["kappa"], d["sigma_min"], d["abs_det"])
        else:
            for f in ckpt.glob("slice_*.npz"):
                f.unlink()
            meta_path.write_text(json.dumps(meta, indent=1))
    todo = [k for k in range(len(zs)) if k not in done]
    resumed = len(done)
    bar = None
    if show_progress:
        from tqdm import tqdm

        bar = tqdm(total=len(zs), initial=resumed, desc="evaluate (z slices)", file=sys.stderr, unit="slice")
    workers = workers or os.cpu_count() or 1
    if todo:
        with ProcessPoolExecutor(max_workers=min(workers, len(todo)), initializer=_init,
                                 initargs=(str(Path(spec).resolve()) if Path(spec).exists() else spec,)) as pool:
            futures = [pool.submit(_task, k, zs[k], xs, ys, rotations, unit) for k in todo]
            try:
                for fut in as_completed(futures):
                    r = fut.result()
                    done[r.index] = r
                    if ckpt is not None:
                        np.savez_compressed(ckpt / f"slice_{r.index:03d}.npz", index=r.index, inside=r.inside,
                                            kappa=r.kappa, sigma_min=r.sigma_min, abs_det=r.abs_det)
                    if bar is not None:
                        bar.update(1)
            except KeyboardInterrupt:
                pool.shutdown(wait=False, cancel_futures=True)
                where = f"; rerun with --out {out} to resume" if ckpt is not None else ""
                print(f"\ninterrupted after {len(done)} of {len(zs)} slices{where}", file=sys.stderr)
                raise
    if bar is not None:
        bar.close()
    stack = [done[k] for k in range(len(zs))]
    inside = np.array([s.inside for s in stack])
    figs = {name: np.array([getattr(s, name) for s in stack]) for name in ("kappa", "sigma_min", "abs_det")}
    n_in = int(inside.sum())
    home = kinematic_evaluation(hexa, hexa.q_home, unit)
    g = hexa.geometry
    report = {
        "hexapod": str(spec), "name": g.name if g else str(spec), "length_unit_m": unit, "cell_m": cell,
        "grid": {"nx": len(xs), "ny": len(ys), "nz": len(zs), "x": [xs[0], xs[-1]], "y": [ys[0], ys[-1]],
                 "z": [zs[0], zs[-1]]},
        "cone_deg": settings.cone_deg, "orientations": len(rotations), "points_inside": n_in,
        "resumed_slices": resumed,
        "volume_m3": n_in * cell ** 3, "volume_paper_units3": n_in * (cell / PAPER_UNIT) ** 3,
        "average": {k: (float(np.nanmean(v[inside])) if n_in else float("nan")) for k, v in figs.items()},
        "home": {"kappa": home.condition_number, "sigma_min": home.sigma_min, "abs_det": home.abs_det,
                 "singular_values": home.singular_values.tolist()},
        "paper": PAPER.get(g.name if g else ""),
    }
    report["_arrays"] = {"xs": xs, "ys": ys, "zs": zs, "inside": inside, **figs}
    return report


def print_report(r: dict, file=None) -> None:
    file = file or sys.stdout
    u = r["length_unit_m"]
    print(f"hexapod {r['hexapod']}: workspace for a {r['cone_deg']:g} deg cone ({r['orientations']} orientations), "
          f"grid {r['grid']['nx']}x{r['grid']['ny']}x{r['grid']['nz']}, cell {r['cell_m'] * 1e3:.4g} mm", file=file)
    print(f"  Jacobian figures with lengths in units of {u:g} m (dl = J [v; w], base frame)", file=file)
    p = r["paper"] or {}
    print(f"{'':24s}{'ours':>14s}{'seed 002':>12s}", file=file)
    rows = [("volume (cm^3)", r["volume_paper_units3"], p.get("volume")),
            ("volume (m^3)", r["volume_m3"], None),
            ("points inside", r["points_inside"], None),
            ("mean kappa", r["average"]["kappa"], p.get("kappa")),
            ("mean sigma_min", r["average"]["sigma_min"], p.get("sigma_min")),
            ("mean |det J|", r["average"]["abs_det"], p.get("abs_det")),
            ("home kappa", r["home"]["kappa"], None),
            ("home sigma_min", r["home"]["sigma_min"], None),
            ("home |det J|", r["home"]["abs_det"], None)]
    for name, ours, paper in rows:
        print(f"  {name:22s}{ours:14.5g}{(f'{paper:12.5g}' if paper is not None else ''):>12s}", file=file)


def plot_sections(r: dict, path: str | Path) -> None:
    """Seed 002 Fig. 5: condition number and sigma_min over a vertical (x-z through home) and a
    horizontal (x-y at home height) section; blank = outside the workspace."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a = r["_arrays"]
    xs, ys, zs = a["xs"], a["ys"], a["zs"]
    iy, iz = len(ys) // 2, int(np.argmin(np.abs(zs - (zs[0] + zs[-1]) / 2)))
    home_z = r.get("home_z")
    if home_z is not None:
        iz = int(np.argmin(np.abs(zs - home_z)))
    fig, axes = plt.subplots(2, 2, figsize=(8, 6.4))
    for col, (key, label) in enumerate((("kappa", "condition number"), ("sigma_min", "sigma_min"))):
        for row, (img, ext, xl, yl, title) in enumerate((
                (a[key][:, iy, :], (xs[0], xs[-1], zs[0], zs[-1]), "x (m)", "z (m)", f"vertical section y = {ys[iy]:.3f} m"),
                (a[key][iz], (xs[0], xs[-1], ys[0], ys[-1]), "x (m)", "y (m)", f"horizontal section z = {zs[iz]:.3f} m"))):
            ax = axes[row, col]
            im = ax.imshow(np.ma.masked_invalid(img), origin="lower", extent=ext, aspect="equal", cmap="viridis")
            fig.colorbar(im, ax=ax, shrink=0.8)
            ax.set_title(f"{label}: {title}", fontsize=8)
            ax.set_xlabel(xl, fontsize=8)
            ax.set_ylabel(yl, fontsize=8)
            ax.tick_params(labelsize=7)
    fig.suptitle(f"{r['name']}: mean over a {r['cone_deg']:g} deg orientation cone (seed 002 Fig. 5)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def register(sub) -> None:
    p = sub.add_parser("evaluate", help="workspace for a cone of orientations and seed 002's kinematic figures")
    p.add_argument("urdf", nargs="?", default="reference", metavar="URDF|PRESET|GEOMETRY",
                   help="URDF file, preset name or geometry file (.toml/.json), e.g. docs/geometries/seed002_model1.toml")
    p.add_argument("--grid", type=int, default=Settings.grid, help="grid points along the longest side (default %(default)s)")
    p.add_argument("--cone-deg", type=float, default=Settings.cone_deg, help="tool cone half-angle (deg)")
    p.add_argument("--cone-samples", type=int, default=Settings.cone_samples, help="tilted orientations on the cone")
    p.add_argument("--length-unit", type=float, default=None,
                   help="m per length unit of the Jacobian figures (default: platform anchor radius)")
    p.add_argument("--workers", type=int, default=None, help="processes (default: all cores)")
    p.add_argument("--out", default=None, help="directory for the PNG and the resumable checkpoint")
    p.add_argument("--json", help="write the report as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    settings = Settings(args.grid, args.cone_deg, args.cone_samples, args.length_unit)
    try:
        r = run_evaluation(args.urdf, settings, args.out, args.workers, show_progress=sys.stderr.isatty())
    except KeyboardInterrupt:
        return 130
    r["home_z"] = float(load_spec(args.urdf).home_pose[2, 3])
    print_report(r)
    if args.out:
        png = Path(args.out) / "evaluate_sections.png"
        plot_sections(r, png)
        print(f"  figure: {png}" + (f" (resumed {r['resumed_slices']} slices)" if r["resumed_slices"] else ""))
    if args.json:
        Path(args.json).write_text(json.dumps({k: v for k, v in r.items() if not k.startswith("_")}, indent=2))
    return 0
