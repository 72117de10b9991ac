"""Figure of ``hexapod track``: worst errors per 100 ms window (the tracking paper's Figs. 7-10)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..files import atomic_save_figure
from ..studies.track import TrackingRun


def plot_run(run: TrackingRun, path: str | Path) -> None:
    """Jakobović and Jelenković (2002) Figs. 7-10: worst angle and coordinate errors per 100 ms window (log scale)."""
    ends, w = run.window_max()
    fig = Figure(figsize=(6.4, 4.8))
    axes = fig.subplots(2, 1, sharex=True)
    for ax, cols, names, unit in (
        (axes[0], range(3), ("roll", "pitch", "yaw"), "deg"),
        (axes[1], range(3, 6), ("x", "y", "z"), "m"),
    ):
        for c, name, style in zip(cols, names, ("-", "--", ":")):
            ax.semilogy(ends, np.maximum(w[:, c], 1e-18), style, label=name)
        ax.set_ylabel(f"abs. error ({unit})")
        ax.legend(loc="upper right", fontsize=8, ncol=3)
        ax.grid(True, which="major", alpha=0.3)
    axes[1].set_xlabel("time (s)")
    axes[0].set_title(
        f"trajectory {run.trajectory}, speed x{run.speed:g}, predictor {run.predictor}: worst error per 100 ms",
        fontsize=9,
    )
    fig.tight_layout()
    atomic_save_figure(fig, path, dpi=80)
