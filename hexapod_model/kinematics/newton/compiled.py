"""The fast path's solver object: a :class:`.solver.NewtonSolver` whose iterations run compiled.

:class:`CompiledSolver` keeps the general solver's interface and state (``iterate``,
``evaluate``, ``run``, ``sign``, ``kappa``, ``theta``, ``certified``) and runs them through the
compiled entries of :mod:`.newton` (:func:`.newton.solve_schur`, :func:`.newton.solve_blocks`)
on the packed tables and buffers of :mod:`.packing`; it adds the one-call solves of
:meth:`~.hexapod.Hexapod.forward` and :meth:`~.hexapod.Hexapod.inverse`
(:meth:`CompiledSolver.certified_forward`, :meth:`CompiledSolver.run_checked`). A warm ``forward``
checks its readings against the stroke and makes the attempt in one compiled call
(:meth:`CompiledSolver.attempt_readings`); a configuration array as its guess is checked by one
compiled call too (:func:`valid_start`).
:func:`solver_for` picks it when the model's layout allows.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...description.model import ClosedLoopModel
from .entries import direct, plain
from .first_compile import announce
from .iteration import solve_blocks, solve_schur
from .kernels import jacobian
from .legs import ChainTables
from .outcomes import CONVERGED, INVALID_INPUT, outcome
from .packing import SETTINGS, STROKE, Packed
from .solver import MAX_STEP, ONE_STEP, SINGULAR_PIVOT_RATIO, THETA_FLOOR, THETA_MAX, Attempt, NewtonSolver


@njit(cache=True)
def valid_start(q, platform_q, tol):
    """Whether ``q`` is a start :func:`.input_checks.check_configuration` takes: finite, unit platform quaternion.

    Every entry finite and ``| |q[platform_q + 3 : platform_q + 7]| - 1 | <= tol``, in one
    compiled call (NumPy's ``q @ q`` costs two dispatches; ``q.dot(q)`` would release the GIL). The
    caller checks dtype and shape first; a False start goes to ``check_configuration`` for its
    error.
    """
    for k in range(q.shape[0]):
        if not math.isfinite(q[k]):
            return False
    s = 0.0
    for k in range(platform_q + 3, platform_q + 7):
        s += q[k] * q[k]
    return abs(math.sqrt(s) - 1.0) <= tol


_BUFFERS = ("J", "R", "p", "E", "r", "x", "G", "dv", "LB", "PB", "A", "M", "pm", "nb", "wb")


class CompiledSolver(NewtonSolver):
    """A :class:`.solver.NewtonSolver` whose ``iterate`` and ``evaluate`` run compiled.

    Its buffers (``J``, ``r``, ``G``, ``x``, the Schur blocks, ...) are views on the packed
    arrays, so everything that reads them after a solve (``run``, :mod:`.certificate`,
    ``_solve_step``) sees the compiled path's values; ``q_aug[:nq]`` holds the last iterate.
    """

    #: :func:`valid_start`, for :meth:`.hexapod.Hexapod.forward` to check a configuration array as its guess
    check_start = staticmethod(valid_start)

    def __init__(
        self, clm: ClosedLoopModel, held_joints: tuple[int, ...], tables: ChainTables, limits: tuple | None = None
    ):
        self.packed: Packed | None = None  # NewtonSolver.__init__ iterates once, on the general path
        super().__init__(clm, held_joints)
        self.one_call = self
        constants = (MAX_STEP, SINGULAR_PIVOT_RATIO, THETA_MAX, THETA_FLOOR, ONE_STEP, self.length_scale)
        schur = self.held_pos is not None
        if not schur and self.block_cols is None:  # solver_for checks the layout first
            raise ValueError("no structured step for these held joints")
        if limits is None:  # the model's own, no slack
            limited = clm.limited_q()
            limits = (limited, clm.lower[limited], clm.upper[limited], 0.0)
        self._prismatic_q = clm.prismatic_q.astype(np.int64)
        held, colmap, free_v = self.held_pos, self.colmap[: clm.nv], self.free_v
        packed = Packed(
            tables, constants, self.step_weights, schur, held, colmap, free_v, clm.nv, self._prismatic_q, limits
        )
        for name in _BUFFERS:
            setattr(self, name, packed.views[name])
        self.state = packed.views["state"]
        self.last_q = self.q_aug[: clm.nq]  # the compiled path writes its iterate here, in place
        self._no_offset = np.zeros(self.r.size)
        #: ``(ints, floats, work, iwork)`` of the packed tables and buffers
        self.arrays = packed.arrays
        self.jac_args = (self.J, self.leg_cols, self.ff_cols, self.colmap, self.rows, self.p, self.E, self.G)
        if schur:
            s = self
            a = [s.J, s.leg_cols, s.held_pos, s.ff_cols, s.colmap, s.rows, s.p, s.E, s.r, s.x, s.LB, s.PB]
            self._schur_args = tuple(a + [s.A, s.M, s.pm, s.nb, s.wb, s.length_scale])
        self.packed = packed
        self._kernel = solve_schur if schur else solve_blocks
        announce(self._kernel)  # the first solve after installation compiles it
        # every call passes the same types (start and offset through plain()): after the first, the
        # machine code it ran is called directly (.entries.direct)
        self._entry, self._direct = self._kernel, False
        # the entries' settings (.packing.SETTINGS), filled in place: per kind of call, the constant ones set here
        self._settings = np.zeros(SETTINGS)
        #: the settings of the next certified attempt of direct kinematics (:meth:`certified_forward`)
        self.forward_settings = np.zeros(SETTINGS)
        self.forward_settings[3:7] = (0.0, 1.0, 1.0, 1.0)  # no homotopy, certify, finish, joints given
        self._checked_settings = np.zeros(SETTINGS)
        self._checked_settings[2:7] = (0.0, 0.0, 0.0, 1.0, 0.0)  # no sign, no homotopy, finish
        self._fixed = (*packed.arrays, self.last_q)  # then an entry's outputs q, pose, G
        self._nq, self._g_shape = self.last_q.shape[0], self.G.shape
        self._forward_joints = self.forward_settings[7:]  # the held joints' entries, a view
        # the settings of attempt_readings: the readings are the entry's offset (given 2), the stroke follows
        self._readings_settings = np.zeros(SETTINGS + STROKE)
        self._readings_settings[3:7] = (0.0, 1.0, 1.0, 2.0)
        self._readings_settings[25] = -np.inf  # no stroke held yet (hold_stroke): every reading is refused
        self._staged = (math.nan, math.nan, math.nan)  # tol, max_iter and sign in _readings_settings
        self._scratch = self._outputs()
        if schur:  # home's sign and condition bound, now from the compiled path
            self.iterate(clm.q_home, np.inf, 0)
            self.home_sign, self.home_kappa = self.sign, self.kappa

    def _call(self, start, offset, settings, arrays, tol):
        """Call the step's entry (:func:`solve_schur` / :func:`solve_blocks`); set the solver's state as ``iterate``.

        Returns ``(status, iterations, residual, message, first joint outside its limits or -1)``.
        """
        code, it, norm, ratio, self.theta, self.det_sign, self.certified, bad = self._run(
            start, offset, settings, arrays
        )
        self.sign, self.kappa = self.state.tolist()
        status, message = ("converged", "") if code == CONVERGED else outcome(code, tol, it, norm, ratio)
        return status, it, norm, message, bad

    def _run(self, start: np.ndarray, offset: np.ndarray, settings: np.ndarray, arrays: tuple) -> tuple:
        """The step's entry on these arguments (``start`` and ``offset`` through :func:`.entries.plain`): its tuple."""
        done = self._entry(start, offset, settings, arrays)
        if not self._direct:
            self._entry, self._direct = direct(self._kernel, (start, offset, settings, arrays)), True
        return done

    def iterate(self, q0, tol, max_iter, sign=0.0, offset=None, scale=0.0, certify=False):
        """:meth:`.solver.NewtonSolver.iterate`, compiled (same arguments, results and state)."""
        if self.packed is None:  # NewtonSolver.__init__'s solve at home: done on the compiled path below
            return "converged", 0, 0.0, ""
        offset = self._no_offset if offset is None else offset
        settings = self._settings
        settings[:7] = (tol, max_iter, sign, scale, certify, 0.0, 0.0)
        status, it, norm, message, _ = self._call(plain(q0), plain(offset), settings, self._scratch, tol)
        return status, it, norm, message

    def _outputs(self) -> tuple:
        """The entries' ``arrays`` with new output arrays ``q``, ``pose``, ``G`` (a Solution keeps them)."""
        return (*self._fixed, np.empty(self._nq), np.empty((4, 4)), np.empty(self._g_shape))

    def certified_forward(
        self, start: np.ndarray, joints: np.ndarray, tol: float, max_iter: int, sign: float
    ) -> Attempt:
        """The certified first attempt of direct kinematics in one compiled call (:func:`solve_schur`).

        Args:
            start: configuration to start from (not modified).
            joints: the six prismatic joint values to hold (m).
            tol: closure residual to reach (checked by the caller).
            max_iter: Newton step limit (checked by the caller).
            sign: determinant sign of the start's assembly (0 when unknown).

        Returns:
            When the attempt converged certified, ``(q, pose, jacobian, iterations, residual,
            first joint outside the packed limits or -1)``; otherwise what :meth:`iterate` returns,
            ``(status, iterations, residual, message)``, for :func:`.certificate.solve_forward` to
            go on from (its ``attempt``). The solver's state is :meth:`iterate`'s either way.
        """
        settings = self.forward_settings
        settings[0] = tol
        settings[1] = max_iter
        settings[2] = sign
        self._forward_joints[:] = joints  # any float dtype or stride: the entry's one signature
        done = self._attempt(start, self._no_offset, settings, tol)
        assert not isinstance(done, int)  # no stroke in these settings
        return done

    def hold_stroke(self, lower: np.ndarray, upper: np.ndarray, slack: float) -> None:
        """The stroke :meth:`attempt_readings` checks its readings against: ``[lower - slack, upper + slack]`` (m)."""
        settings = self._readings_settings
        settings[13:19], settings[19:25], settings[25] = lower, upper, slack

    def attempt_readings(
        self, start: np.ndarray, readings: np.ndarray, tol: float, max_iter: int, sign: float
    ) -> Attempt | int:
        """The stroke check of ``readings`` and :meth:`certified_forward` holding them, in one compiled call.

        For :meth:`.hexapod.Hexapod.forward`'s warm path on a hexapod without an encoder model
        (the readings are the prismatic joints' values). The stroke is :meth:`hold_stroke`'s.

        Args:
            start: configuration to start from (not modified).
            readings: the six readings (m), float64 of shape (6,).
            tol: closure residual to reach (checked by the caller).
            max_iter: Newton step limit (checked by the caller).
            sign: determinant sign of the start's assembly (0 when unknown).

        Returns:
            The index of the first reading outside the stroke or NaN (an int: no solve), or
            :meth:`certified_forward`'s result.
        """
        settings = self._readings_settings
        if (tol, max_iter, sign) != self._staged:  # a warm stream keeps them: no write into the array
            settings[0], settings[1], settings[2] = tol, max_iter, sign
            self._staged = (tol, max_iter, sign)
        # one compiled signature (.entries.plain): a strided, read-only or float32 array would compile another
        return self._attempt(start, plain(readings), settings, tol)

    def _attempt(self, start: np.ndarray, offset: np.ndarray, settings: np.ndarray, tol: float) -> Attempt | int:
        """The certified attempt with ``settings`` into new output arrays (an int: the reading outside the stroke)."""
        # the hot path of a warm solve: :meth:`_call`, :meth:`_run` and :meth:`_outputs` written out
        q, pose, G = np.empty(self._nq), np.empty((4, 4)), np.empty(self._g_shape)
        arrays = (*self._fixed, q, pose, G)
        start = plain(start)  # one compiled signature: a strided, read-only or float32 start would compile another
        code, it, norm, ratio, theta, det_sign, certified, bad = self._entry(start, offset, settings, arrays)
        if not self._direct:
            self._entry, self._direct = direct(self._kernel, (start, offset, settings, arrays)), True
        if code == INVALID_INPUT:  # refused before the solve (attempt_readings' stroke): the state is kept
            return bad
        self.theta, self.det_sign, self.certified = theta, det_sign, certified
        self.sign, self.kappa = self.state.tolist()
        if code == CONVERGED and certified:
            return q, pose, G, it, norm, bad
        status, message = outcome(code, tol, it, norm, ratio)
        return status, it, norm, message

    def run_checked(self, q0: np.ndarray, tol: float, max_iter: int) -> tuple[tuple, np.ndarray, int] | None:
        """:meth:`run` and the pose and limit check of its result in one compiled call (:func:`solve_blocks`).

        Returns ``(run's tuple, pose, first joint outside the packed limits or -1)`` on the block
        step (inverse kinematics), ``None`` on the Schur step (the caller uses :meth:`run`).
        """
        if self.held_pos is not None:
            return None
        settings = self._checked_settings
        settings[0], settings[1] = tol, max_iter
        arrays = self._outputs()
        status, it, norm, message, bad = self._call(plain(q0), self._no_offset, settings, arrays, tol)
        return (arrays[5], status, it, norm, arrays[7], message), arrays[6], bad

    def evaluate(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual (copy) and reduced Jacobian (copy) at URDF configuration ``q``, compiled."""
        settings = self._settings
        settings[:7] = (np.inf, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        # frames and residual at q; the solver's state untouched
        self._run(plain(q), self._no_offset, settings, self._scratch)
        jacobian(*self.jac_args)
        return self.r.copy(), self.G.copy()


def solver_for(clm: ClosedLoopModel, held_joints: tuple[int, ...], limits: tuple | None = None) -> NewtonSolver:
    """The compiled solver when the model and the held joints allow it, else the general one.

    ``limits = (limited q indices, lower, upper, slack)``: the joint-limit check of the compiled
    one-call solves (default: the model's limits, no slack).

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
        return CompiledSolver(clm, held_joints, tables, limits)
    return NewtonSolver(clm, held_joints)
