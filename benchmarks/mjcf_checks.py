"""Figures of the MJCF export checks for every preset (or the ones named): agreement and timings.

    python benchmarks/mjcf_checks.py [PRESET ...] [--poses 1000] [--rest 3]

Per preset, over ``--poses`` random poses of the +-50 mm / +-25 deg box (Bem et al. (2026) §5.2):

* ``pin``: worst gap between Pinocchio's MJCF loader and the URDF path, IK leg readings (m),
  FK platform pose (4x4 entries, m and rotation-matrix entries) and configurations;
* ``mujoco``: worst equality violation (``efc_pos``, m and rad) that MuJoCo reports on the
  solved configurations;
* ``rest``: ``--rest`` poses of a +-30 mm / +-15 deg box simulated in MuJoCo without gravity, the
  actuators at the readings, until every joint velocity is below 1e-9: simulated time to rest,
  wall time, and the worst gap of the platform pose to ``forward`` (m, rad);
* load times of both files and the median cold FK time of each loaded model (same solver).

The tests assert the tolerances (tests/description/test_mjcf*.py); this script only reports.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

from hexapod_model import Hexapod, get_preset
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.mjcf import EQUALITY_SOLIMP, EQUALITY_SOLREF, geometry_to_mjcf
from hexapod_model.description.mjcf_loader import mujoco_qpos, q_of_mujoco_qpos
from hexapod_model.description.presets import PRESETS
from hexapod_model.description.urdf import geometry_to_urdf


def agreement(urdf: Hexapod, mjcf: Hexapod, m, poses: np.ndarray) -> dict:
    worst = dict.fromkeys(("ik_lengths", "ik_q", "fk_pose", "fk_q", "mujoco_violation"), 0.0)
    d = mujoco.MjData(m)
    solved, t_urdf, t_mjcf = 0, [], []
    for T in poses:
        a, b = urdf.inverse(T, check=False), mjcf.inverse(T, check=False)
        if not (a.converged and b.converged):
            continue
        solved += 1
        t0 = time.perf_counter()
        fa = urdf.forward(a.lengths, check=False)
        t1 = time.perf_counter()
        fb = mjcf.forward(a.lengths, check=False)
        t_urdf.append(t1 - t0)
        t_mjcf.append(time.perf_counter() - t1)
        if fa.status != fb.status:
            raise SystemExit(f"fk statuses differ between the URDF and the MJCF: {fa.status} / {fb.status}")
        for key, x, y in (("ik_lengths", a.lengths, b.lengths), ("ik_q", a.q, b.q)):
            worst[key] = max(worst[key], float(np.abs(x - y).max()))
        if fa.converged:  # (3-6: an ambiguous_assembly from both files alike)
            for key, x, y in (("fk_pose", fa.pose, fb.pose), ("fk_q", fa.q, fb.q)):
                worst[key] = max(worst[key], float(np.abs(x - y).max()))
        d.qpos[:] = mujoco_qpos(mjcf.closed_loop, b.q, m)
        mujoco.mj_forward(m, d)
        rows = d.efc_type[: d.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
        worst["mujoco_violation"] = max(worst["mujoco_violation"], float(np.abs(d.efc_pos[: d.nefc][rows]).max()))
    worst["solved"] = solved
    worst["fk_median_us_urdf"] = 1e6 * float(np.median(t_urdf))
    worst["fk_median_us_mjcf"] = 1e6 * float(np.median(t_mjcf))
    return worst


def rest(hexa: Hexapod, m, poses: np.ndarray) -> dict:
    m.opt.gravity[:] = 0.0
    out = {"sim_time_s": 0.0, "wall_time_s": 0.0, "position_gap_m": 0.0, "rotation_gap_rad": 0.0}
    for T in poses:
        lengths = hexa.inverse(T).lengths
        expected = hexa.forward(lengths).pose
        d = mujoco.MjData(m)
        d.ctrl[:] = lengths
        t0 = time.perf_counter()
        while d.time < 10.0:
            mujoco.mj_step(m, d, nstep=100)
            if np.abs(d.qvel).max() < 1e-9:
                break
        out["wall_time_s"] = max(out["wall_time_s"], time.perf_counter() - t0)
        out["sim_time_s"] = max(out["sim_time_s"], d.time)
        pose = hexa.pose_of(q_of_mujoco_qpos(hexa.closed_loop, d.qpos, m))
        out["position_gap_m"] = max(out["position_gap_m"], float(np.abs(pose[:3, 3] - expected[:3, 3]).max()))
        gap = float(np.linalg.norm(pin.log3(pose[:3, :3].T @ expected[:3, :3])))
        out["rotation_gap_rad"] = max(out["rotation_gap_rad"], gap)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=[n for n in PRESETS if not get_preset(n).redundant])  # six readings
    ap.add_argument("--poses", type=int, default=1000)
    ap.add_argument("--rest", type=int, default=3)
    args = ap.parse_args(argv)
    print(
        f"MuJoCo {mujoco.__version__}, Pinocchio {pin.__version__}; solref {EQUALITY_SOLREF}, solimp {EQUALITY_SOLIMP}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.presets:
            geom = get_preset(name)
            urdf_path, mjcf_path = Path(tmp) / f"{name}.urdf", Path(tmp) / f"{name}.xml"
            urdf_path.write_text(geometry_to_urdf(geom))
            mjcf_path.write_text(geometry_to_mjcf(geom, actuated=True))
            t0 = time.perf_counter()
            urdf = Hexapod.from_urdf(urdf_path, check_body=False)  # the kinematics alone, as the MJCF
            t1 = time.perf_counter()
            mjcf = Hexapod.from_mjcf(mjcf_path, check_body=False)
            t2 = time.perf_counter()
            m = mujoco.MjModel.from_xml_path(str(mjcf_path))
            a = agreement(urdf, mjcf, m, box_poses(urdf.home_pose, args.poses, seed=12))
            r = rest(urdf, m, box_poses(urdf.home_pose, args.rest, seed=31, translation=0.03, angle_deg=15.0))
            print(
                f"{name:13s} pin ({a['solved']} poses): IK readings {a['ik_lengths']:.1e} m, q {a['ik_q']:.1e}; "
                f"FK pose {a['fk_pose']:.1e}, q {a['fk_q']:.1e} | mujoco violation {a['mujoco_violation']:.1e}"
            )
            print(
                f"{'':13s} rest ({args.rest} poses): {r['sim_time_s']:.2f} s simulated, "
                f"{r['wall_time_s'] * 1e3:.0f} ms wall, gap {r['position_gap_m']:.1e} m / "
                f"{r['rotation_gap_rad']:.1e} rad | load URDF "
                f"{(t1 - t0) * 1e3:.0f} ms, MJCF {(t2 - t1) * 1e3:.0f} ms | cold FK median "
                f"{a['fk_median_us_urdf']:.0f} / {a['fk_median_us_mjcf']:.0f} us"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
