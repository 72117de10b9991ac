"""The straightforward Pinocchio Newton that the solver is measured against.

Per iteration: ``computeJointJacobians``, then per leg the Pinocchio constraint model's
``calc`` and ``jacobian`` with a ``log6`` residual, and a dense numpy solve of the 36x36
system. Prints its warm-FK figures beside ``hexapod_model``'s on the same trajectory.

    python benchmarks/baseline_newton.py [PRESET]
"""

from __future__ import annotations

import sys
import time

import numpy as np
import pinocchio as pin

from hexapod_model import Hexapod
from hexapod_model.studies.bench import BENCH_TOL, trajectory_readings


def baseline_forward(
    hexa: Hexapod, lengths: np.ndarray, q0: np.ndarray, tol: float = BENCH_TOL, max_iter: int = 20
) -> tuple[np.ndarray, int]:
    """Direct kinematics by plain Newton with Pinocchio's constraint models."""
    clm = hexa.closed_loop
    m, d = clm.model, clm.data
    free = np.setdiff1d(np.arange(clm.nv), clm.prismatic_v)
    q = q0.copy()
    q[clm.prismatic_q] = lengths
    for it in range(max_iter + 1):
        pin.computeJointJacobians(m, d, q)
        res, jac = [], []
        for c, cd in zip(clm.constraints, clm.constraint_datas):
            c.calc(m, d, cd)
            res.append(pin.log6(cd.c1Mc2).vector if clm.kind == "6d" else cd.c1Mc2.translation)
            jac.append(c.jacobian(m, d, cd))
        r = np.concatenate(res)
        if np.linalg.norm(r) <= tol:
            return q, it
        dv = np.zeros(clm.nv)
        dv[free] = np.linalg.solve(np.vstack(jac)[:, free], -r)
        q = pin.integrate(m, q, dv)
    raise RuntimeError("baseline did not converge")


def main(argv=None) -> int:
    preset = (argv if argv is not None else sys.argv[1:] or ["reference"])[0]
    hexa = Hexapod.from_preset(preset)
    poses, readings = trajectory_readings(hexa)
    for name in ("baseline", "hexapod_model"):
        q, times = hexa.forward(readings[0]).q, []
        prev = hexa.forward(readings[0])
        for lengths in readings[1:]:
            t0 = time.perf_counter()
            if name == "baseline":
                q, _ = baseline_forward(hexa, lengths, q)
            else:
                prev = hexa.forward(lengths, guess=prev, tol=BENCH_TOL)
                q = prev.q
            times.append(time.perf_counter() - t0)
        t = np.array(times) * 1e6
        err = np.abs(hexa.pose_of(q) - poses[-1]).max()
        print(
            f"{name:14s} warm FK, trajectory A, {preset}: median {np.median(t):6.1f} us, p95 "
            f"{np.percentile(t, 95):6.1f} us, p99 {np.percentile(t, 99):6.1f} us; final pose error {err:.1e}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
