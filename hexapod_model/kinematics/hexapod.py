"""The user-facing :class:`Hexapod`: direct, inverse and hybrid kinematics in a few calls.

>>> import hexapod_model as hm
>>> hexa = hm.Hexapod.from_preset("reference")
>>> sol = hexa.forward([0.01, 0.0, -0.01, 0.0, 0.01, 0.0])   # leg readings, metres
>>> back = hexa.inverse(sol.pose)                           # back.lengths ~ the readings
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..description.geometry import GEOMETRY_SUFFIXES, HexapodGeometry, load_geometry
from ..description.mjcf_loader import MJCF_SUFFIXES, load_mjcf
from ..description.model import ClosedLoopModel
from ..description.presets import PRESETS, get_preset
from ..description.urdf import geometry_to_urdf
from ..exceptions import AssemblyError, ConvergenceError, InputError, LimitError, SingularityError, WorkspaceError
from . import assembly, batch, hybrid
from .assemblies import DEFAULT_STARTS, Assemblies, AssemblyFinder, review
from .assembly import NEAR_SINGULAR_FACTOR, Outcome
from .batch import BatchResult
from .checks import (
    LIMIT_SLACK,
    MAX_TOL,
    POSE_TOLERANCE,
    check_guess,
    check_home_conditioning,
    check_max_iter,
    check_pose,
    check_tolerance,
    check_vector,
    failure_status,
)
from .newton.kernel_sets import KernelSet, kernel_set
from .newton.outcomes import new_solution
from .newton.proof import StepProver, with_proof
from .newton.solver import NewtonSolver, Solution, size_of

DEFAULT_TOL = 1e-12  # closure residual (m, rad) at a 0.25 m base radius: pose errors below 1e-9 on every preset
DEFAULT_MAX_ITER = 20
#: largest 2-norm condition number of the direct-kinematics constraint Jacobian at home
#: (metres and radians; the presets have 9-67, a 20x smaller hexapod about 700, a singular
#: layout with parallel, coplanar or coincident legs 1e13 and more)
HOME_CONDITION_LIMIT = 1e6
_ERRORS = {
    "singular": SingularityError,
    "out_of_limits": WorkspaceError,
    "ambiguous_assembly": AssemblyError,
    "uncertified": AssemblyError,
    "no_assembly": WorkspaceError,
}

__all__ = ["Hexapod", "POSE_TOLERANCE", "check_pose", "check_vector", "load_hexapod"]


class Hexapod:
    """A hexapod loaded from a URDF that follows the contract of ``docs/urdf_contract.md``.

    Construct with :meth:`from_urdf`, :meth:`from_preset`, :meth:`from_geometry` or :meth:`from_mjcf`.
    Leg readings (``lengths``) are the measured prismatic joints in metres, zero at home;
    poses are 4x4 base -> platform transforms in metres. One object may be shared by threads:
    each thread solves with solver buffers of its own.

    ``compiled=False`` (every constructor takes it) solves with the NumPy kernels instead of the
    numba-compiled ones (:mod:`~hexapod_model.kinematics.newton.kernel_sets`): the same answers, several
    times slower per solve, but no numba import (~1 s, 130 MB) nor first compilation (~20 s).
    """

    def __init__(self, model: ClosedLoopModel, geometry: HexapodGeometry | None = None, *, compiled: bool = True):
        self.closed_loop = model
        #: whether the solves run the numba-compiled kernels
        self.compiled = bool(compiled)
        self.geometry = geometry
        m = model.model
        #: the Pinocchio model of the URDF tree (``RobotWrapper.model``)
        self.model: pin.Model = m
        #: its Pinocchio data (``RobotWrapper.data``); the solver uses buffers of its own
        self.data: pin.Data = model.data
        #: one Pinocchio constraint model per loop closure, leg order
        self.constraint_models = list(model.constraints)
        self.nq, self.nv = m.nq, m.nv
        self.joint_names: tuple[str, ...] = tuple(m.names[1:])
        #: each leg's encoder model (reading = zero + gain * prismatic value), None when the identity
        self._encoder = (
            None
            if not (np.any(model.encoder_zero) or np.any(model.encoder_scale))
            else (model.encoder_zero.copy(), 1.0 + model.encoder_scale)
        )
        #: (6, 2) reading limits (m): the prismatic joint limits, through the encoder model if any
        self.stroke = self.readings_of(np.array([[model.lower[i], model.upper[i]] for i in model.prismatic_q]).T).T
        self.prismatic_names = tuple(m.names[leg.prismatic] for leg in model.legs)
        self._limited = model.limited_q()
        self._local = threading.local()  # .solvers: {held joints: NewtonSolver}, one per thread
        self._home_h = model.home.homogeneous
        self._q_shape = (self.nq,)
        self._prismatic_q = model.prismatic_q
        self._stroke_lo = np.ascontiguousarray(self.stroke[:, 0])
        self._stroke_hi = np.ascontiguousarray(self.stroke[:, 1])
        self._limited_lo = model.lower[self._limited].copy()
        self._limited_hi = model.upper[self._limited].copy()
        #: the joint-limit check's arguments (limited q indices, lower, upper, slack)
        self._limits = (self._limited, self._limited_lo, self._limited_hi, LIMIT_SLACK)
        self._held_forward = tuple(leg.prismatic for leg in model.legs)
        self._held_inverse = (model.platform_joint,)
        self._free_directions: dict[tuple[int, ...], tuple[int, int]] = {}  # held set -> (free, rank)
        #: 2-norm condition number of the direct-kinematics constraint Jacobian at home (scale-free)
        self.home_condition_number = self._check_home_conditioning()
        #: largest horizontal distance of a leg's first joint from the base origin (m), and
        #: the size ratio, to the nearest power of two (1 for the presets), the constants scale by
        self.base_radius, self.scale = size_of(model)
        #: the closure residual a solve stops at by default (m, rad): ``DEFAULT_TOL * scale``
        self.default_tol = min(DEFAULT_TOL * self.scale, MAX_TOL)

    @functools.cached_property
    def _kernels(self) -> KernelSet:
        """The kernels of :attr:`compiled`: numba is imported at the first solve, not on loading."""
        return kernel_set(self.compiled)

    # ----- construction -----
    @classmethod
    def from_urdf(cls, path: str | Path, *, compiled: bool = True) -> Hexapod:
        """Load a URDF file, or a preset when ``path`` is a preset name (see ``PRESETS``)."""
        if str(path) in PRESETS:
            return cls.from_preset(str(path), compiled=compiled)
        return cls(ClosedLoopModel.from_file(path), compiled=compiled)

    @classmethod
    def load(cls, spec: str | Path, *, compiled: bool = True) -> Hexapod:
        """A preset name, or a URDF, geometry (``.toml``, ``.yaml``, ``.yml``, ``.json``) or MJCF (``.xml``) file.

        This is what every ``hexapod`` sub-command does with its HEXAPOD argument.
        """
        if str(spec).lower().endswith(GEOMETRY_SUFFIXES):
            return cls.from_geometry(load_geometry(spec), compiled=compiled)
        if str(spec).lower().endswith(MJCF_SUFFIXES):
            return cls.from_mjcf(spec, compiled=compiled)
        return cls.from_urdf(spec, compiled=compiled)

    @classmethod
    def from_mjcf(cls, path: str | Path, *, compiled: bool = True) -> Hexapod:
        """Load an MJCF file (``hexapod mjcf``, docs/mjcf.md) through Pinocchio's MJCF parser and constraint models."""
        return cls(load_mjcf(path), compiled=compiled)

    @classmethod
    def from_preset(cls, name: str = "reference", *, compiled: bool = True) -> Hexapod:
        """One of the bundled geometries: ``reference``, ``intersecting``, ``spherical``, ``3-6``, ``guideway``."""
        return cls.from_geometry(get_preset(name), compiled=compiled)

    @classmethod
    def from_geometry(cls, geometry: HexapodGeometry, *, compiled: bool = True) -> Hexapod:
        """Generate the URDF of ``geometry`` in memory and load it."""
        clm = ClosedLoopModel(geometry_to_urdf(geometry), f"<geometry {geometry.name}>")
        return cls(clm, geometry, compiled=compiled)

    # ----- conversions -----
    @property
    def home_pose(self) -> np.ndarray:
        """Platform pose at home (4x4, base frame, metres)."""
        return self.closed_loop.home.homogeneous

    @property
    def q_home(self) -> np.ndarray:
        """The zero configuration (assembled at home)."""
        return self.closed_loop.q_home.copy()

    @property
    def q0(self) -> np.ndarray:
        """The home configuration, under the name ``RobotWrapper`` users know."""
        return self.q_home

    def pose_of(self, q: np.ndarray) -> np.ndarray:
        """Platform pose (4x4, base frame, metres) of configuration ``q``."""
        i = self.closed_loop.platform_q
        T = np.empty((4, 4))
        self._kernels.xyzquat_to_pose(q[i : i + 7], self._home_h, T)
        return T

    def lengths_of(self, q: np.ndarray) -> np.ndarray:
        """Leg readings (m) of configuration ``q``, leg order."""
        joints = q[self.closed_loop.prismatic_q]  # a new array already
        return joints if self._encoder is None and joints.dtype == np.float64 else self.readings_of(joints)

    def readings_of(self, joints: np.ndarray) -> np.ndarray:
        """Leg readings (m) of prismatic joint values (m, leg order, last axis).

        The URDF's ``<encoder>`` model; the identity without one.
        """
        if self._encoder is None:
            return np.array(joints, dtype=float)
        return self._encoder[0] + self._encoder[1] * np.asarray(joints, dtype=float)

    def joints_of(self, readings: np.ndarray) -> np.ndarray:
        """Prismatic joint values (m) of leg readings (m, leg order): the inverse of :meth:`readings_of`."""
        if self._encoder is None:
            return np.array(readings, dtype=float)
        return (np.asarray(readings, dtype=float) - self._encoder[0]) / self._encoder[1]

    def _set_pose(self, q: np.ndarray, pose) -> None:
        T = check_pose(pose, self._kernels.rigid_error)
        i = self.closed_loop.platform_q
        self._kernels.pose_to_xyzquat(T, self._home_h, q[i : i + 7])

    def _solver(self, held: tuple[int, ...]) -> NewtonSolver:
        """The calling thread's solver for this set of held joints (buffers are not shared)."""
        solvers = getattr(self._local, "solvers", None)
        if solvers is None:
            solvers = self._local.solvers = {}
        solver = solvers.get(held)
        if solver is None and self.compiled:
            from .newton.compiled import solver_for  # numba: imported by the first compiled solve

            solver = solvers[held] = solver_for(self.closed_loop, held, self._limits)
        elif solver is None:
            solver = solvers[held] = NewtonSolver(self.closed_loop, held, self._kernels)
        return solver

    def _check_home_conditioning(self) -> float:
        """Condition number of the direct-kinematics Jacobian at home; GeometryError above the limit.

        Scale-free: rotation rows times the length scale, metre columns divided by it (the
        solver's weights), so a hexapod scaled by a power of two has its preset's figure.

        Evaluated with the NumPy kernels: loading a hexapod compiles nothing (the first solve
        compiles what it runs).
        """
        solver = NewtonSolver(self.closed_loop, self._held_forward, kernel_set(False))
        _, G = solver.evaluate(self.closed_loop.q_home)
        G = solver.residual_weights[:, None] * G / solver.step_weights  # scale-free rows and columns
        return check_home_conditioning(G, self.closed_loop.source, HOME_CONDITION_LIMIT)

    def _start(self, guess, copy: bool = True) -> np.ndarray:
        """The configuration to start from: home, a :class:`Solution`'s ``q`` or a checked guess.

        With ``copy=False`` home's or the Solution's own array, for a caller that does not write it.
        """
        if guess is None:
            q = self.closed_loop.q_home
        elif isinstance(guess, Solution) and isinstance(guess.q, np.ndarray) and guess.q.shape == (self.nq,):
            q = guess.q
        else:
            return check_guess(guess, self.nq, self.closed_loop.platform_q)  # a new array
        return q.copy() if copy else q

    # ----- solves -----
    def forward(
        self,
        lengths: ArrayLike,
        guess=None,
        *,
        tol: float | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
        check: bool = True,
    ) -> Solution:
        """Direct kinematics: platform pose from the six leg readings (m).

        Args:
            lengths: six readings, leg order, metres (zero at home).
            guess: previous :class:`Solution` or configuration to start from (default: home).
            tol: closure residual to reach, in (0, 1e-6] (metres and radians); default
                :attr:`default_tol` (``DEFAULT_TOL`` = 1e-12 scaled with the base radius to the
                nearest power of two: the presets' 1e-12, 3.1e-14 for a 1 cm base radius).
            max_iter: Newton step limit (an int >= 0).
            check: raise on a result that is not ``converged`` (default). With
                ``check=False`` the :class:`Solution` is returned and its ``status`` says why.

        Raises:
            InputError: wrong count or shape, NaN or inf, complex or text values, a bad
                ``guess``, ``tol`` or ``max_iter``.
            LimitError: a reading outside its stroke.
            ConvergenceError, SingularityError, WorkspaceError: when ``check`` and the solve failed.
        """
        tol = self.default_tol if tol is None else tol
        if not (isinstance(lengths, np.ndarray) and lengths.shape == (6,) and lengths.dtype == np.float64):
            lengths = check_vector("lengths", lengths, 6)
        fast = type(tol) is float and 0.0 < tol <= MAX_TOL and type(max_iter) is int and max_iter >= 0
        solver = getattr(self._local, "staged", None)  # the one-call path's solver, once this thread has it
        fits = (
            guess is None or type(guess) is Solution and type(guess.q) is np.ndarray and guess.q.shape == self._q_shape
        )
        if solver is not None and fast and fits:
            # the hot path of a warm solve: the stroke check and the attempt's settings in one compiled call
            start, sign = (self.closed_loop.q_home, solver.home_sign) if guess is None else (guess.q, guess.det_sign)
            settings = solver.forward_settings
            k = solver.stage(
                lengths, self._stroke_lo, self._stroke_hi, LIMIT_SLACK, settings, tol, float(max_iter), float(sign)
            )
            if k >= 0:
                raise self._stroke_error(lengths, k)
            done = solver.attempt(start, tol)
            if len(done) == 6 and done[5] < 0 and solver.kappa <= NEAR_SINGULAR_FACTOR * solver.home_kappa:
                # converged certified within the limits, not near a singularity: _attempted()'s Solution, built here
                q, pose, jac, it, res, _ = done
                readings = q[self._prismatic_q]  # lengths_of(q) without an encoder model
                return new_solution(pose, q, readings, "converged", it, res, jac, "", (), (), int(solver.sign))
            return self._attempted(solver, done, lengths, lengths, start, tol, max_iter, sign, guess, check, False)
        k = self._kernels.first_outside(lengths, self._stroke_lo, self._stroke_hi, LIMIT_SLACK)
        if k >= 0:
            raise self._stroke_error(lengths, k)
        solver = self._solver(self._held_forward)
        sign = solver.home_sign if guess is None else getattr(guess, "det_sign", 0)
        joints = lengths if self._encoder is None else self.joints_of(lengths)
        start = self._start(guess, copy=False)  # solve_forward writes its own copy
        review = self._finder.exact is not None  # a 3-6 hexapod: every assembly is accounted for
        if fast and solver.compiled_loop:
            if self._encoder is None and not review:  # the next solves on this thread take the hot path
                self._local.staged = solver
            # the certified first attempt in one compiled call; solve_forward goes on from it
            done = solver.certified_forward(start, joints, tol, max_iter, sign)  # type: ignore[attr-defined]
            return self._attempted(solver, done, lengths, joints, start, tol, max_iter, sign, guess, check, review)
        sol = self._finish(solver, start.copy(), tol, max_iter, check and not review, (joints, sign, guess is not None))
        sol = self._proven_near(sol, guess, start, check and not review)
        return self._reviewed(sol, lengths, guess, check) if review else sol

    def _stroke_error(self, lengths: np.ndarray, k: int) -> LimitError:
        """The error for reading ``k`` outside its stroke (an :class:`InputError` first for NaN / inf)."""
        check_vector("lengths", lengths, 6)  # names NaN / inf first
        return LimitError(self.prismatic_names[k], lengths[k], self.stroke[k, 0], self.stroke[k, 1], what="stroke")

    def _attempted(
        self, solver, done: tuple, lengths, joints, start, tol, max_iter, sign, guess, check: bool, review: bool
    ) -> Solution:
        """The :class:`Solution` of :meth:`forward` after the compiled certified attempt ``done``.

        Its result when it converged certified (:meth:`.compiled.CompiledSolver.certified_forward`),
        else :func:`.assembly.solve_forward` goes on from it.
        """
        if len(done) == 6:
            q, pose, jac, it, res, bad = done
            sol = self._solution(assembly.certified_outcome(solver, q, jac, it, res), check and not review, pose, bad)
        else:
            forward = (joints, sign, guess is not None, done)
            sol = self._finish(solver, start.copy(), tol, max_iter, check and not review, forward)
        sol = self._proven_near(sol, guess, start, check and not review)
        return self._reviewed(sol, lengths, guess, check) if review else sol

    @functools.cached_property
    def _finder(self) -> AssemblyFinder:
        """The global direct kinematics (:mod:`.assemblies`)."""
        return AssemblyFinder(self)

    @functools.cached_property
    def _prover(self) -> StepProver | None:
        """The Krawczyk proof of warm steps (:mod:`.newton.proof`)."""
        return StepProver.of(self.closed_loop)

    def prove_step(self, guess, sol: Solution) -> Solution:
        """``sol``, a :meth:`forward` result from ``guess``, with the Krawczyk proof of its readings path.

        The proof (:class:`~.newton.proof.Proof`, rigorous in floating point) that the path of
        solutions for the readings from ``guess``'s to ``sol``'s stays on one assembly and ends
        within :attr:`~.newton.proof.Proof.position_m` / ``rotation_rad`` of ``sol.pose``. A
        ``converged`` result whose proof fails is returned ``uncertified``.

        Args:
            guess: the closed configuration or :class:`Solution` the solve started from.
            sol: the result.
        """
        return with_proof(self._prover, self._start(guess), sol)

    def _proven_near(self, sol: Solution, guess, start: np.ndarray, check: bool) -> Solution:
        """A warm ``converged`` result near a singularity stays so only with its proof (:meth:`prove_step`)."""
        if guess is None or sol.status != "converged" or "near_singular" not in sol.flags:
            return sol
        sol = with_proof(self._prover, start, sol)
        if check and not sol.converged:
            raise AssemblyError(sol, f"{sol.status}: {sol.message}")
        return sol

    def _reviewed(self, sol: Solution, lengths: np.ndarray, guess, check: bool) -> Solution:
        """A 3-6 hexapod's result checked against every assembly (:func:`.assemblies.review`); raised if ``check``."""
        sol = review(self._finder, sol, lengths, guess)
        if check and sol.status != "converged":
            raise _ERRORS.get(sol.status, ConvergenceError)(sol, f"{sol.status}: {sol.message}")
        return sol

    def assemblies(
        self, lengths: ArrayLike, *, reference: np.ndarray | None = None, starts: int = DEFAULT_STARTS, seed: int = 0
    ) -> Assemblies:
        """Every assembly for these readings that can be found: the global answer of direct kinematics.

        For a 3-6 hexapod (e.g. preset ``3-6``) all of them, from the resultant polynomial
        (``complete`` is True); for the others, what plain Newton reaches from home and ``starts``
        random poses (``complete`` is False: assemblies it does not reach may exist).
        See :mod:`~hexapod_model.kinematics.assemblies`.

        Args:
            lengths: six readings, leg order, metres (zero at home).
            reference: order the assemblies by distance to this pose (4x4, default home).
            starts: random starts of the multi-start search (ignored for a 3-6 hexapod).
            seed: random seed of those starts.

        Returns:
            :class:`~.assemblies.Assemblies`: the assemblies within the stroke and joint limits
            (converged inverse-kinematics :class:`Solution` each), the count of those outside.

        Raises:
            InputError, LimitError: as :meth:`forward` for the readings.
        """
        lengths = check_vector("lengths", lengths, 6)
        k = self._kernels.first_outside(lengths, self._stroke_lo, self._stroke_hi, LIMIT_SLACK)
        if k >= 0:
            raise LimitError(self.prismatic_names[k], lengths[k], self.stroke[k, 0], self.stroke[k, 1], what="stroke")
        ref = None if reference is None else check_pose(reference, self._kernels.rigid_error)
        if type(starts) is not int or starts < 0:
            raise InputError("starts", starts, "an int >= 0")
        return self._finder.find(lengths, ref, starts, seed)

    def inverse(
        self,
        pose: np.ndarray,
        guess=None,
        *,
        tol: float | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
        check: bool = True,
    ) -> Solution:
        """Inverse kinematics: leg readings (and all passive joints) for a platform pose.

        A pose that needs a reading outside the stroke or a Cardan angle outside its limit is
        outside the workspace: ``WorkspaceError`` (or status ``out_of_limits``).
        """
        q = self._start(guess)
        self._set_pose(q, pose)
        tol = self.default_tol if tol is None else tol
        return self._finish(self._solver(self._held_inverse), q, tol, max_iter, check)

    def solve(
        self,
        held: Mapping[str, object],
        guess=None,
        *,
        tol: float | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
        check: bool = True,
    ) -> Solution:
        """Hybrid kinematics: hold the named joints at the given values, solve for the rest.

        ``held`` maps URDF joint names to values: a float (m or rad) for a one-dof joint, a
        4x4 pose for ``platform_joint`` (the floating joint). Example: hold three legs and
        the platform height is not possible (whole joints only), but holding five prismatic
        joints and one Cardan angle is. A prismatic joint takes its joint value (extension
        from home), not the reading of an ``<encoder>`` model.

        Raises:
            InputError: an unknown joint, a bad value, or a held set that leaves the other
                joints free to move (under-determined: the message gives the count of free
                directions). Over-determined sets are solved in the least-squares sense and
                converge when the held values are consistent.
        """
        q = self._start(guess)
        held_ids = hybrid.hold(self, held, q)
        tol = self.default_tol if tol is None else tol
        return self._finish(self._solver(held_ids), q, tol, max_iter, check)

    def _limit_error(self, iq: int, value: float) -> LimitError:
        """The error for configuration entry ``iq`` at ``value`` outside its limits."""
        clm = self.closed_loop
        if iq in clm.prismatic_q and self._encoder is not None:  # in readings, as the user gives them
            k = int(np.flatnonzero(clm.prismatic_q == iq)[0])
            zero, gain = self._encoder[0][k], self._encoder[1][k]
            value, lo, hi = zero + gain * value, zero + gain * clm.lower[iq], zero + gain * clm.upper[iq]
            return LimitError(clm.joint_name_of_q(iq), value, lo, hi, "stroke")
        what = "stroke" if iq in clm.prismatic_q else "joint"
        return LimitError(clm.joint_name_of_q(iq), value, clm.lower[iq], clm.upper[iq], what)

    def _finish(self, solver: NewtonSolver, q0, tol, max_iter, check: bool, forward: tuple = ()) -> Solution:
        """Solve from ``q0``: plain, or certified FK with ``forward = (joints, sign, warm[, attempt])``."""
        if type(tol) is not float or not 0.0 < tol <= MAX_TOL:  # one comparison on the hot path
            tol = check_tolerance(tol)
        if type(max_iter) is not int or max_iter < 0:
            max_iter = check_max_iter(max_iter)
        if forward:
            out = assembly.solve_forward(solver, q0, forward[0], tol, max_iter, *forward[1:])
            return self._solution(out, check, max_iter=max_iter)
        if solver.compiled_loop:  # inverse kinematics: the solve, pose and limit check in one compiled call
            done = solver.run_checked(q0, tol, max_iter)  # type: ignore[attr-defined]
            if done is not None:
                return self._solution(Outcome(*done[0]), check, done[1], done[2], max_iter)
        return self._solution(Outcome(*solver.run(q0, tol, max_iter)), check, max_iter=max_iter)

    def _outside(self, q: np.ndarray) -> str | None:
        """The limit error of configuration ``q`` (one line), ``None`` when within the limits (or not finite)."""
        bad = self._kernels.first_outside_at(q, self._limited, self._limited_lo, self._limited_hi, LIMIT_SLACK)
        if bad < 0 or not np.all(np.isfinite(q)):
            return None
        k = int(self._limited[bad])
        return str(self._limit_error(k, q[k]))

    def _solution(
        self,
        out: Outcome,
        check: bool,
        pose: np.ndarray | None = None,
        bad: int | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
    ) -> Solution:
        """The :class:`Solution` of a solve's outcome: the joint-limit check, the pose, the readings.

        ``pose`` and ``bad`` (the first joint outside its limits, -1 if none) when the caller
        has them already (the compiled first attempt of :meth:`forward`); ``max_iter`` the
        caller's step limit (:func:`.checks.failure_status` names a stalled solve).
        """
        q, status, it, res, jac, msg = out[:6]
        flags = out.flags
        if status == "converged":
            if bad is None:
                bad = self._kernels.first_outside_at(q, self._limited, self._limited_lo, self._limited_hi, LIMIT_SLACK)
            if bad >= 0:
                k = int(self._limited[bad])
                status, msg = "out_of_limits", str(self._limit_error(k, q[k]))
        elif status == "max_iterations":
            status, msg = failure_status(status, msg, res, max_iter, self._outside(q), self.scale)
            flags = ("not_closed",) if status == "out_of_limits" else flags
        poses = tuple(self.pose_of(c) for c in out.candidates) if out.candidates else ()
        sol = new_solution(
            self.pose_of(q) if pose is None else pose,
            q,
            self.lengths_of(q),
            status,
            it,
            res,
            jac,
            msg,
            flags,
            poses,
            out.det_sign,
        )
        if check and status != "converged":
            error = _ERRORS.get(status, ConvergenceError)
            raise error(sol, f"{status}: {msg}")
        return sol

    def forward_batch(
        self,
        lengths: ArrayLike,
        guess=None,
        *,
        warm: bool = False,
        tol: float | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
    ) -> BatchResult:
        """Direct kinematics of N rows of readings in one call (a compiled loop; row by row if not ``compiled``).

        Args:
            lengths: (N, 6) readings, leg order, metres.
            guess: where every row starts (:class:`Solution` or configuration; default home).
            warm: start each row from the last row that converged instead (a time series, as
                ``hexapod fk`` reads its rows), the first from ``guess``.
            tol: closure residual to reach, as :meth:`forward`.
            max_iter: Newton step limit per row, as :meth:`forward`.

        Returns:
            A :class:`~.batch.BatchResult`: per row what :meth:`forward` with ``check=False``
            gives (``invalid_input`` where it raises: NaN, out of stroke); never raises on a row.
        """
        tol = self.default_tol if tol is None else tol
        return batch.forward_batch(self, lengths, guess, warm, tol, max_iter)

    def inverse_batch(
        self,
        poses: ArrayLike,
        guess=None,
        *,
        warm: bool = False,
        tol: float | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
    ) -> BatchResult:
        """Inverse kinematics of N poses in one call (a compiled loop; row by row if not ``compiled``).

        Args:
            poses: (N, 4, 4) base -> platform transforms, or (N, 7) rows ``x, y, z, qx, qy, qz, qw``
                (metres; the quaternion of norm 1 within 1e-6).
            guess: where every row starts (default home).
            warm: start each row from the last row that converged instead.
            tol: closure residual to reach.
            max_iter: Newton step limit per row.

        Returns:
            A :class:`~.batch.BatchResult`: per row what :meth:`inverse` with ``check=False`` gives.
        """
        tol = self.default_tol if tol is None else tol
        return batch.inverse_batch(self, poses, guess, warm, tol, max_iter)

    def closure_residual(self, q: np.ndarray) -> np.ndarray:
        """Per-leg closure error at ``q`` computed by Pinocchio's constraint models."""
        return self.closed_loop.closure_errors(np.asarray(q, dtype=float))


def load_hexapod(spec: str | Path, *, compiled: bool = True) -> Hexapod:
    """:meth:`Hexapod.load`: a preset name, URDF file or geometry file as a :class:`Hexapod`."""
    return Hexapod.load(spec, compiled=compiled)
