"""Bem et al.'s full closure formulation (eq.

6) next to the reduced one (eq. 14), for the convergence and conditioning study (Bem et al. (2026) §4.7, §5.3-5.4).

Full formulation, per leg (closure tip frame ``T_tip``, platform anchor frame ``T_anchor``,
both in the base/world frame): the 9 entries of ``R_tip - R_anchor`` (row-major) and the 3 of
``p_tip - p_anchor`` -> 12 rows, 72 for six 6-D closures. (For 3-D ball-joint closures only
the 3 translation rows exist, so both formulations coincide.) Its Jacobian with respect to the
free joint velocities ``v`` (the tangent space of ``pin.integrate``) follows from
``dR = [w] R`` with ``w`` the frame's world angular velocity, and ``dp`` the frame origin's
velocity, both read from Pinocchio's ``LOCAL_WORLD_ALIGNED`` frame Jacobians.

Reduced formulation: the package's :class:`~hexapod_model.kinematics.newton.solver.NewtonSolver` residual
(3 translation + 3 ``vex(skew(R_tip R_anchor^T))`` rows per leg, 36 in all).

Both are iterated here with the same pseudo-inverse Newton step (Bem et al. (2026) eq. 17),
``dx = -J^+ f`` with the condition number of ``J`` (eq. 25), both from the normal equations
(:func:`pinv_step`; an SVD when ``J`` is near rank-deficient), and the same stop rule (eq. 18:
``||dx|| < step_tol``, or the residual already below ``tol``). Each
iteration's ``||dx||`` (mixed metres / radians, eq. 28), condition number and wall time are
recorded in a :class:`Trace`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numba import njit
from scipy.linalg.lapack import dsterf, dsytrd

from ..description.model import ClosedLoopModel
from ..kinematics.newton.solver import NewtonSolver


@dataclass(frozen=True)
class Trace:
    """One Newton solve, iteration by iteration.

    Attributes:
        q: final URDF configuration.
        converged: residual norm <= ``tol`` at the end.
        times: (k,) wall time (s) from the start to the end of each step.
        step_norms: (k,) ``||dx||`` of each step (eq. 28; metres and radians mixed).
        conditions: (k,) 2-norm condition number of the Jacobian used by each step.
        residuals: (k+1,) residual norm before each step and at the end.
    """

    q: np.ndarray
    converged: bool
    times: np.ndarray
    step_norms: np.ndarray
    conditions: np.ndarray
    residuals: np.ndarray

    @property
    def iterations(self) -> int:
        """Newton steps taken."""
        return int(self.step_norms.size)


def free_velocities(clm: ClosedLoopModel, held_joints: tuple[int, ...]) -> np.ndarray:
    """Velocity indices of the joints not held (same order as the reduced solver's columns)."""
    held = np.zeros(clm.nv, dtype=bool)
    for j in held_joints:
        jm = clm.model.joints[j]
        held[jm.idx_v : jm.idx_v + jm.nv] = True
    return np.flatnonzero(~held)


@njit(cache=True)
def _assemble(Jf, masks, R, p, rot, r, G):
    """Residual and Jacobian of the full formulation.

    Fill ``r`` and ``G`` (tip minus anchor, per leg: 9 rotation rows if ``rot``, then 3
    translation rows) from WORLD Jacobian columns ``Jf`` (6, n), the (2, 6, n) support masks
    and the (2, 6, 3, 3) / (2, 6, 3) frame placements (tips first, then anchors).
    """
    rows = 12 if rot else 3
    r[:] = 0.0
    G[:, :] = 0.0
    for s in range(2):
        sign = 1.0 if s == 0 else -1.0
        for i in range(6):
            o = i * rows
            if rot:
                for a in range(3):
                    for k in range(3):
                        r[o + 3 * a + k] += sign * R[s, i, a, k]
                o += 9
            for a in range(3):
                r[o + a] += sign * p[s, i, a]
            for c in range(Jf.shape[1]):
                if masks[s, i, c] == 0.0:
                    continue
                wx, wy, wz = Jf[3, c], Jf[4, c], Jf[5, c]
                px, py, pz = p[s, i, 0], p[s, i, 1], p[s, i, 2]
                G[o + 0, c] += sign * (Jf[0, c] + wy * pz - wz * py)
                G[o + 1, c] += sign * (Jf[1, c] + wz * px - wx * pz)
                G[o + 2, c] += sign * (Jf[2, c] + wx * py - wy * px)
                if rot:
                    for k in range(3):
                        rx, ry, rz = R[s, i, 0, k], R[s, i, 1, k], R[s, i, 2, k]
                        G[o - 9 + k, c] += sign * (wy * rz - wz * ry)
                        G[o - 6 + k, c] += sign * (wz * rx - wx * rz)
                        G[o - 3 + k, c] += sign * (wx * ry - wy * rx)


class FullFormulation:
    """Residual and Jacobian of Bem et al. (2026) eq. 6 on a :class:`ClosedLoopModel`.

    Args:
        clm: the loaded hexapod.
        held_joints: Pinocchio joint ids kept fixed (the prismatic joints for direct
            kinematics, the platform's floating joint for inverse kinematics).
    """

    def __init__(self, clm: ClosedLoopModel, held_joints: tuple[int, ...]):
        self.clm = clm
        self.model = clm.model
        self.data = clm.model.createData()
        self.free_v = free_velocities(clm, held_joints)
        self.rows = 12 if clm.kind == "6d" else 3
        self.r = np.zeros(6 * self.rows)
        self.G = np.zeros((6 * self.rows, self.free_v.size))
        self.Rf = np.zeros((2, 6, 3, 3))
        self.pf = np.zeros((2, 6, 3))
        m = clm.model
        # which free velocities move each closure frame (the joints supporting its parent)
        self.masks = np.zeros((2, 6, self.free_v.size))
        self.frames = [[getattr(leg, w) for leg in clm.legs] for w in ("tip_frame", "anchor_frame")]
        for s in range(2):
            for i, f in enumerate(self.frames[s]):
                for j in list(m.supports[m.frames[f].parentJoint])[1:]:
                    cols = np.arange(m.joints[j].idx_v, m.joints[j].idx_v + m.joints[j].nv)
                    self.masks[s, i, np.isin(self.free_v, cols)] = 1.0

    def evaluate(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual (72,) and Jacobian (72, n_free) at URDF configuration ``q``.

        ``data.J`` (WORLD convention) column ``c`` is ``[v_o; w]``: a frame at ``p`` moved by
        it has origin velocity ``v_o + w x p`` and ``dR = [w] R`` (column ``k``: ``w x R[:, k]``).
        """
        m, d = self.model, self.data
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        oMf = d.oMf
        H = np.array([oMf[f].homogeneous for f in self.frames[0] + self.frames[1]])  # (12, 4, 4), one copy each
        self.Rf[:] = H[:, :3, :3].reshape(2, 6, 3, 3)
        self.pf[:] = H[:, :3, 3].reshape(2, 6, 3)
        _assemble(
            np.ascontiguousarray(d.J[:, self.free_v]), self.masks, self.Rf, self.pf, self.rows == 12, self.r, self.G
        )
        return self.r.copy(), self.G.copy()


def _extreme_eigenvalues(A: np.ndarray) -> tuple[float, float]:
    """Smallest and largest eigenvalue of the symmetric ``A``.

    LAPACK's ``dsytrd`` (tridiagonal form) and ``dsterf`` (its eigenvalues), the two routines
    ``np.linalg.eigvalsh`` runs, called directly: 15-20 us less per call on a 36 x 36 matrix
    (NumPy's checks and dispatch). Equal to ``eigvalsh`` to ``eps * cond(A)`` (both are backward
    stable; the libraries differ in rounding only).
    """
    _, d, e, _, info = dsytrd(A, lower=1)
    w, info2 = dsterf(d, e)
    if info or info2:
        w = np.linalg.eigvalsh(A)
    return float(w[0]), float(w[-1])


def pinv_step(J: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, float]:
    """The step ``dx = -J^+ f`` (eq. 17) and the 2-norm condition number of ``J`` (eq. 25).

    For a Jacobian of full column rank and condition below 1e4, from the normal equations:
    ``J^T J dx = -J^T f``, the condition number from the extreme eigenvalues of ``J^T J`` (the
    squared singular values), several times cheaper than the SVD of a 72 x 36 Jacobian and
    equal to it to ``eps * cond^2`` (1e-12 here). Otherwise from the SVD, singular values below
    ``1e-14 s_max`` dropped.
    """
    A = J.T @ J
    lo, hi = _extreme_eigenvalues(A)
    if lo > 1e-8 * hi:
        return -np.linalg.solve(A, J.T @ f), math.sqrt(hi / lo)
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    keep = s > s[0] * 1e-14
    return -(Vt[keep].T @ ((U[:, keep].T @ f) / s[keep])), float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def _norm(x: np.ndarray) -> float:
    """``np.linalg.norm`` of a real vector (the same ``sqrt(x @ x)``) without its dispatch."""
    return math.sqrt(x @ x)


def pinv_newton(
    evaluate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    model: pin.Model,
    free_v: np.ndarray,
    q0: np.ndarray,
    *,
    tol: float = 1e-13,
    step_tol: float = 1e-12,
    max_iter: int = 30,
    accept: float = 1e-9,
) -> Trace:
    """Pseudo-inverse Newton iteration (Bem et al. (2026) eqs. 17-18) on the constraint manifold.

    ``evaluate(q) -> (f, J)``; the step ``dx = -J^+ f`` (:func:`pinv_step`) is scattered into the free velocities
    and applied with ``pin.integrate``. Stops when ``||dx|| < step_tol``, when ``||f|| <= tol``
    or after ``max_iter`` steps; ``converged`` means a final residual norm <= ``accept``.
    """
    q = np.array(q0, dtype=float)
    dv = np.zeros(model.nv)
    times: list[float] = []
    norms: list[float] = []
    conds: list[float] = []
    res: list[float] = []
    start = time.perf_counter()
    for _ in range(max_iter + 1):
        f, J = evaluate(q)
        res.append(_norm(f))
        if res[-1] <= tol or len(norms) == max_iter or not math.isfinite(res[-1]):
            break
        dx, cond = pinv_step(J, f)
        dv[free_v] = dx
        q = pin.integrate(model, q, dv)
        times.append(time.perf_counter() - start)
        norms.append(_norm(dx))
        conds.append(cond)
        if norms[-1] < step_tol:
            res.append(_norm(evaluate(q)[0]))
            break
    return Trace(q, bool(res[-1] <= accept), np.array(times), np.array(norms), np.array(conds), np.array(res))


class ForwardComparison:
    """Direct kinematics of one hexapod by both formulations, for the study.

    ``hexa`` is a :class:`~hexapod_model.hexapod.Hexapod`; the prismatic joints are held.
    """

    def __init__(self, hexa):
        self.clm = hexa.closed_loop
        held = tuple(leg.prismatic for leg in self.clm.legs)
        self.full = FullFormulation(self.clm, held)
        self.reduced = NewtonSolver(self.clm, held)

    def traces(self, lengths: np.ndarray, q0: np.ndarray | None = None, **kwargs) -> tuple[Trace, Trace]:
        """Newton traces of the full and the reduced formulation.

        Solve ``lengths`` (m) with the full (72-row) and the reduced (36-row) formulation
        from the same start (default: home); returns ``(full, reduced)``. Keywords go to
        :func:`pinv_newton`.
        """
        clm = self.clm
        q = clm.q_home.copy() if q0 is None else np.array(q0, dtype=float)
        q[clm.prismatic_q] = lengths
        return (
            pinv_newton(self.full.evaluate, clm.model, self.full.free_v, q, **kwargs),
            pinv_newton(self.reduced.evaluate, clm.model, self.reduced.free_v, q, **kwargs),
        )
