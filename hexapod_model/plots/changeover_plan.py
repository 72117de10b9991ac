"""Figure of ``hexapod changeover plan --plot``: the arm's joints and the carried legs over time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..files import atomic_save_figure
from ..planning.model import Plan


def plan_figure(plan: Plan, velocity_limits: np.ndarray | None = None) -> Figure:
    """The plan's figure: three panels against time (s), the carries shaded.

    The UR10's joints (deg), their speeds (rad/s, or the share of ``velocity_limits`` when
    given) and the carried hexapods' leg readings (mm).
    """
    fig = Figure(figsize=(8.0, 7.2))
    ax_q, ax_v, ax_l = fig.subplots(3, 1, sharex=True)
    short = [n.replace("_joint", "") for n in plan.joint_names]
    for j, name in enumerate(short):
        ax_q.plot(plan.t, np.degrees(plan.q[:, j]), label=name)
        v = plan.qd[:, j] if velocity_limits is None else plan.qd[:, j] / velocity_limits[j]
        ax_v.plot(plan.t, v, label=name)
    ax_q.set_ylabel("joint (deg)")
    ax_q.legend(loc="upper right", fontsize=7, ncol=3)
    ax_v.set_ylabel("speed (rad/s)" if velocity_limits is None else "speed / URDF limit")
    for name in plan.order:
        rows = np.array([k for k, (p, f) in enumerate(zip(plan.phase, plan.fixture)) if p == "carry" and f == name])
        for i in range(6):
            ax_l.plot(plan.t[rows], plan.readings[rows, i] * 1e3, label=f"{name} leg {i + 1}")
        for ax in (ax_q, ax_v, ax_l):
            ax.axvspan(plan.t[rows[0]], plan.t[rows[-1]], color="0.9", zorder=0)
    ax_l.set_ylabel("leg reading (mm)")
    ax_l.legend(loc="upper right", fontsize=6, ncol=len(plan.order) * 2)
    ax_l.set_xlabel("time (s); shaded: carrying")
    for ax in (ax_q, ax_v, ax_l):
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"changeover {' -> '.join(plan.order)}: {plan.total_time:.2f} s", fontsize=10)
    fig.tight_layout()
    return fig


def plot_plan(plan: Plan, path: str | Path, velocity_limits: np.ndarray | None = None) -> Path:
    """Save :func:`plan_figure` as a PNG (atomically)."""
    return atomic_save_figure(plan_figure(plan, velocity_limits), path, dpi=90)
