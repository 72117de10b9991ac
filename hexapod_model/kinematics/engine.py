"""The solve engine under :class:`~hexapod_model.kinematics.hexapod.Hexapod`: solvers, limits, answers.

:class:`SolveEngine` holds what a solve needs besides its inputs: the joint space of
:mod:`.joint_space` (the encoder model, the stroke and joint limits and their messages, the
conversions between readings, configurations and poses), one Newton solver per held set
and per thread (compiled where :func:`.newton.compiled.solver_for` allows, else general), the
global direct kinematics of :mod:`.all_assemblies`, and how a solve's outcome becomes a
:class:`Solution` or an error. ``Hexapod`` is the facade users call; :mod:`.batch`,
:mod:`.hybrid`, :mod:`.all_assemblies` and the analyses call this engine (``hexa.engine``).
"""

from __future__ import annotations

import functools
import threading
from dataclasses import replace
from typing import Literal

import numpy as np

from ..description.geometry import HexapodGeometry
from ..description.model import ClosedLoopModel
from ..exceptions import AssemblyError, ConvergenceError, SingularityError, WorkspaceError
from . import certificate
from .all_assemblies import AssemblyFinder, review
from .body_check import BodyCheck
from .certificate import Outcome
from .connected import connected_chain, connected_end
from .input_checks import LIMIT_SLACK, MAX_TOL, check_home_conditioning, check_max_iter, check_tolerance, failure_status
from .joint_space import JointSpace
from .newton.kernel_sets import kernel_set
from .newton.outcomes import new_solution
from .newton.proof import Proof, StepProver, attach_proof, with_proof
from .newton.solver import NewtonSolver, Solution

DEFAULT_MAX_ITER = 20
#: largest 2-norm condition number of the direct-kinematics constraint Jacobian at home
#: (metres and radians; the presets have 9-67, a 20x smaller hexapod about 700, a singular
#: layout with parallel, coplanar or coincident legs 1e13 and more)
HOME_CONDITION_LIMIT = 1e6
#: a guess whose closure at its own readings moves no joint further (m, rad) is proven from as it is
GUESS_CLOSED = 1e-9
#: ``prove`` of :meth:`SolveEngine.forward`: the proof of a warm result near a singularity only
NEAR_SINGULAR: Literal["near_singular"] = "near_singular"
#: which warm results :meth:`SolveEngine.forward` proves: every one (True), none, or :data:`NEAR_SINGULAR`
Prove = bool | Literal["near_singular"]
#: a warm step the whole-step proof does not prove is followed in proven steps: at most this
#: many Newton solves (each with its proof) ...
WARM_CHAIN_SOLVES = 256
#: ... none shorter than this fraction of the step (shorter ones fail only at a fold)
WARM_CHAIN_MIN_STEP = 2.0**-8
#: the error each failed status raises with ``check`` (``ConvergenceError`` for the others)
ERRORS = {
    "singular": SingularityError,
    "out_of_limits": WorkspaceError,
    "ambiguous_assembly": AssemblyError,
    "uncertified": AssemblyError,
    "no_assembly": WorkspaceError,
    "cone_limit": WorkspaceError,
    "collision": WorkspaceError,
}


class SolveEngine(JointSpace):
    """The state and the solves of one loaded hexapod (see the module doc).

    Args:
        model: the loaded closed-loop model.
        geometry: the geometry it was generated from, if any (the 3-6 resultant uses it).
        compiled: solve with the numba-compiled kernels (else the NumPy ones).
        check_body: judge every answer against the joint cones and the collision bodies
            (:mod:`.body_check`; :attr:`body` is None without it).

    One engine may be shared by threads: :meth:`solver` gives each thread solvers of its own.
    Lengths are metres, angles radians, poses 4x4 base -> platform transforms.
    """

    def __init__(
        self,
        model: ClosedLoopModel,
        geometry: HexapodGeometry | None = None,
        *,
        compiled: bool = True,
        check_body: bool = True,
    ):
        super().__init__(model, geometry, compiled=compiled)
        #: the cones, collision and envelope check of the answers (:mod:`.body_check`), None when off
        self.body: BodyCheck | None = BodyCheck(model, geometry, compiled) if check_body else None
        #: the calling thread's state: ``.solvers`` {held joints: solver}, ``.staged`` the warm forward's solver
        self.local = threading.local()
        #: joint ids held by direct kinematics (the prismatic joints) and by inverse kinematics (the platform)
        self.held_forward = tuple(leg.prismatic for leg in model.legs)
        self.held_inverse = (model.platform_joint,)
        #: held set -> (free directions, rank) of the closure system (:func:`.hybrid.free_directions_of`)
        self.free_directions: dict[tuple[int, ...], tuple[int, int]] = {}
        #: 2-norm condition number of the direct-kinematics constraint Jacobian at home (scale-free)
        self.home_condition_number = self._home_conditioning()

    @functools.cached_property
    def finder(self) -> AssemblyFinder:
        """The global direct kinematics (:mod:`.all_assemblies`)."""
        return AssemblyFinder(self)

    def _home_conditioning(self) -> float:
        """Condition number of the direct-kinematics Jacobian at home; GeometryError above the limit.

        Scale-free: rotation rows times the length scale, metre columns divided by it (the
        solver's weights), so a hexapod scaled by a power of two has its preset's figure.
        Evaluated with the NumPy kernels: loading a hexapod compiles nothing.
        """
        solver = NewtonSolver(self.closed_loop, self.held_forward, kernel_set(False))
        _, G = solver.evaluate(self.closed_loop.q_home)
        G = solver.residual_weights[:, None] * G / solver.step_weights  # scale-free rows and columns
        return check_home_conditioning(G, self.closed_loop.source, HOME_CONDITION_LIMIT)

    # ----- solvers -----
    def solver(self, held: tuple[int, ...]) -> NewtonSolver:
        """The calling thread's solver for this set of held joint ids (buffers are not shared)."""
        solvers = getattr(self.local, "solvers", None)
        if solvers is None:
            solvers = self.local.solvers = {}
        solver = solvers.get(held)
        if solver is None and self.compiled:
            from .newton.compiled import solver_for  # numba: imported by the first compiled solve

            solver = solvers[held] = solver_for(self.closed_loop, held, self.limits)
        elif solver is None:
            solver = solvers[held] = NewtonSolver(self.closed_loop, held, self.kernels)
        return solver

    # ----- answers -----
    def solution(
        self,
        out: Outcome,
        check: bool,
        pose: np.ndarray | None = None,
        bad: int | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
        forward: bool = False,
    ) -> Solution:
        """The :class:`Solution` of a solve's outcome: the joint-limit check, the pose, the readings.

        ``pose`` and ``bad`` (the first joint outside its limits, -1 if none) when the caller
        has them already (the compiled first attempt of direct kinematics); ``max_iter`` the
        caller's step limit (:func:`.input_checks.failure_status` names a stalled solve);
        ``forward``: a direct-kinematics answer (the body check flags it, else sets its status).
        Raises the status's error when ``check`` and the status is not ``converged``.
        """
        q, status, it, res, jac, msg = out[:6]
        flags = out.flags
        if status == "converged":
            if bad is None:
                bad = self.kernels.first_outside_at(q, self.limited, self.limited_lo, self.limited_hi, LIMIT_SLACK)
            if bad >= 0:
                k = int(self.limited[bad])
                status, msg = "out_of_limits", str(self.limit_error(k, q[k]))
        elif status == "max_iterations":
            status, msg = failure_status(status, msg, res, max_iter, self.outside(q), self.scale)
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
        if self.body is not None:
            sol = self.body.judged(sol, forward)
            status, msg = sol.status, sol.message
        if check and status != "converged":
            text = msg if msg.startswith(f"{status}:") else f"{status}: {msg}"  # the body check's names it
            raise ERRORS.get(status, ConvergenceError)(sol, text)
        return sol

    def finish(
        self, solver: NewtonSolver, q0: np.ndarray, tol: object, max_iter: object, check: bool, forward: tuple = ()
    ) -> Solution:
        """Solve from ``q0``: plain, or certified FK with ``forward = (joints, sign, warm[, attempt])``."""
        if type(tol) is not float or not 0.0 < tol <= MAX_TOL:  # one comparison on the hot path
            tol = check_tolerance(tol)
        if type(max_iter) is not int or max_iter < 0:
            max_iter = check_max_iter(max_iter)
        if forward:
            start = q0.copy()  # solve_forward writes the readings into q0
            out = certificate.solve_forward(solver, q0, forward[0], tol, max_iter, *forward[1:])
            if out.status == "ambiguous_assembly":  # the path is blocked: the candidates
                out = self.candidates(solver, out, start, forward[0], tol, max_iter)
            return self.solution(out, check, max_iter=max_iter, forward=True)
        one_call = solver.one_call
        if one_call is not None:  # inverse kinematics: the solve, pose and limit check in one compiled call
            done = one_call.run_checked(q0, tol, max_iter)
            if done is not None:
                return self.solution(Outcome(*done[0]), check, done[1], done[2], max_iter)
        return self.solution(Outcome(*solver.run(q0, tol, max_iter)), check, max_iter=max_iter)

    def candidates(
        self, solver: NewtonSolver, out: Outcome, start: np.ndarray, joints: np.ndarray, tol: float, max_iter: int
    ) -> Outcome:
        """A blocked path's ``ambiguous_assembly`` outcome: the connected assembly first, the machine's only.

        The proven path past the block (:func:`.connected.connected_end`) gives the assembly
        connected to ``start`` (the first candidate, flagged ``connected``); with the body check
        on, only the candidates within the cones, the collision-free set and the envelope
        remain (the certificate kept those within the stroke and joint limits).
        """
        if self.prover is not None:
            end = connected_end(solver, self.prover, start, joints, tol, max_iter)
            if end is not None:
                out = certificate.with_connected(solver, out, end)
        body = self.body
        if body is None:
            return out
        keep = [not body.violations(c) and body.within_envelope(self.pose_of(c)) for c in out.candidates]
        return certificate.restricted(solver, out, keep, "beyond a cone, in collision or outside the envelope")

    def reviewed(self, sol: Solution, lengths: np.ndarray, guess: object, check: bool) -> Solution:
        """A 3-6 hexapod's result checked against every assembly (:func:`.all_assemblies.review`).

        A warm ``out_of_limits`` is only the verdict of the assembly the path from the guess
        reached (near a singularity, perhaps not even the connected one): every assembly
        settles it, so readings whose one assembly within the limits is another get that
        assembly, as a cold solve does, not a false workspace verdict.
        Raised when ``check`` and the reviewed status is not ``converged``.
        """
        settle = guess is not None and sol.status == "out_of_limits"
        sol = review(self.finder, sol, lengths, guess, settle=settle)
        if check and sol.status != "converged":
            raise ERRORS.get(sol.status, ConvergenceError)(sol, f"{sol.status}: {sol.message}")
        return sol

    # ----- solves -----
    def forward(
        self,
        lengths: np.ndarray,
        guess: object,
        tol: float,
        max_iter: int,
        check: bool,
        fast: bool,
        prove: Prove = True,
    ) -> Solution:
        """Direct kinematics of checked readings ``lengths`` (m) but for their stroke, off the warm path.

        ``fast``: ``tol`` and ``max_iter`` are valid already. Sets this thread's warm-path solver
        (``local.staged``, a :class:`.newton.solver.OneCallSolver`) when the hexapod allows it.
        See :meth:`.hexapod.Hexapod.forward`.
        """
        k = self.kernels.first_outside(lengths, self.stroke_lo, self.stroke_hi, LIMIT_SLACK)
        if k >= 0:
            raise self.stroke_error(lengths, k)
        solver = self.solver(self.held_forward)
        sign = solver.home_sign if guess is None else getattr(guess, "det_sign", 0)
        joints = lengths if self.encoder is None else self.joints_of(lengths)
        start = self.start(guess, copy=False)  # solve_forward writes its own copy
        review = self.finder.exact is not None  # a 3-6 hexapod: every assembly is accounted for
        one_call = solver.one_call
        if fast and one_call is not None:
            if self.encoder is None and not review:  # the next solves on this thread take the warm path
                one_call.hold_stroke(self.stroke_lo, self.stroke_hi, LIMIT_SLACK)
                self.local.staged = one_call
            # the certified first attempt in one compiled call; solve_forward goes on from it
            done = one_call.certified_forward(start, joints, tol, max_iter, sign)
            return self.attempted(
                solver, done, lengths, joints, start, tol, max_iter, sign, guess, check, review, prove
            )
        sol = self.finish(solver, start.copy(), tol, max_iter, check and not review, (joints, sign, guess is not None))
        tol, max_iter = check_tolerance(tol), check_max_iter(max_iter)  # valid: finish raised otherwise
        return self.judged(sol, lengths, joints, guess, start, tol, max_iter, check, review, prove)

    def attempted(
        self,
        solver: NewtonSolver,
        done: tuple,
        lengths: np.ndarray,
        joints: np.ndarray,
        start: np.ndarray,
        tol: float,
        max_iter: int,
        sign: float,
        guess: object,
        check: bool,
        review: bool,
        prove: Prove = True,
    ) -> Solution:
        """The :class:`Solution` of direct kinematics after the compiled certified attempt ``done``.

        Its result when it converged certified (:meth:`.newton.compiled.CompiledSolver.certified_forward`),
        else :func:`.certificate.solve_forward` goes on from it.
        """
        if len(done) == 6:
            q, pose, jac, it, res, bad = done
            outcome = certificate.certified_outcome(solver, q, jac, it, res)
            sol = self.solution(outcome, check and not review, pose, bad, forward=True)
        else:
            forward = (joints, sign, guess is not None, done)
            sol = self.finish(solver, start.copy(), tol, max_iter, check and not review, forward)
        return self.judged(sol, lengths, joints, guess, start, tol, max_iter, check, review, prove)

    @functools.cached_property
    def prover(self) -> StepProver | None:
        """The Krawczyk proof of warm steps (:mod:`.newton.proof`)."""
        return StepProver.of(self.closed_loop)

    def prove_step(self, guess: object, sol: Solution) -> Solution:
        """``sol``, a direct-kinematics result from ``guess``, with the Krawczyk proof of its readings path."""
        return with_proof(self.prover, self.start(guess), sol)

    def judged(
        self,
        sol: Solution,
        lengths: np.ndarray,
        joints: np.ndarray,
        guess: object,
        start: np.ndarray,
        tol: float,
        max_iter: int,
        check: bool,
        review: bool,
        prove: Prove = True,
    ) -> Solution:
        """A direct-kinematics result with its proof (:meth:`proven_warm`), a 3-6 hexapod's reviewed first.

        The review against every assembly (:meth:`reviewed`) comes first: a result it replaces
        (the candidates of several assemblies, or the only one within the limits) is the global
        answer of the resultant, not a step from the guess, and is not proven as one.
        ``prove`` False: no proof (:meth:`.hexapod.Hexapod.forward`); :data:`NEAR_SINGULAR`: only
        of a result flagged ``near_singular`` (the batches' rule, :mod:`.batch`).
        """
        if prove == NEAR_SINGULAR:
            prove = "near_singular" in sol.flags
        if not review:
            if not prove:
                return sol
            return self.proven_warm(sol, guess, start, joints, tol, max_iter, check)
        reviewed = self.reviewed(sol, lengths, guess, False)
        if reviewed is sol and prove:
            reviewed = self.proven_warm(sol, guess, start, joints, tol, max_iter, False)
        if check and reviewed.status != "converged":
            raise ERRORS.get(reviewed.status, ConvergenceError)(reviewed, f"{reviewed.status}: {reviewed.message}")
        return reviewed

    def proven_warm(
        self,
        sol: Solution,
        guess: object,
        start: np.ndarray,
        joints: np.ndarray,
        tol: float,
        max_iter: int,
        check: bool,
        proof: Proof | None = None,
    ) -> Solution:
        """A warm ``converged`` result stays so only with the Krawczyk proof of its readings path from ``start``.

        One test of the whole step first (:meth:`.newton.proof.StepProver.prove`, which
        subdivides the step when that fails); a guess that does not close at its own readings
        is then closed there by plain Newton, and the step proven from that closure. Away from a
        singularity a step it cannot prove (a long one) is followed from ``start`` in proven
        steps (:func:`.connected.connected_chain`, at most ``WARM_CHAIN_SOLVES`` solves, none
        shorter than ``WARM_CHAIN_MIN_STEP`` of the path), and the last of them is proven again
        to end at ``sol``. Not near a singularity (flag ``near_singular``): there the straight
        readings path that the steps follow may pass a fold that the plate's own path did not,
        and end at another assembly than the plate's; only the step's own proof counts. Without
        a proof the result is ``uncertified``. A hexapod without a prover (legs that are not
        chains of one-dof joints) keeps the certificate's verdict. ``joints``: the prismatic
        values of the readings (m). ``proof``: the step's own proof, when the caller ran it.
        """
        if guess is None or sol.status != "converged":
            return sol
        prover = self.prover  # numba: the proof's kernels compile (or load) at the first warm solve
        if prover is None:
            return sol
        if proof is None:
            proof = prover.prove(start, sol.q)
        if proof.proven:  # the usual case: nothing more to look up or solve
            return attach_proof(sol, proof)
        solver = self.solver(self.held_forward)
        # a guess that does not close: from its closure at its own readings
        closed, status = solver.run(start.copy(), tol, max_iter)[:2]
        if status == "converged" and np.max(np.abs(closed - start)) > GUESS_CLOSED:
            start, tests = closed, proof.tests
            proof = prover.prove(start, sol.q)
            proof = replace(proof, tests=tests + proof.tests)
        if not proof.proven and "near_singular" not in sol.flags:
            chain = connected_chain(
                solver, prover, start, joints, tol, max_iter, WARM_CHAIN_MIN_STEP, WARM_CHAIN_SOLVES
            )
            tests = proof.tests + (0 if chain is None else chain.tests)
            last = None if chain is None else prover.prove(chain.before, sol.q)
            if chain is not None and last is not None and last.proven:
                proof = replace(last, tests=tests + last.tests, subdivisions=chain.steps)
            else:
                proof = replace(proof, tests=tests + (0 if last is None else last.tests))
                why = "no proven path of steps from the guess" if chain is None else "its proven steps end elsewhere"
                sol = attach_proof(sol, proof)
                sol = replace(sol, message=f"{sol.message}, and {why}")
        sol = attach_proof(sol, proof)
        if check and not sol.converged:
            raise AssemblyError(sol, f"{sol.status}: {sol.message}")
        return sol

    def inverse(
        self,
        pose: object,
        guess: object = None,
        tol: float | None = None,
        max_iter: int = DEFAULT_MAX_ITER,
        check: bool = True,
    ) -> Solution:
        """Inverse kinematics of ``pose`` (4x4, base -> platform, m): :meth:`.hexapod.Hexapod.inverse`."""
        solver = self.solver(self.held_inverse)  # made first: a first solve after installation is announced
        q = self.start(guess)
        self.set_pose(q, pose)  # the first after installation compiles its check and conversion: announced above
        tol = self.default_tol if tol is None else tol
        return self.finish(solver, q, tol, max_iter, check)
