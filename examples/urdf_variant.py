"""Make a URDF variant of a hexapod from its geometry file and look at it headless.

    python examples/urdf_variant.py [GEOMETRY.toml | PRESET] [--raise 0.03] [--out variant/]

Reads a geometry file (docs/geometry.md; or a preset's geometry, by default ``reference``),
makes a variant with the platform raised by ``--raise`` metres at home (same anchors, longer
legs), writes the variant's geometry file and URDF, loads the URDF as any user of the file
would, and renders the variant at a tilted pose: a self-contained HTML scene (opens in a browser
with no server) and, where Debian's ``chromium`` is installed, a PNG. No display is needed.
"""

import argparse
import dataclasses
from pathlib import Path

import hexapod_model as hm
from hexapod_model.description.geometry_toml import save_geometry
from hexapod_model.exceptions import RenderError
from hexapod_model.viz.meshcat_scene import HexapodScene, solve_view_configuration, start_visualizer, stop_visualizer
from hexapod_model.viz.render import find_chromium, render_pngs, write_html

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("geometry", nargs="?", default="reference", help="geometry file or preset name")
ap.add_argument("--raise", dest="dz", type=float, default=0.03, help="m (default 0.03)")
ap.add_argument("--out", type=Path, default=Path("variant"))
args = ap.parse_args()

geometry = hm.get_preset(args.geometry) if args.geometry in hm.PRESETS else hm.load_geometry(args.geometry)
variant = dataclasses.replace(geometry, name=f"{geometry.name}_raised", home_height=geometry.home_height + args.dz)
args.out.mkdir(parents=True, exist_ok=True)
save_geometry(variant, args.out / f"{variant.name}.toml", comment=f"{args.geometry} raised by {args.dz} m")
urdf = hm.write_urdf(variant, args.out / f"{variant.name}.urdf")

hexa = hm.Hexapod.from_urdf(urdf, compiled=False)  # the file as Pinocchio and every tool reads it
home = hexa.home_pose[2, 3]
tilted = (0.02, -0.01, home + 0.01, 8.0, -5.0, 10.0)  # x, y, z (m), roll, pitch, yaw (deg)
sol = solve_view_configuration(hexa, pose_xyz_rpy=tilted)
print(
    f"{urdf}: home height {home:.3f} m (was {geometry.home_height:.3f}); leg readings at the tilted pose "
    + " ".join(f"{v * 1e3:.1f}" for v in sol.lengths)
    + " mm"
)

vis = start_visualizer()  # a local meshcat server on 127.0.0.1, stopped below
try:
    HexapodScene(hexa, vis).show(sol)
    html = write_html(vis, args.out / f"{variant.name}.html")
finally:
    stop_visualizer(vis)
print(f"wrote {html}")
try:
    find_chromium()
except RenderError as exc:
    print(f"no PNG: {exc}")
else:
    print("wrote", *render_pngs([html], [args.out / f"{variant.name}.png"]))
