"""The whole Newton iteration of the fast path in one compiled call.

For hexapods whose six legs are chains of ``rows`` one-dof joints (6 for ``6d`` closures, 3
for ball joints) and the two structured problems: one joint held per leg, the platform free
(direct kinematics: the Schur elimination of :func:`.linalg.schur_solve`), or the platform held
(inverse kinematics: the blocks of :func:`.linalg.blocks_solve`). :func:`iterate` is
:meth:`.solver.NewtonSolver.iterate` with Pinocchio replaced by :mod:`.chains`; per iteration:

1. closure frames and WORLD Jacobian columns at ``q`` (:func:`.chains.evaluate_chains`);
2. residual, Bem et al. (2026) eqs. 10-14 (:func:`.kernels.closure_residual`), minus
   ``scale * offset`` on a homotopy path; stop when its norm is at most ``tol`` (a 180-degree
   flipped closure, ``trace(R_tip R_anchor^T) < 1``, is refused; a first step above
   ``one_step`` is followed by a second, to measure a contraction), after ``max_iter`` steps
   or on NaN; a start that closes at once is checked for singularity by one step;
3. Newton step ``G dq = -r`` by the structured solve; singular below ``singular_ratio``
   (smallest / largest pivot); the Schur step also gives the determinant sign and the
   condition bound (``state``);
4. with ``certify``: the step's determinant sign equals the start's, it is not shortened and
   the contraction ``|dx_k+1| / |dx_k|`` stays below ``theta_max`` (the certificate of
   :mod:`.assembly`); otherwise the solve stops, ``UNCERTIFIED``;
5. the step limited to ``max_step`` along its direction (:func:`.kernels.scatter_step`) and
   applied on the manifold: ``q_j += dq_j`` for the leg joints, ``M_p <- M_p exp6(v_p)`` for the
   platform (:func:`.lie.integrate_free_flyer`).

:class:`CompiledSolver` is a :class:`.solver.NewtonSolver` whose buffers are the packed ones
(:mod:`.packing`) and whose ``iterate`` / ``evaluate`` run compiled; :func:`solver_for` picks it
when the layout allows.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..description.model import ClosedLoopModel
from .chains import evaluate_chains
from .kernels import closure_residual, first_outside_at, jacobian, scatter_step, shift_residual, xyzquat_to_pose
from .legs import ChainTables
from .lie import integrate_free_flyer
from .linalg import blocks_solve, schur_solve
from .outcomes import CONVERGED, FLIPPED, NO_CONVERGENCE, SINGULAR, START_SINGULAR, UNCERTIFIED, outcome
from .packing import Packed, unpack_floats, unpack_ints, unpack_iwork, unpack_work
from .solver import _ONE_STEP, _THETA_FLOOR, MAX_STEP, SINGULAR_PIVOT_RATIO, THETA_MAX, NewtonSolver

# outcome codes of :func:`iterate` (:func:`outcome` turns them into statuses and messages)


@njit(cache=True, inline="always")
def _integrate(q, dv, leg_q, leg_v, platform_q, platform_v, Rs, ps, quat):
    """``q <- q (+) dv``: leg joints add their velocity, the platform's free flyer integrates on SE(3)."""
    for i in range(leg_q.shape[0]):
        for k in range(leg_q.shape[1]):
            q[leg_q[i, k]] += dv[leg_v[i, k]]
    v = dv[platform_v[0] : platform_v[0] + 6]
    integrate_free_flyer(q[platform_q : platform_q + 7], v, Rs[0], Rs[1], Rs[2], ps[0], quat)


@njit(cache=True, inline="always")
def _step(schur, rows, held_pos, colmap, leg_v, platform_v, frames, blocks, state):
    """Solve ``G x = r`` (Schur elimination or blocks); returns the smallest pivot ratio.

    ``frames = (J, p, E, r, x)``, ``blocks = (LB, PB, A, M, pm, nb, wb)``. The Schur step leaves
    the determinant sign (``-1`` when singular, as the general path) and the condition bound in
    ``state``.
    """
    J, p, E, r, x = frames
    LB, PB, A, M, pm, nb, wb = blocks
    if schur:
        ratio, kappa = schur_solve(J, leg_v, held_pos, platform_v, colmap, rows, p, E, r, x, LB, PB, A, M, pm, nb, wb)
        state[0], state[1] = (1.0 if ratio > 0.0 else -1.0), kappa
        return abs(ratio)
    return blocks_solve(J, leg_v, colmap, rows, p, E, r, x, LB, PB, wb)


@njit(cache=True, inline="always")
def _iterate(schur, q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork):
    """Newton from ``q0`` into ``q`` (see the module docstring), by the Schur or the block step.

    Returns ``(code, iterations, norm, ratio, theta, sign, certified)``: the outcome code, the
    last residual norm and pivot ratio, the largest contraction, the determinant sign the
    solve kept (``sign``, or the first step's when 0) and whether every check passed.
    """
    rows, platform_q = ints[0], ints[3]
    max_step, singular_ratio, theta_max, theta_floor, one_step = floats[0], floats[1], floats[2], floats[3], floats[4]
    (leg_q, leg_v, platform_v, held_pos, colmap, free_v, kinds), _ = unpack_ints(ints)
    (placements, motions, closure, home), _ = unpack_floats(ints, floats)
    (oR, op, J, R, p, E, r, x, dv, G, LB, A, M, nb, wb, Rs, ps, quat, state), _ = unpack_work(ints, work)
    (PB, pm), _ = unpack_iwork(ints, iwork)
    frames, blocks = (J, p, E, r, x), (LB, PB, A, M, pm, nb, wb)  # the step's inputs and buffers
    for k in range(q.shape[0]):
        q[k] = q0[k]
    it, ratio, theta, previous, certified = 0, 1.0, 0.0, 0.0, True
    while True:
        evaluate_chains(
            q, placements, kinds, motions, leg_q, leg_v, closure, home, platform_q, platform_v, oR, op, J, R, p
        )
        norm, min_trace = closure_residual(R, p, rows, E, r)
        if scale != 0.0:
            norm = shift_residual(r, offset, scale)
        if norm <= tol and (it != 1 or previous <= one_step):
            code = CONVERGED
            if min_trace < 1.0:
                code, certified = FLIPPED, False
            elif it == 0:  # no step factored the Jacobian: check the start itself is not singular
                ratio = _step(schur, rows, held_pos, colmap, leg_v, platform_v, frames, blocks, state)
                if ratio < singular_ratio:
                    code, certified = START_SINGULAR, False
            break
        if it >= max_iter or not norm < np.inf:  # also stops on NaN
            code = NO_CONVERGENCE
            break
        ratio = _step(schur, rows, held_pos, colmap, leg_v, platform_v, frames, blocks, state)
        if ratio < singular_ratio:
            code, certified = SINGULAR, False
            break
        biggest = scatter_step(x, free_v, dv, max_step)
        if certify:
            certified = sign == 0.0 or state[0] == sign  # the sign is only known on the Schur path
            sign = sign if sign != 0.0 else state[0]
            if previous > theta_floor and biggest > theta * previous:
                theta = biggest / previous
            previous = biggest
            if not (certified and biggest <= max_step and theta <= theta_max):
                code, certified = UNCERTIFIED, False
                break
        _integrate(q, dv, leg_q, leg_v, platform_q, platform_v, Rs, ps, quat)
        it += 1
    return code, it, norm, ratio, theta, sign, certified


# For the compiled loops of .follow and .batch_kernels, ``schur`` a constant in each.
@njit(cache=True)
def iterate_schur(q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork):
    """:func:`_iterate` with the Schur step (one joint held per leg, the platform free)."""
    return _iterate(True, q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork)


@njit(cache=True)
def iterate_blocks(q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork):
    """:func:`_iterate` with the block step (the platform held)."""
    return _iterate(False, q0, q, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork)


@njit(cache=True, inline="always")
def _solve(
    schur, start, joints, prismatic_q, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays
):  # noqa: E501
    """:func:`_iterate` from ``start`` (prismatic joints set to ``joints`` unless empty), and a ``Solution``'s arrays.

    ``arrays = (ints, floats, work, iwork, q_solver, q, pose, G)``. The iteration runs from
    ``q`` (``start``'s copy) and leaves its last iterate in ``q_solver``, as :func:`_iterate`
    does. With ``finish``, unless a ``certify``-ing solve did not converge certified, it also
    writes the configuration into ``q``, the platform pose ``home * X(q_p)`` into ``pose``, the
    reduced Jacobian (:func:`.kernels.jacobian`) into ``G`` and, when converged, finds the first
    joint outside ``limits = (limited q indices, lower, upper, slack)``. Returns
    :func:`_iterate`'s tuple and that joint (-1 if none or not looked for).
    """
    ints, floats, work, iwork, q_solver, q, pose, G = arrays
    for k in range(q.shape[0]):
        q[k] = start[k]
    if joints.shape[0] == prismatic_q.shape[0]:
        for i in range(prismatic_q.shape[0]):
            q[prismatic_q[i]] = joints[i]
    code, it, norm, ratio, theta, sign, certified = _iterate(
        schur, q, q_solver, tol, max_iter, sign, offset, scale, certify, ints, floats, work, iwork
    )
    bad = -1
    if finish and (not certify or (code == CONVERGED and certified)):
        (_, leg_v, platform_v, _, colmap, _, _), _ = unpack_ints(ints)
        views = unpack_work(ints, work)[0]
        q[:] = q_solver
        jacobian(views[2], leg_v, platform_v, colmap, ints[0], views[4], views[5], G)
        xyzquat_to_pose(q[ints[3] : ints[3] + 7], home, pose)
        if code == CONVERGED:
            bad = first_outside_at(q, limits[0], limits[1], limits[2], limits[3])
    return code, it, norm, ratio, theta, sign, certified, bad


# The entry points from Python: one per step, the iteration inlined in each (numba re-optimises
# a called compiled function in every caller's unit, so a second entry would compile it again).
@njit(cache=True)
def solve_schur(start, joints, prismatic_q, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays):
    """:func:`_solve` with the Schur step (direct kinematics: the certified first attempt, plain solves)."""
    return _solve(
        True, start, joints, prismatic_q, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays
    )


@njit(cache=True)
def solve_blocks(start, joints, prismatic_q, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays):
    """:func:`_solve` with the block step (inverse kinematics)."""
    return _solve(
        False, start, joints, prismatic_q, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays
    )


_BUFFERS = ("J", "R", "p", "E", "r", "x", "G", "dv", "LB", "PB", "A", "M", "pm", "nb", "wb")


class CompiledSolver(NewtonSolver):
    """A :class:`.solver.NewtonSolver` whose ``iterate`` and ``evaluate`` run compiled.

    Its buffers (``J``, ``r``, ``G``, ``x``, the Schur blocks, ...) are views on the packed
    arrays, so everything that reads them after a solve (``run``, :mod:`.assembly`,
    ``_solve_step``) sees the compiled path's values; ``q_aug[:nq]`` holds the last iterate.
    """

    compiled_loop = True

    def __init__(self, clm: ClosedLoopModel, held_joints: tuple[int, ...], tables: ChainTables):
        self.packed: Packed | None = None  # NewtonSolver.__init__ iterates once, on the general path
        super().__init__(clm, held_joints)
        constants = (MAX_STEP, SINGULAR_PIVOT_RATIO, THETA_MAX, _THETA_FLOOR, _ONE_STEP)
        schur = self.held_pos is not None
        if not schur and self.block_cols is None:  # solver_for checks the layout first
            raise ValueError("no structured step for these held joints")
        packed = Packed(tables, constants, schur, self.held_pos, self.colmap[: clm.nv], self.free_v, clm.nv)
        for name in _BUFFERS:
            setattr(self, name, packed.views[name])
        self._state = packed.views["state"]
        self._q = self.q_aug[: clm.nq]  # the compiled path writes its iterate here, in place
        self._no_offset = np.zeros(self.r.size)
        self._prismatic_q = clm.prismatic_q.astype(np.int64)
        #: ``(ints, floats, work, iwork)`` of the packed tables and buffers
        self.arrays = packed.arrays
        self._jac_args = (self.J, self.leg_cols, self.ff_cols, self.colmap, self.rows, self.p, self.E, self.G)
        if schur:
            s = self
            a = [s.J, s.leg_cols, s.held_pos, s.ff_cols, s.colmap, s.rows, s.p, s.E, s.r, s.x, s.LB, s.PB]
            self._schur_args = tuple(a + [s.A, s.M, s.pm, s.nb, s.wb])
        self.packed = packed
        self._kernel = solve_schur if schur else solve_blocks
        self._home = tables.home
        nq = clm.nq
        # the entries' other arguments when a plain iterate() does not use them
        self._no_joints, self._no_limits = np.zeros(0), (np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), 0.0)
        self._scratch = (*packed.arrays, self._q, np.empty(nq), np.empty((4, 4)), np.empty(self.G.shape))
        if schur:  # home's sign and condition bound, now from the compiled path
            self.iterate(clm.q_home, np.inf, 0)
            self.home_sign, self.home_kappa = self.sign, self.kappa

    def _call(self, start, joints, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays):
        """Call the step's entry (:func:`solve_schur` / :func:`solve_blocks`); set the solver's state as ``iterate``."""
        out = self._kernel(
            start, joints, self._prismatic_q, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays
        )
        code, it, norm, ratio, self.theta, self.det_sign, self.certified, bad = out
        self.sign, self.kappa = self._state.tolist()
        return code, it, norm, ratio, bad

    def iterate(self, q0, tol, max_iter, sign=0.0, offset=None, scale=0.0, certify=False):
        """:meth:`.solver.NewtonSolver.iterate`, compiled (same arguments, results and state)."""
        if self.packed is None:  # NewtonSolver.__init__'s solve at home: done on the compiled path below
            return "converged", 0, 0.0, ""
        offset = self._no_offset if offset is None else offset
        q0 = q0 if q0.dtype == np.float64 and q0.flags.c_contiguous else np.ascontiguousarray(q0, dtype=float)
        # one compiled signature: callers pass ints or floats (det_sign, scale, ...)
        code, it, norm, ratio, _ = self._call(
            q0, self._no_joints, float(tol), int(max_iter), float(sign), offset, float(scale), bool(certify),
            False, self._no_limits, self._home, self._scratch,
        )  # fmt: skip
        status, message = ("converged", "") if code == CONVERGED else outcome(code, tol, it, norm, ratio)
        return status, it, norm, message

    def _outputs(self, nq: int) -> tuple:
        """The entries' ``arrays`` with new output arrays ``q``, ``pose``, ``G`` (a Solution keeps them)."""
        return (*self.arrays, self._q, np.empty(nq), np.empty((4, 4)), np.empty(self.G.shape))

    def certified_forward(
        self, start: np.ndarray, joints: np.ndarray, tol: float, max_iter: int, sign: float, limits: tuple, home
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, float, int] | tuple[str, int, float, str]:
        """The certified first attempt of direct kinematics in one compiled call (:func:`solve_schur`).

        Args:
            start: configuration to start from (not modified).
            joints: the six prismatic joint values to hold (m).
            tol: closure residual to reach (checked by the caller).
            max_iter: Newton step limit (checked by the caller).
            sign: determinant sign of the start's assembly (0 when unknown).
            limits: ``(limited q indices, lower, upper, slack)`` of the joint-limit check.
            home: the platform's home placement (4x4).

        Returns:
            When the attempt converged certified, ``(q, pose, jacobian, iterations, residual,
            first joint outside its limits or -1)``; otherwise what :meth:`iterate` returns,
            ``(status, iterations, residual, message)``, for :func:`.assembly.solve_forward` to
            go on from (its ``attempt``). The solver's state is :meth:`iterate`'s either way.
        """
        arrays = self._outputs(start.shape[0])
        code, it, norm, ratio, bad = self._call(
            start, joints, tol, max_iter, float(sign), self._no_offset, 0.0, True, True, limits, home, arrays
        )
        if code == CONVERGED and self.certified:
            return arrays[5], arrays[6], arrays[7], it, norm, bad
        status, message = ("converged", "") if code == CONVERGED else outcome(code, tol, it, norm, ratio)
        return status, it, norm, message

    def run_checked(
        self, q0: np.ndarray, tol: float, max_iter: int, limits: tuple, home: np.ndarray
    ) -> tuple[tuple, np.ndarray, int] | None:
        """:meth:`run` and the pose and limit check of its result in one compiled call (:func:`solve_blocks`).

        Returns ``(run's tuple, pose, first joint outside its limits or -1)`` on the block step
        (inverse kinematics), ``None`` on the Schur step (the caller uses :meth:`run`).
        """
        if self.held_pos is not None:
            return None
        q0 = q0 if q0.dtype == np.float64 and q0.flags.c_contiguous else np.ascontiguousarray(q0, dtype=float)
        arrays = self._outputs(q0.shape[0])
        code, it, norm, ratio, bad = self._call(
            q0, self._no_joints, tol, max_iter, 0.0, self._no_offset, 0.0, False, True, limits, home, arrays
        )
        status, message = ("converged", "") if code == CONVERGED else outcome(code, tol, it, norm, ratio)
        return (arrays[5], status, it, norm, arrays[7], message), arrays[6], bad

    def evaluate(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual (copy) and reduced Jacobian (copy) at URDF configuration ``q``, compiled."""
        q = np.ascontiguousarray(q, dtype=float)
        self._kernel(
            q, self._no_joints, self._prismatic_q, np.inf, 0, 0.0, self._no_offset, 0.0, False, False,
            self._no_limits, self._home, self._scratch,
        )  # fmt: skip  # frames and residual at q; the solver's state untouched
        jacobian(*self._jac_args)
        return self.r.copy(), self.G.copy()


def solver_for(clm: ClosedLoopModel, held_joints: tuple[int, ...]) -> NewtonSolver:
    """The compiled solver when the model and the held joints allow it, else the general one.

    Compiled: every leg a chain of ``rows`` one-dof joints (``rows`` = 6 for ``6d`` closures, 3
    for ``3d``), no other joint but the platform's, and either exactly one joint held per leg
    with the platform free (the Schur path), or the platform alone held (the blocks).
    """
    rows = 6 if clm.kind == "6d" else 3
    tables = ChainTables.of(clm)
    if tables is None or tables.placements.shape[1] != rows or clm.nv != 6 + 6 * rows:
        return NewtonSolver(clm, held_joints)
    held = set(held_joints)
    per_leg = [sum(j in held for j in leg.joints) for leg in clm.legs]
    if held == {clm.platform_joint} or (clm.platform_joint not in held and per_leg == [1] * 6 and len(held) == 6):
        return CompiledSolver(clm, held_joints, tables)
    return NewtonSolver(clm, held_joints)
