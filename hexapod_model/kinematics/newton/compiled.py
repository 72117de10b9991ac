"""The fast path's solver object: a :class:`.solver.NewtonSolver` whose iterations run compiled.

:class:`CompiledSolver` keeps the general solver's interface and state (``iterate``,
``evaluate``, ``run``, ``sign``, ``kappa``, ``theta``, ``certified``) and runs them through the
compiled entries of :mod:`.newton` (:func:`.newton.solve_schur`, :func:`.newton.solve_blocks`)
on the packed tables and buffers of :mod:`.packing`; it adds the one-call solves of
:meth:`~.hexapod.Hexapod.forward` and :meth:`~.hexapod.Hexapod.inverse`
(:meth:`CompiledSolver.certified_forward`, :meth:`CompiledSolver.run_checked`).
:func:`solver_for` picks it when the model's layout allows.
"""

from __future__ import annotations

import numpy as np

from ...description.model import ClosedLoopModel
from .first_compile import announce
from .iteration import solve_blocks, solve_schur
from .kernels import jacobian
from .legs import ChainTables
from .outcomes import CONVERGED, outcome
from .packing import Packed
from .solver import _ONE_STEP, _THETA_FLOOR, MAX_STEP, SINGULAR_PIVOT_RATIO, THETA_MAX, NewtonSolver

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
        announce(self._kernel)  # the first solve after installation compiles it
        self._home = tables.home
        nq = clm.nq
        # the entries' other arguments when a plain iterate() does not use them
        self._no_joints, self._no_limits = np.zeros(0), (np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), 0.0)
        self._scratch = (*packed.arrays, self._q, np.empty(nq), np.empty((4, 4)), np.empty(self.G.shape))
        if schur:  # home's sign and condition bound, now from the compiled path
            self.iterate(clm.q_home, np.inf, 0)
            self.home_sign, self.home_kappa = self.sign, self.kappa

    def _call(self, start, joints, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays):
        """Call the step's entry (:func:`solve_schur` / :func:`solve_blocks`); set the solver's state as ``iterate``.

        Returns ``(status, iterations, residual, message, first joint outside its limits or -1)``.
        """
        out = self._kernel(
            start, joints, self._prismatic_q, tol, max_iter, sign, offset, scale, certify, finish, limits, home, arrays
        )
        code, it, norm, ratio, self.theta, self.det_sign, self.certified, bad = out
        self.sign, self.kappa = self._state.tolist()
        status, message = ("converged", "") if code == CONVERGED else outcome(code, tol, it, norm, ratio)
        return status, it, norm, message, bad

    def iterate(self, q0, tol, max_iter, sign=0.0, offset=None, scale=0.0, certify=False):
        """:meth:`.solver.NewtonSolver.iterate`, compiled (same arguments, results and state)."""
        if self.packed is None:  # NewtonSolver.__init__'s solve at home: done on the compiled path below
            return "converged", 0, 0.0, ""
        offset = self._no_offset if offset is None else offset
        q0 = _contiguous(q0)
        # one compiled signature: callers pass ints or floats (det_sign, scale, ...)
        status, it, norm, message, _ = self._call(
            q0, self._no_joints, float(tol), int(max_iter), float(sign), offset, float(scale), bool(certify),
            False, self._no_limits, self._home, self._scratch,
        )  # fmt: skip
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
        # one compiled signature: contiguous float64 (a strided or float32 array would compile another)
        start, joints = _contiguous(start), _contiguous(joints)
        arrays = self._outputs(start.shape[0])
        status, it, norm, message, bad = self._call(
            start, joints, tol, max_iter, float(sign), self._no_offset, 0.0, True, True, limits, home, arrays
        )
        if status == "converged" and self.certified:
            return arrays[5], arrays[6], arrays[7], it, norm, bad
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
        q0 = _contiguous(q0)
        arrays = self._outputs(q0.shape[0])
        status, it, norm, message, bad = self._call(
            q0, self._no_joints, tol, max_iter, 0.0, self._no_offset, 0.0, False, True, limits, home, arrays
        )
        return (arrays[5], status, it, norm, arrays[7], message), arrays[6], bad

    def evaluate(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual (copy) and reduced Jacobian (copy) at URDF configuration ``q``, compiled."""
        q = _contiguous(q)
        self._kernel(
            q, self._no_joints, self._prismatic_q, np.inf, 0, 0.0, self._no_offset, 0.0, False, False,
            self._no_limits, self._home, self._scratch,
        )  # fmt: skip  # frames and residual at q; the solver's state untouched
        jacobian(*self._jac_args)
        return self.r.copy(), self.G.copy()


def _contiguous(a: np.ndarray) -> np.ndarray:
    """``a`` as a C-contiguous float64 array (itself when it is one already)."""
    return a if a.dtype == np.float64 and a.flags.c_contiguous else np.ascontiguousarray(a, dtype=np.float64)


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
