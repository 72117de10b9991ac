"""The user-facing :class:`Hexapod`: direct, inverse and hybrid kinematics in a few calls.

>>> import hexapod_model as hm
>>> hexa = hm.Hexapod.from_preset("reference")
>>> sol = hexa.forward([0.01, 0.0, -0.01, 0.0, 0.01, 0.0])   # leg readings, metres
>>> back = hexa.inverse(sol.pose)                           # back.lengths ~ the readings
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..description.geometry import GEOMETRY_SUFFIXES, HexapodGeometry, load_geometry
from ..description.mjcf_loader import MJCF_SUFFIXES, load_mjcf
from ..description.model import ClosedLoopModel
from ..description.presets import PRESETS, get_preset
from ..description.sensor_layout import SensorLayout, read_sensors
from ..description.urdf import geometry_to_urdf
from ..exceptions import InputError
from . import batch, hybrid
from .all_assemblies import DEFAULT_STARTS, Assemblies
from .batch import BatchResult
from .body_check import BodyCheck
from .certificate import NEAR_SINGULAR_FACTOR
from .consistency import DEFAULT_ALPHA
from .engine import DEFAULT_MAX_ITER, HOME_CONDITION_LIMIT, SolveEngine
from .input_checks import LIMIT_SLACK, MAX_TOL, POSE_TOLERANCE, check_pose, check_vector
from .joint_space import DEFAULT_TOL
from .newton.outcomes import new_solution
from .newton.solver import OneCallSolver, Solution
from .redundant import RedundantSensing

if TYPE_CHECKING:
    from .clearance import Clearance

__all__ = [
    "DEFAULT_MAX_ITER",
    "DEFAULT_TOL",
    "HOME_CONDITION_LIMIT",
    "POSE_TOLERANCE",
    "Hexapod",
    "check_pose",
    "check_vector",
    "load_hexapod",
]


class Hexapod:
    """A hexapod loaded from a URDF that follows the contract of ``docs/urdf_contract.md``.

    Construct with :meth:`from_urdf`, :meth:`from_preset`, :meth:`from_geometry` or :meth:`from_mjcf`.
    Leg readings (``lengths``) are the measured prismatic joints in metres, zero at home;
    poses are 4x4 base -> platform transforms in metres. One object may be shared by threads:
    each thread solves with solver buffers of its own.

    ``compiled=False`` (every constructor takes it) solves with the NumPy kernels instead of the
    numba-compiled ones (:mod:`~hexapod_model.kinematics.newton.kernel_sets`): the same answers, several
    times slower per solve, but no numba import (~1 s, 130 MB) nor first compilation (~20 s).

    ``check_body`` (default True; every constructor takes it, and :attr:`check_body` may be set
    later) judges every answer against the joint cones and the collision bodies
    (:mod:`~hexapod_model.kinematics.body_check`):
    inverse and hybrid kinematics return ``cone_limit`` or ``collision``, direct kinematics
    flags them. ``False`` skips the check (a warm forward solve then costs no clearance query)
    and the envelope's say in the choice between assemblies.

    The solves run on :attr:`engine` (:class:`~hexapod_model.kinematics.engine.SolveEngine`):
    the per-thread solvers, the limits and the encoder model, for code that builds on them.
    """

    def __init__(
        self,
        model: ClosedLoopModel,
        geometry: HexapodGeometry | None = None,
        *,
        compiled: bool = True,
        check_body: bool = True,
    ):
        #: the solve engine: solvers, limits, the encoder model, how outcomes become answers
        self.engine = engine = SolveEngine(model, geometry, compiled=compiled, check_body=check_body)
        self.closed_loop = model
        #: whether the solves run the numba-compiled kernels
        self.compiled = engine.compiled
        self.geometry = geometry
        m = model.model
        #: the Pinocchio model of the URDF tree (``RobotWrapper.model``)
        self.model: pin.Model = m
        #: its Pinocchio data (``RobotWrapper.data``); the solver uses buffers of its own
        self.data: pin.Data = model.data
        #: one Pinocchio constraint model per loop closure, leg order
        self.constraint_models = list(model.constraints)
        self.nq, self.nv = m.nq, m.nv
        self.joint_names = engine.joint_names
        #: (6, 2) reading limits (m): the prismatic joint limits, through the encoder model if any
        self.stroke = engine.stroke
        self.prismatic_names = engine.prismatic_names
        #: 2-norm condition number of the direct-kinematics constraint Jacobian at home (scale-free)
        self.home_condition_number = engine.home_condition_number
        #: largest horizontal distance of a leg's first joint from the base origin (m), and
        #: the size ratio, to the nearest power of two (1 for the presets), the constants scale by
        self.base_radius, self.scale = engine.base_radius, engine.scale
        #: the closure residual a solve stops at by default (m, rad): ``DEFAULT_TOL * scale``
        self.default_tol = engine.default_tol
        layout = (
            SensorLayout.from_geometry(geometry)
            if geometry is not None
            else read_sensors(model.urdf_xml, model.source)
            if model.urdf_xml
            else None
        )
        #: the least-squares solve over the measuring legs and inclinometer, ``None`` without any
        #: (:mod:`~hexapod_model.kinematics.redundant`)
        self.redundancy = None if layout is None else RedundantSensing(engine, layout)
        #: the names of the readings :meth:`forward` takes, in their order
        self.reading_names = ("leg1", "leg2", "leg3", "leg4", "leg5", "leg6") if layout is None else layout.names
        #: the leg encoders' count (m of reading) from the geometry; 0: continuous or not known
        self.encoder_resolution = 0.0 if geometry is None else geometry.encoder_resolution

    @property
    def check_body(self) -> bool:
        """Whether answers are judged against the cones and collision bodies (see the class doc)."""
        return self.engine.body is not None

    @check_body.setter
    def check_body(self, on: bool) -> None:
        engine = self.engine
        if not isinstance(on, bool):
            raise InputError("check_body", on, "expected True or False")
        if on and engine.body is None:
            engine.body = BodyCheck(self.closed_loop, self.geometry, self.compiled)
        elif not on:
            engine.body = None

    # ----- construction -----
    @classmethod
    def from_urdf(cls, path: str | Path, *, compiled: bool = True, check_body: bool = True) -> Hexapod:
        """Load a URDF file, or a preset when ``path`` is a preset name (see ``PRESETS``)."""
        if str(path) in PRESETS:
            return cls.from_preset(str(path), compiled=compiled, check_body=check_body)
        return cls(ClosedLoopModel.from_file(path), compiled=compiled, check_body=check_body)

    @classmethod
    def load(cls, spec: str | Path, *, compiled: bool = True, check_body: bool = True) -> Hexapod:
        """A preset name, or a URDF, geometry (``.toml``, ``.yaml``, ``.yml``, ``.json``) or MJCF (``.xml``) file.

        This is what every ``hexapod`` sub-command does with its HEXAPOD argument.
        """
        if str(spec).lower().endswith(GEOMETRY_SUFFIXES):
            return cls.from_geometry(load_geometry(spec), compiled=compiled, check_body=check_body)
        if str(spec).lower().endswith(MJCF_SUFFIXES):
            return cls.from_mjcf(spec, compiled=compiled, check_body=check_body)
        return cls.from_urdf(spec, compiled=compiled, check_body=check_body)

    @classmethod
    def from_mjcf(cls, path: str | Path, *, compiled: bool = True, check_body: bool = True) -> Hexapod:
        """Load an MJCF file (``hexapod mjcf``, docs/mjcf.md) through Pinocchio's MJCF parser and constraint models."""
        return cls(load_mjcf(path), compiled=compiled, check_body=check_body)

    @classmethod
    def from_preset(cls, name: str = "reference", *, compiled: bool = True, check_body: bool = True) -> Hexapod:
        """One of the bundled geometries (``PRESETS``).

        ``reference``, ``intersecting``, ``spherical``, ``3-6``, ``guideway``; with redundant
        sensors ``reference7`` and ``reference_tilt``.
        """
        return cls.from_geometry(get_preset(name), compiled=compiled, check_body=check_body)

    @classmethod
    def from_geometry(cls, geometry: HexapodGeometry, *, compiled: bool = True, check_body: bool = True) -> Hexapod:
        """Generate the URDF of ``geometry`` in memory and load it."""
        clm = ClosedLoopModel(geometry_to_urdf(geometry), f"<geometry {geometry.name}>")
        return cls(clm, geometry, compiled=compiled, check_body=check_body)

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
        return self.engine.pose_of(q)

    def lengths_of(self, q: np.ndarray) -> np.ndarray:
        """Leg readings (m) of configuration ``q``, leg order."""
        return self.engine.lengths_of(q)

    def readings_of(self, joints: np.ndarray) -> np.ndarray:
        """Leg readings (m) of prismatic joint values (m, leg order, last axis).

        The URDF's ``<encoder>`` model; the identity without one.
        """
        return self.engine.readings_of(joints)

    def joints_of(self, readings: np.ndarray) -> np.ndarray:
        """Prismatic joint values (m) of leg readings (m, leg order): the inverse of :meth:`readings_of`."""
        return self.engine.joints_of(readings)

    # ----- solves -----
    def forward(
        self,
        lengths: ArrayLike,
        guess=None,
        *,
        tol: float | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
        check: bool = True,
        alpha: float = DEFAULT_ALPHA,
        prove: bool = True,
    ) -> Solution:
        """Direct kinematics: platform pose from the six leg readings (m), or from all readings of redundant sensors.

        From a ``guess`` (a warm solve) a ``converged`` result carries the Krawczyk proof of its
        readings path from the guess (``proof``; docs/solver.md): it is proven to be the
        assembly connected to the guess, within ``proof.position_m`` (m) and
        ``proof.rotation_rad`` (rad) of the exact solution; a result that could not be proven is
        ``uncertified``. A cold solve (from home) carries the certificate's checks instead.

        A hexapod with measuring legs or an inclinometer (:attr:`redundancy`) takes every
        reading, in the order of :attr:`reading_names`, and returns a
        :class:`~hexapod_model.kinematics.redundant.RedundantSolution`: the weighted
        least-squares pose and its chi-square consistency test (status
        ``inconsistent_readings`` when it fails; docs/redundancy.md).

        Args:
            lengths: six readings, leg order, metres (zero at home); with redundant sensors the
                readings of :attr:`reading_names` (m for legs, rad for tilts).
            guess: previous :class:`Solution` or configuration to start from (default: home).
            tol: closure residual to reach, in (0, 1e-6] (metres and radians); default
                :attr:`default_tol` (``DEFAULT_TOL`` = 1e-12 scaled with the base radius to the
                nearest power of two: the presets' 1e-12, 3.1e-14 for a 1 cm base radius).
            max_iter: Newton step limit (an int >= 0).
            check: raise on a result that is not ``converged`` (default). With
                ``check=False`` the :class:`Solution` is returned and its ``status`` says why.
            alpha: false-alarm rate of the consistency test (redundant sensors only).
            prove: False skips the proof of a warm step (``proof`` None): ``converged`` then
                rests on the certificate's checks alone, a heuristic (docs/solver.md), for a
                caller that measures the solve alone or proves the step otherwise.

        Raises:
            InputError: wrong count or shape, NaN or inf, complex or text values, a bad
                ``guess``, ``tol``, ``max_iter`` or ``alpha``.
            LimitError: a reading outside its stroke.
            ConvergenceError, SingularityError, WorkspaceError, InconsistentReadingsError: when
                ``check`` and the solve failed.
        """
        tol = self.default_tol if tol is None else tol
        if self.redundancy is not None:
            return self.redundancy.forward(lengths, guess, tol, max_iter, check, alpha, prove)
        if not (isinstance(lengths, np.ndarray) and lengths.shape == (6,) and lengths.dtype == np.float64):
            lengths = check_vector("lengths", lengths, 6)
        fast = type(tol) is float and 0.0 < tol <= MAX_TOL and type(max_iter) is int and max_iter >= 0
        engine = self.engine
        solver: OneCallSolver | None = getattr(engine.local, "staged", None)  # the warm path's, once this thread has it
        # a configuration array (a tracker's prediction) starts with no determinant sign, as in engine.forward
        array = type(guess) is np.ndarray
        fits = (
            guess is None
            or array
            or type(guess) is Solution
            and type(guess.q) is np.ndarray
            and guess.q.shape == engine.q_shape
        )
        if solver is not None and fast and fits:
            # the hot path of a warm solve: the stroke check and the certified attempt in one compiled call
            if guess is None:
                start, sign = self.closed_loop.q_home, solver.home_sign
            elif array:  # a new array; one that is not a valid start goes the general way (the stroke first)
                ok = guess.dtype == np.float64 and guess.shape == engine.q_shape
                start, sign = (guess.copy() if ok else guess), 0
                if not (ok and solver.check_start(start, self.closed_loop.platform_q, POSE_TOLERANCE)):
                    return engine.forward(lengths, guess, tol, max_iter, check, fast, prove)
            else:
                start, sign = guess.q, guess.det_sign
            done = solver.attempt_readings(start, lengths, tol, max_iter, sign)
            if isinstance(done, int):
                raise engine.stroke_error(lengths, done)
            if len(done) == 6 and done[5] < 0 and solver.kappa <= NEAR_SINGULAR_FACTOR * solver.home_kappa:
                # converged certified within the limits, not near a singularity: engine.attempted()'s Solution
                q, pose, jac, it, res, _ = done
                readings = q[engine.prismatic_q]  # lengths_of(q) without an encoder model
                prover = None if guess is None or not prove else engine.prover
                proof = None if prover is None else prover.prove(start, q)  # a warm step's proof
                good = proof is None or proof.proven
                sol = new_solution(pose, q, readings, "converged", it, res, jac, "", (), (), int(solver.sign), proof)
                if engine.body is not None:
                    sol = engine.body.judged(sol, True)
                if good:
                    return sol
                return engine.proven_warm(sol, guess, start, lengths, tol, max_iter, check, proof)
            held = engine.solver(engine.held_forward)
            return engine.attempted(
                held, done, lengths, lengths, start, tol, max_iter, sign, guess, check, False, prove
            )
        return engine.forward(lengths, guess, tol, max_iter, check, fast, prove)

    def assemblies(
        self, lengths: ArrayLike, *, reference: np.ndarray | None = None, starts: int = DEFAULT_STARTS, seed: int = 0
    ) -> Assemblies:
        """Every assembly for these readings that can be found: the global answer of direct kinematics.

        For a 3-6 hexapod (e.g. preset ``3-6``) all of them, from the resultant polynomial
        (``complete`` is True); for the others, what plain Newton reaches from home and ``starts``
        random poses (``complete`` is False: assemblies it does not reach may exist).
        See :mod:`~hexapod_model.kinematics.all_assemblies`.

        Args:
            lengths: six readings, leg order, metres (zero at home).
            reference: order the assemblies by distance to this pose (4x4, default home).
            starts: random starts of the multi-start search (ignored for a 3-6 hexapod).
            seed: random seed of those starts.

        Returns:
            :class:`~.all_assemblies.Assemblies`: the assemblies within the stroke and joint limits
            (converged inverse-kinematics :class:`Solution` each), the count of those outside.

        Raises:
            InputError, LimitError: as :meth:`forward` for the readings.
        """
        engine = self.engine
        lengths = check_vector("lengths", lengths, 6)
        k = engine.kernels.first_outside(lengths, engine.stroke_lo, engine.stroke_hi, LIMIT_SLACK)
        if k >= 0:
            raise engine.stroke_error(lengths, k)
        ref = None if reference is None else check_pose(reference, engine.kernels.rigid_error)
        if type(starts) is not int or starts < 0:
            raise InputError("starts", starts, "an int >= 0")
        return engine.finder.find(lengths, ref, starts, seed)

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
        return self.engine.inverse(pose, guess, tol, max_iter, check)

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
        engine = self.engine
        q = engine.start(guess)
        held_ids = hybrid.hold(engine, held, q)
        tol = self.default_tol if tol is None else tol
        return engine.finish(engine.solver(held_ids), q, tol, max_iter, check)

    def forward_batch(
        self,
        lengths: ArrayLike,
        guess=None,
        *,
        warm: bool = False,
        tol: float | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
        prove: bool = True,
    ) -> BatchResult:
        """Direct kinematics of N rows of readings in one call (a compiled loop; row by row if not ``compiled``).

        Args:
            lengths: (N, 6) readings, leg order, metres.
            guess: where every row starts (:class:`Solution` or configuration; default home).
            warm: start each row from the last row that converged instead (a time series, as
                ``hexapod fk`` reads its rows), the first from ``guess``.
            tol: closure residual to reach, as :meth:`forward`.
            max_iter: Newton step limit per row, as :meth:`forward`.
            prove: as :meth:`forward`: a ``converged`` row solved from a guess (``guess``, or
                the last converged row with ``warm``) carries the Krawczyk proof of its step
                (:attr:`~.batch.BatchResult.proofs`), and one that cannot be proven is
                ``uncertified``; a step longer than :data:`~.batch.PROOF_STEP` (2 mm of a
                reading) keeps the certificate's checks. False keeps the certificate's checks
                alone (and proves a row near a singularity only), for a caller that measures the
                solve alone.

        Returns:
            A :class:`~.batch.BatchResult`: per row what :meth:`forward` with ``check=False``
            gives (``invalid_input`` where it raises: NaN, out of stroke); never raises on a row.

        Raises:
            InputError: a hexapod with redundant sensors (its readings are solved by :meth:`forward`, one set a call).
        """
        if self.redundancy is not None:
            names = ", ".join(self.reading_names)
            raise InputError(
                "lengths",
                "(N, 6) rows",
                f"this hexapod takes its {len(self.reading_names)} readings ({names}) in forward()",
            )
        tol = self.default_tol if tol is None else tol
        return batch.forward_batch(self.engine, lengths, guess, warm, tol, max_iter, bool(prove))

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
            warm: start each row from the last row that converged instead (a row refused as
                ``cone_limit`` or ``collision`` counts: its configuration closes within the limits).
            tol: closure residual to reach.
            max_iter: Newton step limit per row.

        Returns:
            A :class:`~.batch.BatchResult`: per row what :meth:`inverse` with ``check=False`` gives.
        """
        tol = self.default_tol if tol is None else tol
        return batch.inverse_batch(self.engine, poses, guess, warm, tol, max_iter)

    def prove_step(self, guess: Solution | ArrayLike, sol: Solution) -> Solution:
        """``sol``, a :meth:`forward` result from ``guess``, with the Krawczyk proof of its readings path.

        The proof (:class:`~.newton.proof.Proof`, rigorous in floating point) that the path of
        solutions for the readings from ``guess``'s to ``sol``'s stays on one assembly and ends
        within :attr:`~.newton.proof.Proof.position_m` / ``rotation_rad`` of ``sol.pose``. A
        ``converged`` result whose proof fails is returned ``uncertified``. :meth:`forward` runs
        it on every warm result (with proven steps for a long one); this runs the one test of
        the step (halved when it fails) on any result: a batch row, a ``prove=False`` solve.

        Args:
            guess: the closed configuration or :class:`Solution` the solve started from.
            sol: the result.
        """
        return self.engine.prove_step(guess, sol)

    def clearance(self, q_or_pose: ArrayLike) -> Clearance:
        """Smallest distance between two collision bodies, their names and nearest points (docs/solver.md).

        ``q_or_pose``: a configuration (``nq`` values) or a 4x4 platform pose (base frame, m).
        """
        from . import clearance  # coal and the collision bodies load at the first query, not with the package

        return clearance.clearance(self, q_or_pose)

    def closure_residual(self, q: np.ndarray) -> np.ndarray:
        """Per-leg closure error at ``q`` computed by Pinocchio's constraint models."""
        return self.closed_loop.closure_errors(np.asarray(q, dtype=float))


def load_hexapod(spec: str | Path, *, compiled: bool = True, check_body: bool = True) -> Hexapod:
    """:meth:`Hexapod.load`: a preset name, URDF file or geometry file as a :class:`Hexapod`."""
    return Hexapod.load(spec, compiled=compiled, check_body=check_body)
