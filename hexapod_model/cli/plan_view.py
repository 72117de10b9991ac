"""``hexapod view --plan`` and ``hexapod snapshot --plan``: a changeover plan in meshcat."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..extras import require_extra
from ..files import check_output_path
from ._common import serve_until_interrupted


def run_view_plan(args: argparse.Namespace) -> int:
    """Animate the plan at its own pace (``--rate`` points per second at most), then serve until Ctrl-C."""
    require_extra("view")
    from ..planning.writers import read_plan
    from ..viz.meshcat_scene import start_visualizer, stop_visualizer
    from ..viz.plan_scene import PlanScene

    plan = read_plan(args.plan)
    vis = start_visualizer()
    try:
        scene = PlanScene(plan, vis)
        print(f"meshcat: {vis.url()}", flush=True)
        start, last = time.monotonic(), -1.0
        for k in range(len(plan.t)):
            if plan.t[k] - last < 1.0 / args.rate and k != len(plan.t) - 1:
                continue  # fewer frames than points: keep to the rate
            last = float(plan.t[k])
            time.sleep(max(0.0, start + last - time.monotonic()))
            scene.show(k)
        print(f"played {plan.total_time:.2f} s of {', '.join(plan.order)}", file=sys.stderr)
        if not args.once:
            serve_until_interrupted()
    finally:
        stop_visualizer(vis)
    return 0


def frame_paths(output: str, label: str, k: int, suffix: str) -> Path:
    """``OUTPUT_NN_LABEL.suffix`` next to ``output``."""
    out = Path(output)
    return out.with_name(f"{out.stem}_{k:02d}_{label}{suffix}")


def run_snapshot_plan(args: argparse.Namespace, size: tuple[int, int]) -> int:
    """Write the plan's key frames (its start, each carry's start and end, its end) as HTML and PNG (``size`` px)."""
    require_extra("view")
    from ..planning.writers import read_plan
    from ..viz.meshcat_scene import start_visualizer, stop_visualizer
    from ..viz.plan_scene import PlanScene, key_frames
    from ..viz.render import find_chromium, render_pngs, write_html

    check_output_path(args.output, args.plan)
    if args.png:
        check_output_path(args.png, args.plan)
        find_chromium()
    plan = read_plan(args.plan)
    frames = key_frames(plan)
    htmls, pngs = [], []
    vis = start_visualizer()
    try:
        scene = PlanScene(plan, vis)
        for n, (k, label) in enumerate(frames):
            scene.show(k)
            htmls.append(write_html(vis, frame_paths(args.output, label, n, ".html")))
            if args.png:
                pngs.append(str(frame_paths(args.png, label, n, ".png")))
    finally:
        stop_visualizer(vis)
    print(f"wrote {len(htmls)} key frames: {htmls[0]} ...", file=sys.stderr)
    if args.png:
        render_pngs(htmls, pngs, size=size)
        print(f"wrote {len(pngs)} PNGs: {pngs[0]} ...", file=sys.stderr)
    return 0
