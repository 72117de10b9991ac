"""Figures of ``hexapod calibrate`` (matplotlib ``Figure`` objects saved as PNG).

* ``calibration_errors.png``: cumulative distributions of the held-out pose errors before and
  after calibration (and of the true geometry in a simulation), translation and rotation;
* ``calibration_parameters.png``: the identified corrections with 1-sigma error bars, in units
  of each parameter's expected magnitude; held parameters marked, the truth when simulated;
* ``calibration_singular_values.png``: the singular values of the scaled identification
  Jacobian against the identifiability threshold.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..files import atomic_save_figure
from ..studies.calibrate import CalibrationResult

COLOURS = {"before": "#d62728", "after": "#1f77b4", "true": "#2ca02c"}


def errors(path: Path, result: CalibrationResult) -> Path:
    """Cumulative distributions of the held-out errors before / after (and the truth's)."""
    fig = Figure(figsize=(8.0, 3.3), dpi=90)
    axes = fig.subplots(1, 2)
    sets = [("before", result.validation.before, "nominal geometry, frames fitted")]
    sets.append(("after", result.validation.after, "calibrated"))
    if result.true_errors is not None:
        sets.append(("true", result.true_errors, "true geometry"))
    for k, (ax, unit) in enumerate(zip(axes, ("mm", "deg"))):
        for key, e, label in sets:
            values = np.sort(e[k])
            share = np.arange(1, values.size + 1) / values.size
            ax.step(
                values, share, where="post", color=COLOURS[key], label=f"{label}: mean {np.mean(values):.3g} {unit}"
            )
        ax.set_xlabel(f"{'translation' if k == 0 else 'rotation'} error [{unit}]")
        ax.set_ylabel("share of poses")
        ax.set_xlim(left=0)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="center right")
    fig.suptitle(
        f"Held-out pose errors ({result.validation.folds}-fold), {len(result.data.readings)} poses", fontsize=10
    )
    fig.tight_layout()
    atomic_save_figure(fig, path)
    return path


def parameters(path: Path, result: CalibrationResult) -> Path:
    """Corrections / expected magnitude with 1-sigma bars; held parameters as grey crosses at 0."""
    ident = result.identification
    ps = ident.parameters
    x = np.arange(ps.size)
    y, e = ident.delta / ps.scales, ident.sigma / ps.scales
    fig = Figure(figsize=(12.0, 4.0), dpi=90)
    ax = fig.subplots()
    ok = ident.identifiable
    ax.errorbar(x[ok], y[ok], yerr=e[ok], fmt="o", ms=3, color=COLOURS["after"], capsize=2, label="identified, 1 sigma")
    ax.plot(x[~ok], np.zeros((~ok).sum()), "x", color="0.5", label="held at nominal")
    if result.truth is not None:
        ax.plot(x, result.truth / ps.scales, "_", ms=9, color=COLOURS["true"], label="simulated truth")
    for leg in range(1, 6):
        ax.axvline(ps.legs[leg][0] - 0.5, color="0.85", lw=0.8)
    ax.set_xticks([int(ps.legs[i][0]) + len(ps.legs[i]) // 2 for i in range(6)], [f"leg {i + 1}" for i in range(6)])
    ax.set_ylabel("correction / expected magnitude")
    ax.set_title(
        "Identified joint parameters (per leg: base centre xyz, axis tilt/turn, offset; platform the same; "
        "encoder zero)",
        fontsize=9,
    )
    ax.axhline(0, color="0.6", lw=0.8)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    atomic_save_figure(fig, path)
    return path


def singular_values(path: Path, result: CalibrationResult, max_sigma: float = 1.0) -> Path:
    """The spectrum of the scaled identification Jacobian, with the threshold ``1 / max_sigma``."""
    s = result.identification.spectrum
    fig = Figure(figsize=(6.0, 3.5), dpi=90)
    ax = fig.subplots()
    ax.semilogy(np.arange(1, s.size + 1), np.maximum(s, 1e-12), "o-", ms=3, color=COLOURS["after"])
    ax.axhline(1.0 / max_sigma, color=COLOURS["before"], ls="--", label="threshold: 1-sigma = expected magnitude")
    ax.set_xlabel("combination (descending)")
    ax.set_ylabel("singular value (scaled, whitened)")
    ax.set_title("Identifiability: singular values, frame convention applied", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_save_figure(fig, path)
    return path


def write_figures(out: str | Path, result: CalibrationResult, max_sigma: float = 1.0) -> list[Path]:
    """Write the three figures into ``out`` (created); returns the paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    return [
        errors(out / "calibration_errors.png", result),
        parameters(out / "calibration_parameters.png", result),
        singular_values(out / "calibration_singular_values.png", result, max_sigma),
    ]
