"""``hexapod sweep``: evaluate every candidate geometry of a spec as a Dask task, resumably, into one table.

Under ``OUT``: ``geometries/<id>.toml`` (each candidate, the file ``hexapod evaluate`` reads),
``results/<id>.json`` (its figures, written when its task finishes: a rerun computes only the
candidates without one) and ``sweep.csv`` (one row per candidate, spec order). The id is a hash of
the base geometry, the candidate's parameters and the evaluation settings, so a changed spec gets
new ids and never reuses a stale result.
"""

from __future__ import annotations

import hashlib
import json
import time
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.workspace import WORST
from ..description.geometry import HexapodGeometry, geometry_from_dict
from ..description.geometry_toml import geometry_to_toml
from ..exceptions import HexapodError
from ..files import atomic_write_csv, atomic_write_text
from ..kinematics.hexapod import Hexapod
from .evaluate import Settings, evaluate_hexapod
from .sweep_placement import (
    PLACEMENT_METRICS,
    PlacementSettings,
    placement_figures,
    rank_rows,
    write_placement_table,
)
from .sweep_spec import SweepSpec, apply_parameters

RESULT_VERSION = 2
#: the table's figures: the workspace (collision-free, within the cones; ``volume_limits_m3``: within the
#: stroke and joint limits alone), its worst cases (:data:`~hexapod_model.analysis.workspace.WORST`), home
METRICS = (
    "volume_m3",
    "volume_limits_m3",
    "points_inside",
    "kappa_mean",
    *WORST,
    "home_kappa",
    "home_sigma_min",
    "length_unit_m",
    "seconds",
)


def candidate_id(spec: SweepSpec, values: dict[str, float]) -> str:
    """12 hex digits naming a candidate: its base, parameters, evaluation settings and checks."""
    key = {
        "version": RESULT_VERSION,
        "base": spec.base.to_dict(),
        "values": values,
        "settings": asdict(spec.settings),
        "leg_stiffness": spec.leg_stiffness,
        "leg_clearance": spec.leg_clearance,
    }
    if spec.placement is not None:  # only then: the ids of a sweep without one stay as they were
        key["placement"] = asdict(spec.placement)
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:12]


def _segment_distance(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> float:
    """Smallest distance (m) between the segments ``p0 p1`` and ``q0 q1`` (closest points, clamped)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, f = d1 @ d1, d2 @ d2, d2 @ r
    c, b = d1 @ r, d1 @ d2
    den = a * e - b * b
    s = float(np.clip((b * f - c * e) / den, 0.0, 1.0)) if den > 1e-18 * a * e else 0.0
    t = (b * s + f) / e
    if t < 0.0 or t > 1.0:
        t = float(np.clip(t, 0.0, 1.0))
        s = float(np.clip((b * t - c) / a, 0.0, 1.0))
    return float(np.linalg.norm(p0 + s * d1 - q0 - t * d2))


def crossing_legs(g: HexapodGeometry, clearance: float) -> str | None:
    """Why ``g``'s legs cross at home (two legs closer than ``clearance`` m away from shared anchors), or None."""
    b, p = g.base_points(), g.platform_points() + g.home_translation
    for i in range(6):
        for j in range(i + 1, 6):
            if np.allclose(b[i], b[j]) or np.allclose(p[i], p[j]):
                continue  # a shared joint (3-6 layouts): they meet there by design
            # the middle 90 % of each leg: legs from neighbouring anchors approach each other at the ends
            pi0, pi1 = b[i] + 0.05 * (p[i] - b[i]), b[i] + 0.95 * (p[i] - b[i])
            pj0, pj1 = b[j] + 0.05 * (p[j] - b[j]), b[j] + 0.95 * (p[j] - b[j])
            d = _segment_distance(pi0, pi1, pj0, pj1)
            if d <= max(clearance, 1e-6):
                return f"legs {i + 1} and {j + 1} cross at home ({d * 1e3:.3g} mm apart, clearance {clearance:g} m)"
    return None


def evaluate_candidate(
    toml_text: str,
    settings: Settings,
    leg_stiffness: float | None,
    clearance: float,
    placement: PlacementSettings | None = None,
) -> dict[str, Any]:
    """The figures of one candidate geometry (TOML text), or ``{"status": "invalid", "reason": ...}``.

    A Dask task: it needs nothing but its arguments (the geometry travels as text, read back exactly).
    With ``placement``, the placement score too (:mod:`.sweep_placement`), and without the workspace
    figures when ``placement.workspace`` is false.
    """
    start = time.perf_counter()
    try:
        g = geometry_from_dict(tomllib.loads(toml_text), "candidate")
        crossing = crossing_legs(g, clearance)
        if crossing:
            return {"status": "invalid", "reason": crossing}
        placed = {} if placement is None else placement_figures(g, placement)
        if placement is not None and not placement.workspace:
            return {"status": "ok", "reason": "", **placed, "seconds": time.perf_counter() - start}
        hexa = Hexapod.from_geometry(g)
    except HexapodError as exc:
        return {"status": "invalid", "reason": " ".join(str(exc).split())}
    r = evaluate_hexapod(hexa, settings, g.name)
    worst = dict(r["worst"])
    k = leg_stiffness if leg_stiffness is not None else float("nan")
    for name in ("stiffness_translational_min", "stiffness_rotational_min"):
        worst[name] *= k  # per N/m of leg stiffness in the slices
    return {
        "status": "ok",
        "reason": "",
        "volume_m3": float(r["volume_m3"]),
        "volume_limits_m3": float(r["volume_limits_m3"]),
        "points_inside": r["points_inside"],
        "kappa_mean": r["average"]["kappa"],
        **worst,
        "home_kappa": r["home"]["kappa"],
        "home_sigma_min": r["home"]["sigma_min"],
        "length_unit_m": r["length_unit_m"],
        **placed,
        "seconds": time.perf_counter() - start,
    }


def pareto_front(volume: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Boolean mask of the candidates no other beats on both: larger volume and smaller leg force per N."""
    ok = np.isfinite(volume) & np.isfinite(force) & (volume > 0)
    front = np.zeros(len(volume), dtype=bool)
    for i in np.flatnonzero(ok):
        others = ok & (volume >= volume[i]) & (force <= force[i]) & ((volume > volume[i]) | (force < force[i]))
        front[i] = not others.any()
    return front


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    scheduler: str | None = None,
    workers: int | None = None,
    on_progress: Callable[[int, int], None] | None = None,
    on_client: Callable[[Any], None] | None = None,
) -> dict[str, Any]:
    """Evaluate the missing candidates of ``spec`` under ``out`` and write ``sweep.csv``.

    Args:
        spec: the parsed spec.
        out: output folder (created).
        scheduler: ``tcp://HOST:PORT`` of a running Dask scheduler; ``None``: a LocalCluster.
        workers: LocalCluster processes (default: all cores).
        on_progress: called as ``on_progress(done, total)`` over the candidates to compute.
        on_client: called with the ``distributed.Client`` once connected.

    Returns:
        ``{"rows": [...], "computed": n, "reused": m, "table": path}`` (rows as written, spec order; ``reused``:
        results of earlier runs; candidates whose parameters give no geometry are neither); with a
        ``[placement]`` table also ``"ranked"`` (the valid rows, best first) and ``"placement_table"``.

    Raises:
        InputError: no scheduler answering at ``scheduler``; dask.distributed not installed.
    """
    out = Path(out)
    (out / "geometries").mkdir(parents=True, exist_ok=True)
    (out / "results").mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    todo: dict[str, tuple[str, list[int]]] = {}  # id -> geometry text, its rows (a value listed twice: one task)
    reused = 0
    for values in spec.candidates():
        cid = candidate_id(spec, values)
        row: dict[str, Any] = {"id": cid, **values, "geometry": ""}
        rows.append(row)
        try:
            g = apply_parameters(spec.base, values, f"{spec.base.name}_{cid}")
        except HexapodError as exc:
            row |= {"status": "invalid", "reason": " ".join(str(exc).split())}
            continue
        path = out / "geometries" / f"{cid}.toml"
        if not path.exists():
            comment = f"candidate {cid} of a sweep over {spec.base_source}: " + json.dumps(values)
            atomic_write_text(path, geometry_to_toml(g, comment))
        row["geometry"] = str(path)
        saved = out / "results" / f"{cid}.json"
        if saved.exists():
            row |= json.loads(saved.read_text())
            reused += 1
        else:
            todo.setdefault(cid, (path.read_text(), []))[1].append(len(rows) - 1)
    if todo:
        for cid, result in _compute(spec, todo, scheduler, workers, on_progress, on_client):
            atomic_write_text(out / "results" / f"{cid}.json", json.dumps(result) + "\n")
            for k in todo[cid][1]:
                rows[k] |= result
    for row in rows:
        for name in METRICS:
            row.setdefault(name, float("nan"))
    volume = np.array([float(r["volume_m3"]) for r in rows])
    force = np.array([float(r["force_per_force_max"]) for r in rows])
    for row, on_front in zip(rows, pareto_front(volume, force)):
        row["pareto"] = bool(on_front)
    summary: dict[str, Any] = {"rows": rows, "computed": len(todo), "reused": reused}
    extra: tuple[str, ...] = ()
    if spec.placement is not None:
        extra = PLACEMENT_METRICS
        ranked = rank_rows(rows)
        summary["placement_table"] = write_placement_table(out / "placement.csv", ranked, list(spec.parameters))
        summary["ranked"] = ranked
    summary["table"] = write_table(out / "sweep.csv", rows, list(spec.parameters), extra)
    return summary


def _compute(
    spec: SweepSpec,
    todo: dict[str, tuple[str, list[int]]],
    scheduler: str | None,
    workers: int | None,
    on_progress: Callable[[int, int], None] | None,
    on_client: Callable[[Any], None] | None,
) -> Iterator[tuple[str, dict[str, Any]]]:
    """``(id, result)`` of every candidate of ``todo`` as its Dask task finishes."""
    from distributed import as_completed

    from .cluster import dask_client

    with dask_client(scheduler, workers) as client:
        if on_client is not None:
            on_client(client)
        args = (spec.settings, spec.leg_stiffness, spec.leg_clearance, spec.placement)
        futures = {
            client.submit(evaluate_candidate, text, *args, key=f"candidate-{cid}", pure=False): cid
            for cid, (text, _) in todo.items()
        }
        try:
            for n, fut in enumerate(as_completed(futures), start=1):
                yield futures[fut], fut.result()
                if on_progress is not None:
                    on_progress(n, len(todo))
        except (KeyboardInterrupt, GeneratorExit):
            client.cancel(list(futures))
            raise


def write_table(path: Path, rows: list[dict[str, Any]], parameters: list[str], extra: tuple[str, ...] = ()) -> Path:
    """``sweep.csv``: id, status, reason, the parameters, the metrics, ``extra``, pareto, geometry (atomically)."""
    header = ["id", "status", "reason", *parameters, *METRICS, *extra, "pareto", "geometry"]
    return atomic_write_csv(path, header, rows)
