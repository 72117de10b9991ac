"""Write the figures of docs/evaluate.md into docs/img/ (matplotlib, Agg).

* evaluate_seed002_model1.png: Fig. 5 of Jakobović and Jelenković (2002), model 1 (kappa, sigma_min sections);
* track_B_reference.png: Jakobović and Jelenković (2002) Figs. 7-10, trajectory B at 1 kHz on the reference hexapod;
* track_B_three_six.png: Jakobović and Jelenković (2002) Figs. 9-10, trajectory B on the 3-6 preset without and with
  prediction (the 'division' onto another branch);
* track_singular_passage.png: the spherical preset turned through its 90 deg yaw singularity,
  without prediction (follows the wrong branch, flagged) and with eq. 22 (stays on the true one);
* three_six_assemblies.png: every assembly of the 3-6 sensor for one set of readings (Shi, She and Duan (2016)).

Usage: python scripts/make_eval_figures.py [--grid N]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import hexapod_model as hm  # noqa: E402
from hexapod_model.kinematics.three_six import ThreeSixFK  # noqa: E402
from hexapod_model.lie import rpy_to_matrix  # noqa: E402
from hexapod_model.plots.evaluate import plot_sections  # noqa: E402
from hexapod_model.plots.track import plot_run  # noqa: E402
from hexapod_model.studies.evaluate import Settings, run_evaluation  # noqa: E402
from hexapod_model.studies.track import simulate  # noqa: E402
from hexapod_model.tracking.tracker import Tracker, pose_distance  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
IMG = ROOT / "docs" / "img"


def _save(fig, title: str, name: str) -> None:
    """Title, tight layout, PNG in docs/img/, close."""
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(IMG / name, dpi=80)
    plt.close(fig)


def evaluate_figure(grid: int) -> None:
    spec = ROOT / "docs" / "geometries" / "seed002_model1.toml"
    r = run_evaluation(str(spec), Settings(grid=grid))
    r["home_z"] = float(hm.load_geometry(spec).home_height)
    plot_sections(r, IMG / "evaluate_seed002_model1.png")


def track_figure() -> None:
    hexa = hm.Hexapod.from_preset("reference")
    plot_run(simulate(hexa, "B", 1, "eq22"), IMG / "track_B_reference.png")


def three_six_division_figure() -> None:
    """Jakobović and Jelenković (2002) Figs. 9/10 on the 3-6 preset: trajectory B without and with prediction."""
    hexa = hm.Hexapod.from_preset("3-6")
    fig, axes = plt.subplots(2, 1, figsize=(6.4, 4.8), sharex=True)
    for ax, predictor in zip(axes, ("none", "eq22")):
        run = simulate(hexa, "B", 1, predictor)
        ends, w = run.window_max()
        for c, name, style in zip(range(3), ("roll", "pitch", "yaw"), ("-", "--", ":")):
            ax.semilogy(ends, np.maximum(w[:, c], 1e-16), style, label=name)
        s = run.summary()
        ax.set_title(
            f"predictor {predictor}: {s['branch_jumps']} branch jump(s), {s['flagged']} samples flagged", fontsize=9
        )
        ax.set_ylabel("abs. error (deg)")
        ax.legend(loc="lower right", fontsize=7, ncol=3)
        ax.grid(True, alpha=0.3)
    axes[1].set_xlabel("time (s)")
    _save(
        fig,
        "3-6 preset, trajectory B at 1 kHz: worst angle error per 100 ms (Jakobović and Jelenković (2002) Figs. 9-10)",
        "track_B_three_six.png",
    )


def singular_passage_figure() -> None:
    hexa = hm.Hexapod.from_preset("spherical")
    yaws = np.linspace(80.0, 100.0, 2001)
    poses, lengths, sol = [], [], None
    for yaw in np.radians(yaws):
        T = hexa.home_pose.copy()
        T[:3, :3] = rpy_to_matrix(0.0, 0.0, yaw)
        sol = hexa.inverse(T, guess=sol)
        poses.append(T)
        lengths.append(sol.lengths)
    fig, axes = plt.subplots(2, 1, figsize=(6.4, 4.8), sharex=True)
    for ax, predictor in zip(axes, ("none", "eq22")):
        tracker = Tracker(hexa, predictor, initial=hexa.inverse(poses[0]))
        res = [tracker.step(l) for l in lengths]
        err = np.array([pose_distance(T, r.pose, 0.25) for T, r in zip(poses, res)])
        flagged = np.array([not r.ok for r in res])
        ax.semilogy(yaws, np.maximum(err, 1e-16), "k-", lw=1, label="pose error vs truth (m, rot. x 0.25 m)")
        ax.fill_between(yaws, 1e-16, 1, where=flagged, color="tab:orange", alpha=0.3, label="flagged by the tracker")
        ax.set_ylim(1e-16, 1)
        ax.set_ylabel("error")
        ax.set_title(f"predictor {predictor}", fontsize=9)
        ax.legend(loc="upper left", fontsize=7)
    axes[1].set_xlabel("true yaw (deg); the spherical preset is singular at 90 deg")
    _save(
        fig,
        "1 kHz tracking through a forward-kinematics singularity (Jakobović and Jelenković 2002, §V)",
        "track_singular_passage.png",
    )


def three_six_figure() -> None:
    hexa = hm.Hexapod.from_preset("3-6")
    T = hexa.home_pose.copy()
    T[:3, 3] += [0.02, -0.01, 0.015]
    T[:3, :3] = rpy_to_matrix(0.1, -0.15, 0.2)
    lengths = hexa.inverse(T).lengths
    fk = ThreeSixFK(hexa.geometry)
    sols = [s for s in fk.solve_all(lengths) if s.pose[2, 3] > 0]
    best = fk.solve(lengths, reference=hexa.home_pose)
    fig = plt.figure(figsize=(6.4, 5.2))
    ax = fig.add_subplot(projection="3d")
    b = fk.base
    ax.plot(*np.vstack([b, b[:1]]).T, "k-", lw=1.5)
    for s in sols:
        chosen = np.allclose(s.pose, best.pose)
        A = s.points
        style = dict(
            color="tab:blue" if chosen else "tab:gray", lw=2.0 if chosen else 0.8, alpha=1.0 if chosen else 0.6
        )
        ax.plot(*np.vstack([A, A[:1]]).T, **style)
        for k in range(3):
            for j in (2 * k, 2 * k + 1):
                ax.plot(*np.vstack([b[j], A[k]]).T, **style)
    ax.set_title(
        f"3-6 sensor: {len(sols)} assemblies above the base for one set of readings\n"
        f"(blue: nearest home = the Newton solution; mirrors below the base not drawn)",
        fontsize=8,
    )
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    fig.tight_layout()
    fig.savefig(IMG / "three_six_assemblies.png", dpi=80)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=25)
    ap.add_argument("--out", type=Path, default=IMG, help="figure directory (default docs/img)")
    args = ap.parse_args()
    globals()["IMG"] = args.out  # the figure functions write to IMG
    IMG.mkdir(parents=True, exist_ok=True)
    evaluate_figure(args.grid)
    track_figure()
    three_six_division_figure()
    singular_passage_figure()
    three_six_figure()
    for name in (
        "evaluate_seed002_model1",
        "track_B_reference",
        "track_B_three_six",
        "track_singular_passage",
        "three_six_assemblies",
    ):
        p = IMG / f"{name}.png"
        print(f"{p}: {p.stat().st_size // 1024} kB")


if __name__ == "__main__":
    main()
