"""Figure of ``hexapod sweep``: the trade-off between workspace volume and leg force per unit load."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..files import atomic_save_figure


def plot_pareto(rows: list[dict[str, Any]], path: str | Path) -> Figure:
    """Workspace volume against the largest leg force per newton of every valid candidate; returns the figure.

    The Pareto front (no other candidate has more volume and less force) is joined and its points
    labelled with their candidate id (the table's ``id``); points are coloured by the home
    condition number.
    """
    ok = [r for r in rows if r.get("status") == "ok" and float(r["volume_m3"]) > 0]
    fig = Figure(figsize=(7, 5))
    ax = fig.subplots()
    if ok:
        v = np.array([float(r["volume_m3"]) for r in ok]) * 1e6
        f = np.array([float(r["force_per_force_max"]) for r in ok])
        k = np.array([float(r["home_kappa"]) for r in ok])
        sc = ax.scatter(v, f, c=k, cmap="viridis", s=30, zorder=2)
        fig.colorbar(sc, ax=ax, label="home condition number")
        front = np.array([bool(r["pareto"]) for r in ok])
        order = np.argsort(v[front])
        ax.plot(v[front][order], f[front][order], "r-o", mfc="none", ms=10, zorder=3, label="Pareto front")
        for r, x, y in zip((r for r, on in zip(ok, front) if on), v[front], f[front]):
            ax.annotate(str(r["id"]), (x, y), textcoords="offset points", xytext=(6, 6), fontsize=8)
        ax.legend(loc="best")
    invalid = len(rows) - len(ok)
    ax.set_xlabel("workspace volume for the tool cone (cm^3)")
    ax.set_ylabel("largest leg force per unit force over it (N/N)")
    ax.set_title(f"{len(ok)} candidates" + (f" ({invalid} invalid or empty, not shown)" if invalid else ""))
    ax.grid(alpha=0.3)
    atomic_save_figure(fig, path)
    return fig
