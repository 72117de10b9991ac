"""Per-sample sensitivity of the pose to the readings, compiled (the tracker's figures).

The tracker's uncertainty and singularity figures come without an SVD of the 36-column
constraint Jacobian.
From the closure Jacobian ``G`` of all joints at a solved configuration (one
``pin.computeJointJacobians`` call), each leg's joints are eliminated exactly as in the
solver's Schur step (:func:`hexapod_model.kinematics.newton.structured.schur_solve`): with ``L_i`` the
square block of leg ``i``'s joints and ``L_i^T n_i = e_reading``, ``n_i`` annihilates the
passive columns and ``n_i . c_i = 1``, so row ``i`` of the eliminated Jacobian is
``-n_i^T A_i`` (``A_i`` the platform columns). ``dl = J xi`` with ``xi`` the platform
velocity in the platform (LOCAL) frame, m/s and rad/s (:mod:`hexapod_model.analysis.jacobian`
derives the same matrix by SVD; a test checks that both agree).

From ``J`` (6x6), one LU gives ``J^-1``; with independent reading noise of standard deviation
``sigma`` (m) the pose covariance is ``sigma^2 J^-1 J^-T``, whose translation and rotation
traces give the 1-sigma figures (rotation-invariant, so the same in the base frame). The
condition number is that of ``J`` with its rotation columns divided by a length ``L`` (m per
rad), from the eigenvalues of the 6x6 ``Js^T Js`` by cyclic Jacobi rotations.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..kinematics.hexapod import Hexapod
from ..kinematics.newton.entries import direct
from ..kinematics.newton.first_compile import announce
from ..kinematics.newton.linalg import (
    lu_apply,
    lu_apply_transposed,
    lu_factor,
    lu_factor_in_place,
    lu_solve_transposed_in_place,
)
from ..kinematics.newton.proven import built
from ..kinematics.newton.solver import NewtonSolver
from ..kinematics.newton.structured import closure_weights, leg_block, platform_block

_JACOBI_SWEEPS = 30


@njit(cache=True)
def _eliminate(G, leg_cols, reading_pos, ff_cols, rows, LB, PB, w, n, J):
    """Fill ``J`` (6x6, ``dl = J xi``, LOCAL frame) from the full closure Jacobian ``G``.

    ``leg_cols[i, :rows]`` are leg ``i``'s velocity columns, ``reading_pos[i]`` the position of
    its measured joint among them. Returns the smallest pivot ratio of the leg blocks (0 when
    a leg is itself singular: then ``J`` is not filled).
    """
    worst = 1.0
    for i in range(6):
        o = i * rows
        for a in range(rows):
            for b in range(rows):
                LB[a, b] = G[o + a, leg_cols[i, b]]
        ratio = lu_factor(LB, LB, PB)
        if ratio == 0.0:
            return 0.0
        worst = min(worst, ratio)
        w[:] = 0.0
        w[reading_pos[i]] = 1.0
        lu_apply_transposed(LB, PB, w, n)
        for k in range(6):
            s = 0.0
            for a in range(rows):
                s += n[a] * G[o + a, ff_cols[k]]
            J[i, k] = -s
    return worst


@njit(cache=True)
def _sym_eigvals(S, out):
    """Eigenvalues of the symmetric ``S`` (destroyed) by cyclic Jacobi rotations, into ``out``."""
    n = S.shape[0]
    for _ in range(_JACOBI_SWEEPS):
        off, diag = 0.0, 0.0
        for p in range(n):
            diag += S[p, p] * S[p, p]
            for q in range(p + 1, n):
                off += S[p, q] * S[p, q]
        if off <= 1e-32 * diag:
            break
        for p in range(n):
            for q in range(p + 1, n):
                if S[p, q] == 0.0:
                    continue
                theta = (S[q, q] - S[p, p]) / (2.0 * S[p, q])
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):
                    a, b = S[k, p], S[k, q]
                    S[k, p], S[k, q] = c * a - s * b, s * a + c * b
                for k in range(n):
                    a, b = S[p, k], S[q, k]
                    S[p, k], S[q, k] = c * a - s * b, s * a + c * b
    for p in range(n):
        out[p] = S[p, p]


@njit(cache=True)
def _invert_and_measure(J, length, LU, piv, e, col, Jinv, S, eig):
    """``Jinv = J^-1`` and ``(trace_t, trace_r, cond, det)``.

    The translation (m^2) and rotation (rad^2) traces of ``J^-1 J^-T`` per unit reading variance, the 2-norm condition
    number of ``J`` with rotation columns divided by ``length``, and ``det J``.
    ``(inf, inf, inf, 0)`` when singular.
    """
    ratio = lu_factor(J, LU, piv)
    if ratio < 1e-14:
        return np.inf, np.inf, np.inf, 0.0
    det = 1.0
    for k in range(6):
        det *= LU[k, k] if piv[k] == k else -LU[k, k]
    for k in range(6):
        e[:] = 0.0
        e[k] = 1.0
        lu_apply(LU, piv, e, col)
        for a in range(6):
            Jinv[a, k] = col[a]
    tt, tr = 0.0, 0.0
    for a in range(6):
        for b in range(6):
            v = Jinv[a, b] * Jinv[a, b]
            if a < 3:
                tt += v
            else:
                tr += v
    for a in range(6):  # S = Js^T Js, Js = J diag(1, 1, 1, 1/L, 1/L, 1/L)
        fa = 1.0 if a < 3 else 1.0 / length
        for b in range(6):
            fb = 1.0 if b < 3 else 1.0 / length
            s = 0.0
            for i in range(6):
                s += J[i, a] * J[i, b]
            S[a, b] = s * fa * fb
    _sym_eigvals(S, eig)
    lo, hi = np.inf, 0.0
    for a in range(6):
        lo = min(lo, eig[a])
        hi = max(hi, eig[a])
    cond = np.sqrt(hi / lo) if lo > 0.0 else np.inf
    return tt, tr, cond, det


@njit(cache=True)
def measure(G, index, rows, length, mats, vecs, piv, J, Jinv):
    """One compiled call: :func:`_eliminate` then :func:`_invert_and_measure`.

    ``index`` rows: leg columns (6 x rows), then reading positions and platform columns
    (``index[6, :6]``, ``index[7, :6]``); ``mats`` (3, 6, 6), ``vecs`` (5, 6) and ``piv``
    (2, 6) are work buffers. Returns ``(trace_t, trace_r, cond, det)``.
    """
    LB = mats[0, :rows, :rows]
    if _eliminate(G, index[:6], index[6], index[7], rows, LB, piv[0, :rows], vecs[0, :rows], vecs[1, :rows], J) == 0.0:
        return np.inf, np.inf, np.inf, 0.0
    return _invert_and_measure(J, length, mats[1], piv[1], vecs[2], vecs[3], Jinv, mats[2], vecs[4])


@njit(cache=True)
def measure_solved(J, leg_cols, held_pos, ff_cols, rows, p, E, length, blocks, mats, vecs, piv, Jout, Jinv):
    """:func:`measure` from the joint Jacobians a Schur-path solve left at its last iterate.

    ``J, leg_cols, held_pos, ff_cols, rows, p, E`` are the direct-kinematics solver's (its
    held joint per leg is the measured one): the leg blocks ``L_i`` and platform columns
    ``A_i`` are built by the functions that
    :func:`~hexapod_model.kinematics.newton.structured.schur_solve` builds them with, so no
    ``computeJointJacobians``, no full closure Jacobian and no allocation. ``blocks``
    (7, rows, 6) is a work buffer. Returns ``(trace_t, trace_r, cond, det)``.
    """
    LB, A, PB, n = blocks[6, :rows, :rows], blocks[:6, :rows, :], piv[0, :rows], vecs[0, :rows]
    for i in range(6):
        ht, ha = closure_weights(E, i, rows)
        leg_block(J, leg_cols[i], rows, p[i], ht, LB)  # L_i: the leg's joints
        platform_block(J, ff_cols, rows, p[6 + i], ha, A[i])  # A_i: the platform's velocity
        if lu_factor_in_place(LB, PB, rows) == 0.0:
            return np.inf, np.inf, np.inf, 0.0
        for a in range(rows):
            n[a] = 1.0 if a == held_pos[i] else 0.0
        lu_solve_transposed_in_place(LB, PB, n, rows)
        for k in range(6):
            s = 0.0
            for a in range(rows):
                s += n[a] * A[i, a, k]
            Jout[i, k] = -s
    return _invert_and_measure(Jout, length, mats[1], piv[1], vecs[2], vecs[3], Jinv, mats[2], vecs[4])


@njit(cache=True)
def _holds(q_aug, q):
    """Whether ``q_aug[:q.size] == q`` element by element (as ``(q_aug[:n] == q).all()``)."""
    if q_aug.shape[0] < q.shape[0]:
        return False
    for i in range(q.shape[0]):
        if not q_aug[i] == q[i]:
            return False
    return True


@dataclass(frozen=True)
class Sensitivity:
    """Pose sensitivity at one configuration, per unit (1 m) reading standard deviation.

    Attributes:
        translation: sqrt of the trace of the position covariance (m per m of reading noise).
        rotation: sqrt of the trace of the orientation covariance (rad per m of reading noise).
        condition_number: 2-norm condition number of ``J`` with rotations scaled by ``length``.
        det_sign: sign of ``det J`` (+1, -1; 0 when singular): it changes only across a
            singularity, so a change between two samples means a singularity lies between.
    """

    translation: float
    rotation: float
    condition_number: float
    det_sign: int


class SensitivityEvaluator:
    """Eliminated 6x6 Jacobian, its inverse and the figures above at configurations of ``hexa``.

    Owns its solver buffers (one evaluator per tracker: not shared between threads). The
    compiled elimination needs legs of as many one-dof joints as closure rows (every preset:
    ``supported``); other URDFs that the contract allows take the slower SVD route of
    :func:`~hexapod_model.analysis.jacobian.leg_jacobian_local`.

    Args:
        hexa: the hexapod.
        length: m per rad for the condition number.
    """

    def __init__(self, hexa: Hexapod, length: float):
        clm = hexa.closed_loop
        self.hexa = hexa
        self.length = float(length)
        self.rows = 6 if clm.kind == "6d" else 3
        m = clm.model
        legs = [[int(m.joints[j].idx_v) for j in leg.joints] for leg in clm.legs]
        self.supported = all(len(c) == self.rows for c in legs) and all(
            m.joints[j].nv == 1 for leg in clm.legs for j in leg.joints
        )
        self._solver = NewtonSolver(clm, ())
        width = max(self.rows, 6)
        self.index = np.zeros((8, width), dtype=np.int64)
        if self.supported:
            for i, leg in enumerate(clm.legs):
                self.index[i, : self.rows] = legs[i]
                self.index[6, i] = legs[i].index(int(m.joints[leg.prismatic].idx_v))
        self.index[7, :6] = np.arange(clm.platform_v, clm.platform_v + 6)
        self._mats, self._vecs = np.zeros((3, 6, 6)), np.zeros((5, 6))
        self._piv = np.zeros((2, 6), dtype=np.int64)
        self.J = np.zeros((6, 6))
        self.Jinv = np.zeros((6, 6))
        self._blocks: np.ndarray | None = None  # evaluate_solved's leg blocks, made on first use
        self._solved_by: NewtonSolver | None = None  # the solver whose buffers _solved_args holds
        self._solved_args: tuple | None = None
        # measure_solved on _solved_args (the solver's buffers and this evaluator's: their types never change),
        # the dispatcher until its first call with them, then the machine code that call ran (.entries.direct)
        self._measure: Callable[..., tuple] = measure_solved
        self._measure_direct = False
        self._announced = False  # evaluate's kernels: their first compilation is announced (first_compile)

    def evaluate_solved(self, q: np.ndarray) -> Sensitivity:
        """:meth:`evaluate` at ``q``, the configuration the calling thread's last direct-kinematics solve ended on.

        The tracker's per-sample call: the solve left the joint Jacobians at ``q`` in its
        solver's buffers, so the elimination starts from them (a third of :meth:`evaluate`'s
        cost). Falls back to :meth:`evaluate` when the solver holds another configuration or
        has no Schur step.
        """
        hexa = self.hexa
        s = hexa.engine.solver(hexa.engine.held_forward)  # the calling thread's (one per thread)
        if s is not self._solved_by:  # the kernel's arguments from this solver (its buffers stay)
            self._solved_by, self._solved_args = s, self._arguments(s)
        args = self._solved_args
        if args is None or not _holds(s.q_aug, q):
            return self.evaluate(q)
        if not self._measure_direct:  # its first call: announced if it compiles, then its machine code directly
            announce(measure_solved)
            tt, tr, cond, det = measure_solved(*args)
            self._measure, self._measure_direct = direct(measure_solved, args), True
        else:
            tt, tr, cond, det = self._measure(*args)
        if cond == math.inf:
            self.Jinv[:] = np.nan
        # Sensitivity(...), the same object, without the frozen __init__'s __setattr__ per field (one a tracker step)
        sign = (det > 0.0) - (det < 0.0)
        return built(
            Sensitivity,
            {"translation": math.sqrt(tt), "rotation": math.sqrt(tr), "condition_number": cond, "det_sign": sign},
        )

    def _arguments(self, s: NewtonSolver) -> tuple | None:
        """:func:`measure_solved`'s arguments for solver ``s`` (``None``: no Schur step of these legs)."""
        if s.held_pos is None or not self.supported or s.rows != self.rows:
            return None
        if self._blocks is None:
            self._blocks = np.zeros((7, self.rows, 6))
        return (
            s.J, s.leg_cols, s.held_pos, s.ff_cols, self.rows, s.p, s.E, self.length,
            self._blocks, self._mats, self._vecs, self._piv, self.J, self.Jinv,
        )  # fmt: skip

    def evaluate(self, q: np.ndarray) -> Sensitivity:
        """Fill :attr:`J` and :attr:`Jinv` at ``q``; return the figures (``inf`` when singular)."""
        if not self._announced:  # the first call after installation compiles the Jacobian's and measure's kernels
            announce(measure)
            self._announced = True
        _, G = self._solver.evaluate(q)
        if self.supported:
            tt, tr, cond, det = measure(
                G, self.index, self.rows, self.length, self._mats, self._vecs, self._piv, self.J, self.Jinv
            )
        else:  # general URDF: the SVD route of the jacobian module
            from .jacobian import leg_jacobian_local

            self.J[:] = leg_jacobian_local(self.hexa, q)[0]
            tt, tr, cond, det = np.inf, np.inf, np.inf, 0.0
            if np.all(np.isfinite(self.J)):
                tt, tr, cond, det = _invert_and_measure(
                    self.J,
                    self.length,
                    self._mats[1],
                    self._piv[1],
                    self._vecs[2],
                    self._vecs[3],
                    self.Jinv,
                    self._mats[2],
                    self._vecs[4],
                )
        if cond == math.inf:
            self.Jinv[:] = np.nan
        return Sensitivity(math.sqrt(tt), math.sqrt(tr), cond, (det > 0.0) - (det < 0.0))
