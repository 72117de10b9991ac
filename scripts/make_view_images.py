"""Regenerate the snapshots of the README and docs/python.md.

Regenerate the snapshots of the README and docs/python.md: docs/img/reference.png (the reference hexapod at a
tilted pose) and docs/img/cell.png (the same pose with the UR10 coupled to the top plate).

    python scripts/make_view_images.py [--out docs/img]

Needs Debian's chromium (headless, no display).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from hexapod_model import Hexapod
from hexapod_model.viz.meshcat_scene import HexapodScene, solve_view_configuration, start_visualizer, stop_visualizer
from hexapod_model.viz.render import render_pngs, write_html
from hexapod_model.viz.robot_cell import add_cell

ROOT = Path(__file__).resolve().parent.parent
POSE = (0.03, -0.02, 0.41, 12.0, -8.0, 20.0)  # x, y, z (m), roll, pitch, yaw (deg)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    hexa = Hexapod.from_preset("reference")
    sol = solve_view_configuration(hexa, pose_xyz_rpy=POSE)
    vis = start_visualizer()
    with tempfile.TemporaryDirectory() as tmp:
        html = []
        try:
            for cell in (False, True):
                vis.delete()
                scene = HexapodScene(hexa, vis)
                scene.show(sol)
                if cell:
                    add_cell(scene, sol)
                html.append(write_html(vis, Path(tmp) / f"{'cell' if cell else 'reference'}.html"))
        finally:
            stop_visualizer(vis)
        for png in render_pngs(html, [args.out / "reference.png", args.out / "cell.png"], size=(1024, 768)):
            print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
