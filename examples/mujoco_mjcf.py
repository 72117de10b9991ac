"""Export a hexapod as MJCF, load it into MuJoCo and let its actuators drive the platform to a pose.

    python examples/mujoco_mjcf.py [HEXAPOD] [-o hexapod.xml] [--pose X Y Z ROLL PITCH YAW]

The MJCF holds the six loop closures as equality constraints and, with ``actuated=True``, a
position actuator per leg reading. The readings of the target pose come from our inverse
kinematics; MuJoCo simulates the hexapod without gravity from home until it is at rest, and
the platform pose it reaches is compared with our direct kinematics of the same readings.
``python -m mujoco.viewer --mjcf=hexapod.xml`` shows the file interactively (docs/mjcf.md).
"""

import argparse
from pathlib import Path

import mujoco
import numpy as np

import hexapod_model as hm
from hexapod_model.description.mjcf_loader import q_of_mujoco_qpos
from hexapod_model.lie import rpy_to_matrix

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("hexapod", nargs="?", default="reference", help="preset name, URDF or geometry file")
ap.add_argument("-o", "--output", default="hexapod.xml")
ap.add_argument(
    "--pose",
    nargs=6,
    type=float,
    default=(0.02, -0.01, 0.41, 8.0, -5.0, 10.0),
    metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"),
    help="m and degrees",
)
args = ap.parse_args()

hexa = hm.Hexapod.load(args.hexapod, compiled=False)
Path(args.output).write_text(hm.urdf_to_mjcf(hexa.closed_loop.urdf_xml, actuated=True))

target = np.eye(4)
target[:3, :3] = rpy_to_matrix(*np.radians(args.pose[3:]))
target[:3, 3] = args.pose[:3]
lengths = hexa.inverse(target).lengths  # leg readings (m) that put the platform at the target

model = mujoco.MjModel.from_xml_path(args.output)
model.opt.gravity[:] = 0.0
data = mujoco.MjData(model)
data.ctrl[:] = lengths  # the actuators drive each leg reading to its value
while data.time < 5.0 and not (data.time > 0 and np.abs(data.qvel).max() < 1e-9):
    mujoco.mj_step(model, data, nstep=100)

reached = hexa.pose_of(q_of_mujoco_qpos(hexa.closed_loop, data.qpos, model))
solved = hexa.forward(lengths).pose
print(f"wrote {args.output}; MuJoCo at rest after {data.time:.2f} s of simulation")
print(
    f"platform: {1e3 * np.abs(reached[:3, 3] - target[:3, 3]).max():.2e} mm from the target, "
    f"{1e3 * np.abs(reached[:3, 3] - solved[:3, 3]).max():.2e} mm from forward kinematics"
)
closures = data.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY
print(f"largest closure violation at rest: {np.abs(data.efc_pos[closures]).max():.1e} (m, rad)")
