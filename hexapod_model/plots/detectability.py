"""Figure of ``hexapod evaluate --detectability``: each reading's minimal detectable bias over a workspace section."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..analysis.detectability import DetectabilityMap
from ..files import atomic_save_figure


def plot_detectability(dmap: DetectabilityMap, path: str | Path, title: str = "") -> None:
    """One panel per reading: its minimal detectable bias (um for legs, urad for tilts) over the x-y section.

    Blank cells are outside the workspace.
    """
    m = len(dmap.names)
    cols = min(4, m)
    rows = math.ceil(m / cols)
    fig = Figure(figsize=(3.2 * cols, 2.9 * rows + 0.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    ext = [1e3 * dmap.xs[0], 1e3 * dmap.xs[-1], 1e3 * dmap.ys[0], 1e3 * dmap.ys[-1]]
    for j, ax in enumerate(axes):
        if j >= m:
            ax.set_visible(False)
            continue
        name = dmap.names[j]
        unit = "urad" if name.startswith("tilt") else "um"
        im = ax.imshow(1e6 * dmap.mdb[:, :, j], origin="lower", extent=ext, cmap="viridis", aspect="equal")
        fig.colorbar(im, ax=ax, shrink=0.85, label=unit)
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    head = f"minimal detectable bias (false-alarm rate {dmap.alpha:g}, power {dmap.power:g}) at z = {dmap.z:.3g} m"
    fig.suptitle(f"{title}: {head}" if title else head, fontsize=10)
    atomic_save_figure(fig, path)
