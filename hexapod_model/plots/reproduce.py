"""Figures of ``hexapod reproduce`` (matplotlib ``Figure`` objects saved as PNG).

Shaped like the offset-Cardan paper's:

* ``reproduce_errors_cardan.png`` / ``reproduce_errors_standard.png`` (Figs. 4-5): the
  reference pose positions (mm from home, base frame) as 3-D point clouds coloured by the
  translation error (mm) and by the rotation error (deg) of one model;
* ``reproduce_histograms.png``: the error distributions of both models on log axes, with
  Bem et al.'s Table 1 means (measured on the real hexapod) as dashed lines;
* ``reproduce_convergence.png`` (Fig. 6): Newton update norm ``||dx||`` against computation
  time for the full (72-row), reduced (36-row) and standard solvers, cold start from home;
* ``reproduce_conditioning.png`` (Fig. 7): mean +- std of the Jacobian condition number per
  iteration, full vs reduced.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..files import atomic_save_figure
from ..studies.paper_table import PAPER

COLOURS = {"full": "#d62728", "reduced": "#1f77b4", "standard": "#2ca02c"}
LABELS = {
    "full": "full Cardan-aware (eq. 6)",
    "reduced": "reduced Cardan-aware (eq. 14)",
    "standard": "standard Stewart-Gough (eq. 3)",
}
ROWS = {"full": 72, "reduced": 36, "standard": 6}


def _label(name: str, rows: dict | None) -> str:
    return LABELS[name].replace("(", f"({(rows or ROWS)[name]} rows, ")


def _figure(width: float, height: float, dpi: int) -> Figure:
    """A matplotlib :class:`~matplotlib.figure.Figure` (no pyplot, no backend choice)."""
    return Figure(figsize=(width, height), dpi=dpi)


def error_clouds(path: Path, positions_mm: np.ndarray, err: tuple[np.ndarray, np.ndarray], title: str) -> Path:
    """Figs. 4-5: two 3-D scatters of the pose positions (mm), coloured by each error."""
    fig = _figure(9.0, 4.2, 80)
    for k, (values, label, cmap) in enumerate(
        ((err[0], "translation error [mm]", "viridis"), (err[1], "rotation error [deg]", "plasma"))
    ):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        order = np.argsort(values)  # largest errors drawn last, on top
        vmax = float(np.percentile(values, 99))
        sc = ax.scatter(
            *positions_mm[order].T, c=values[order], cmap=cmap, s=3, depthshade=False, linewidths=0, vmin=0.0, vmax=vmax
        )
        ax.set_xlabel("x [mm]", labelpad=-2)
        ax.set_ylabel("y [mm]", labelpad=-2)
        ax.set_zlabel("z [mm]", labelpad=-2)
        ax.tick_params(labelsize=7, pad=0)
        ax.set_title(f"{label}\nmean {np.mean(values):.3g}, std {np.std(values, ddof=1):.3g}", fontsize=9)
        fig.colorbar(sc, ax=ax, shrink=0.65, pad=0.1, extend="max").ax.tick_params(labelsize=7)
    fig.suptitle(title, fontsize=11)
    fig.subplots_adjust(left=0.0, right=0.95, bottom=0.04, top=0.86, wspace=0.15)
    atomic_save_figure(fig, path)
    return path


def histograms(path: Path, err_cardan, err_standard) -> Path:
    """Error distributions of both models (log-spaced bins), with Bem et al.'s means marked."""
    fig = _figure(8.0, 3.3, 80)
    axes = fig.subplots(1, 2)
    for k, (ax, unit, key) in enumerate(zip(axes, ("mm", "deg"), ("translation_mean_mm", "rotation_mean_deg"))):
        a, b = np.asarray(err_cardan[k]), np.asarray(err_standard[k])
        both = np.concatenate([a, b])
        pos = both[both > 0]
        lo = float(pos.min()) if pos.size else 1e-12
        hi = max(float(both.max()), 10 * lo)
        bins = np.logspace(np.log10(lo), np.log10(hi), 50)
        for values, name in ((a, "reduced"), (b, "standard")):
            label = "Cardan-aware" if name == "reduced" else "standard"
            ax.hist(
                np.maximum(values, lo),
                bins=bins,
                color=COLOURS[name],
                alpha=0.6,
                label=f"{label}: mean {np.mean(values):.3g} {unit}",
            )
        for model, name in (("cardan", "reduced"), ("spherical", "standard")):
            ax.axvline(PAPER[model][key], color=COLOURS[name], ls="--", lw=1.2)
        ax.set_xscale("log")
        ax.set_xlabel(f"{'translation' if k == 0 else 'rotation'} error [{unit}] (log)")
        ax.set_ylabel("poses")
        ax.set_ylim(0, ax.get_ylim()[1] * 1.3)  # room for the legend
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle(f"Pose errors over {len(err_cardan[0])} poses (dashed: Bem et al. 2026, Table 1 means)", fontsize=10)
    fig.tight_layout()
    atomic_save_figure(fig, path)
    return path


def convergence(path: Path, traces: dict) -> Path:
    """Fig. 6: ``||dx||`` vs time; thin lines for 25 poses, thick line = median per iteration."""
    fig = _figure(7.0, 4.2, 90)
    ax = fig.subplots()
    for name in ("full", "reduced", "standard"):
        runs = [(t.times, t.step_norms) if hasattr(t, "times") else t for t in traces[name]]
        runs = [(np.asarray(a) * 1e3, np.asarray(b)) for a, b in runs if len(a)]
        for times, norms in runs[:25]:
            ax.plot(times, norms, color=COLOURS[name], alpha=0.15, lw=0.8)
        depth = max(len(r[0]) for r in runs)
        med_t = [np.median([r[0][i] for r in runs if len(r[0]) > i]) for i in range(depth)]
        med_n = [np.median([r[1][i] for r in runs if len(r[1]) > i]) for i in range(depth)]
        keep = [i for i in range(depth) if sum(len(r[0]) > i for r in runs) >= max(1, len(runs) // 10)]
        ax.plot(
            np.take(med_t, keep),
            np.take(med_n, keep),
            "o-",
            color=COLOURS[name],
            lw=2,
            ms=4,
            label=f"{_label(name, traces.get('rows'))}: {len(runs)} poses",
        )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("computation time [ms] (log)")
    ax.set_ylabel(r"update norm $\|\Delta x\|_2$")
    ax.set_title("Newton convergence from the home pose (Bem et al. (2026) Fig. 6)", fontsize=11)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    atomic_save_figure(fig, path)
    return path


def conditioning(path: Path, full: list, reduced: list, rows: dict | None = None) -> Path:
    """Fig. 7: mean +- std of the condition number at each iteration."""
    fig = _figure(6.0, 4.0, 90)
    ax = fig.subplots()
    for name, runs, dx in (("full", full, -0.08), ("reduced", reduced, 0.08)):
        conds = [t.conditions for t in runs]
        depth = max(len(c) for c in conds)
        its = [i for i in range(depth) if sum(len(c) > i for c in conds) >= max(2, len(conds) // 20)]
        mean = np.array([np.mean([c[i] for c in conds if len(c) > i]) for i in its])
        std = np.array([np.std([c[i] for c in conds if len(c) > i]) for i in its])
        x = np.array(its) + 1
        ax.errorbar(x + dx, mean, yerr=std, fmt="o-", color=COLOURS[name], capsize=4, lw=1.5, label=_label(name, rows))
    ax.set_xlabel("iteration")
    ax.set_ylabel(r"condition number $\kappa(J)$")
    ax.set_title(
        f"Jacobian conditioning, mean $\\pm$ std over {len(full)} poses (Bem et al. 2026, Fig. 7)", fontsize=10
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_save_figure(fig, path)
    return path


def write_figures(
    out: str | Path, positions_m: np.ndarray, err_cardan, err_standard, traces: dict | None
) -> list[Path]:
    """Write all figures into ``out`` (created); returns the paths.

    ``positions_m`` (N, 3) are the reference positions relative to home (m); ``traces`` may be None (no Figs.
    6-7).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    pos = np.asarray(positions_m) * 1e3
    paths = [
        error_clouds(
            out / "reproduce_errors_cardan.png", pos, err_cardan, "Cardan-aware model (Bem et al. 2026, Fig. 4)"
        ),
        error_clouds(
            out / "reproduce_errors_standard.png",
            pos,
            err_standard,
            "Standard Stewart-Gough model (Bem et al. 2026, Fig. 5)",
        ),
        histograms(out / "reproduce_histograms.png", err_cardan, err_standard),
    ]
    if traces is not None:
        paths.append(convergence(out / "reproduce_convergence.png", traces))
        paths.append(
            conditioning(out / "reproduce_conditioning.png", traces["full"], traces["reduced"], traces.get("rows"))
        )
    return paths
