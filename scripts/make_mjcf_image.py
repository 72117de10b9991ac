"""Render the MuJoCo picture of docs/mjcf.md: the exported MJCF, driven by its actuators to a pose.

    MUJOCO_GL=egl python scripts/make_mjcf_image.py [--out docs/img/mjcf_reference.png]

The reference hexapod's MJCF (``hexapod mjcf reference --actuated``) is simulated in MuJoCo,
without gravity, from home with the actuators at the leg readings of a tilted pose until it is at
rest; the picture is MuJoCo's own offscreen rendering (headless: ``MUJOCO_GL=egl``, or ``osmesa``
with Debian's libosmesa6). The script prints how far the platform at rest is from ``forward``.
"""

from __future__ import annotations

import argparse
import os
import re
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
POSE = (0.03, -0.02, 0.41, 12.0, -8.0, 20.0)  # x, y, z (m), roll, pitch, yaw (deg), as in make_view_images.py
SCENE = """
  <visual><global offwidth="960" offheight="720"/><quality shadowsize="4096"/></visual>
  <asset>
    <texture type="skybox" builtin="gradient" rgb1="1 1 1" rgb2="0.80 0.84 0.90" width="256" height="256"/>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.92 0.93 0.95" rgb2="0.84 0.86 0.89"
             width="512" height="512"/>
    <material name="floor" texture="grid" texrepeat="8 8"/>
  </asset>
"""
LIGHTS = """
    <light pos="0.6 -0.8 1.6" dir="-0.4 0.5 -1" diffuse="0.7 0.7 0.7" castshadow="true"/>
    <light pos="-0.8 0.6 1.2" dir="0.5 -0.4 -1" diffuse="0.35 0.35 0.35" castshadow="false"/>
    <geom name="floor" type="plane" size="1.5 1.5 0.01" pos="0 0 -0.041" material="floor" contype="0" conaffinity="0"/>
"""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "mjcf_reference.png")
    args = ap.parse_args(argv)
    os.environ.setdefault("MUJOCO_GL", "egl")
    import mujoco
    from PIL import Image

    from hexapod_model import Hexapod, get_preset
    from hexapod_model.description.mjcf import geometry_to_mjcf
    from hexapod_model.description.mjcf_loader import q_of_mujoco_qpos
    from hexapod_model.lie import rpy_to_matrix

    hexa = Hexapod.from_preset("reference")
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(*np.radians(POSE[3:]))
    T[:3, 3] = POSE[:3]
    lengths = hexa.inverse(T).lengths
    text = geometry_to_mjcf(get_preset("reference"), actuated=True)
    text = re.sub(r'\s*<geom name="floor"[^>]*/>', "", text)  # the exported plain floor: this one has a material
    text = text.replace("<worldbody>", SCENE.strip() + "\n  <worldbody>" + LIGHTS.rstrip(), 1)
    m = mujoco.MjModel.from_xml_string(text)
    m.opt.gravity[:] = 0.0
    d = mujoco.MjData(m)
    d.ctrl[:] = lengths
    while d.time < 5.0 and not (d.time > 0 and np.abs(d.qvel).max() < 1e-9):
        mujoco.mj_step(m, d, nstep=100)
    pose = hexa.pose_of(q_of_mujoco_qpos(hexa.closed_loop, d.qpos, m))
    gap = np.abs(pose[:3, 3] - hexa.forward(lengths).pose[:3, 3]).max()
    print(f"at rest after {d.time:.2f} s of simulation: platform {gap:.1e} m from forward kinematics")
    camera = mujoco.MjvCamera()
    camera.lookat[:] = (0.0, 0.0, 0.21)
    camera.distance, camera.azimuth, camera.elevation = 1.0, 135.0, -20.0
    with mujoco.Renderer(m, 720, 960) as renderer:
        renderer.update_scene(d, camera)
        image = renderer.render()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(args.out, optimize=True)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
