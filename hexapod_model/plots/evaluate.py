"""Figure of ``hexapod evaluate``: condition number and sigma_min over workspace sections."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..files import atomic_save_figure


def plot_sections(r: dict, path: str | Path) -> None:
    """Jakobović and Jelenković (2002) Fig.

    5: condition number and sigma_min over a vertical (x-z through home) and a horizontal (x-y at home height)
    section; blank = outside the workspace.
    """
    a = r["_arrays"]
    xs, ys, zs = a["xs"], a["ys"], a["zs"]
    iy, iz = len(ys) // 2, int(np.argmin(np.abs(zs - (zs[0] + zs[-1]) / 2)))
    home_z = r.get("home_z")
    if home_z is not None:
        iz = int(np.argmin(np.abs(zs - home_z)))
    fig = Figure(figsize=(8, 6.4))
    axes = fig.subplots(2, 2)
    for col, (key, label) in enumerate((("kappa", "condition number"), ("sigma_min", "sigma_min"))):
        for row, (img, ext, xl, yl, title) in enumerate(
            (
                (
                    a[key][:, iy, :],
                    (xs[0], xs[-1], zs[0], zs[-1]),
                    "x (m)",
                    "z (m)",
                    f"vertical section y = {ys[iy]:.3f} m",
                ),
                (
                    a[key][iz],
                    (xs[0], xs[-1], ys[0], ys[-1]),
                    "x (m)",
                    "y (m)",
                    f"horizontal section z = {zs[iz]:.3f} m",
                ),
            )
        ):
            ax = axes[row, col]
            im = ax.imshow(np.ma.masked_invalid(img), origin="lower", extent=ext, aspect="equal", cmap="viridis")
            fig.colorbar(im, ax=ax, shrink=0.8)
            ax.set_title(f"{label}: {title}", fontsize=8)
            ax.set_xlabel(xl, fontsize=8)
            ax.set_ylabel(yl, fontsize=8)
            ax.tick_params(labelsize=7)
    fig.suptitle(
        f"{r['name']}: mean over a {r['cone_deg']:g} deg orientation cone (Jakobović and Jelenković 2002, Fig. 5)",
        fontsize=9,
    )
    fig.tight_layout()
    atomic_save_figure(fig, path, dpi=80)
