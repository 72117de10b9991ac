"""Direct kinematics from more readings than pose coordinates: weighted least squares and its consistency test.

A hexapod whose geometry (or URDF) declares measuring legs or an inclinometer
(:mod:`hexapod_model.description.sensors`) takes ``m > 6`` readings in
:meth:`hexapod_model.Hexapod.forward`, in the order of ``geometry.reading_names``. The solve:

1. the six legs' readings give the certified pose of direct kinematics (the usual solve,
   compiled or not), the start;
2. Gauss-Newton on the pose ``T <- T exp6(delta)`` (``delta`` in the platform frame) minimises
   ``sum ((z_j - h_j(T)) / sigma_j)^2``, with ``h`` the readings a pose gives: the six legs'
   by inverse kinematics (the closed-loop model, offset Cardan joints included), the measuring
   legs' and the tilts' in closed form; a step that raises the weighted cost is halved (a gross
   fault makes the problem far from linear). The Jacobian ``dh / d delta`` is analytic: the six
   legs' rows from the closure constraints' Jacobian at the inverse-kinematics configuration
   (the passive joints eliminated by one linear solve, the encoder model's gain applied), the
   measuring legs' and the tilts' in closed form (:meth:`RedundantSensing.jacobian`; tested
   against central differences of ``h``);
3. the residual's chi-square test, isolation and the minimal detectable biases
   (:mod:`.consistency`).

``converged`` then states: the six legs' readings alone have a certified assembly (the start),
Gauss-Newton converged from it to the least-squares pose (step below the solve's tolerance),
and the residual passes the chi-square test at ``alpha``; the pose is the weighted
least-squares pose of all readings. A set failing the test gets status
``inconsistent_readings``: ``pose`` is the least-squares pose of all readings, or, when the
data name the faulty reading and the others pass the test without it, their least-squares
pose, flagged ``estimate``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pinocchio as pin

from ..description.sensor_layout import SensorLayout
from ..exceptions import (
    ConvergenceError,
    InconsistentReadingsError,
    InputError,
    LimitError,
    SingularityError,
    SolverError,
)
from .body_check import BODY_STATUSES
from .consistency import DEFAULT_ALPHA, Consistency, consistency, threshold
from .engine import ERRORS, SolveEngine
from .input_checks import LIMIT_SLACK, check_max_iter, check_tolerance, check_vector
from .newton.solver import Solution

MAX_GAUSS_NEWTON = 30  # Gauss-Newton steps of one redundant solve
HALVINGS = 30  # step halvings of one Gauss-Newton step at most


@dataclass(frozen=True)
class RedundantSolution(Solution):
    """A :class:`Solution` of redundant readings, with its consistency test.

    Attributes:
        readings: (m,) the readings given (m, rad), reading order.
        consistency: the chi-square test, suspects and minimal detectable biases.
    """

    readings: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    consistency: Consistency | None = None


class RedundantSensing:
    """Least-squares direct kinematics over the six legs and the extra sensors of ``layout`` (module doc).

    Args:
        engine: the hexapod's solve engine (its six-leg solves).
        layout: the extra sensors.
    """

    def __init__(self, engine: SolveEngine, layout: SensorLayout):
        self.engine = engine
        self.layout = layout
        self.names = layout.names
        self.m = len(self.names)
        self.sigmas = layout.sigmas
        home = engine.home_pose
        d = home[:3, 3] + layout.platform @ home[:3, :3].T - layout.base
        #: (k,) measuring legs' anchor distances at home (m)
        self.home_lengths = np.linalg.norm(d, axis=1)
        clm = engine.closed_loop
        ff = np.arange(clm.platform_v, clm.platform_v + 6)
        free = np.setdiff1d(np.arange(clm.model.nv), ff)
        #: velocity indices of the platform's free flyer and of every other joint (the eliminated ones)
        self._ff, self._free = ff, free
        #: each leg's prismatic joint among ``_free``
        self._prismatic = np.searchsorted(free, clm.prismatic_v)
        self._gain = np.ones(6) if engine.encoder is None else engine.encoder[1].copy()

    # ----- the measurement model -----
    def extra_readings(self, pose: np.ndarray) -> np.ndarray:
        """Readings of the measuring legs (m) and the inclinometer (rad) at ``pose`` (4x4, base frame, m)."""
        lay = self.layout
        R, t = pose[:3, :3], pose[:3, 3]
        dist = np.linalg.norm(t + lay.platform @ R.T - lay.base, axis=1)
        out = lay.zero + (1.0 + lay.scale) * (dist - self.home_lengths)
        if lay.tilt_rotation is not None:
            S = R @ lay.tilt_rotation
            out = np.concatenate([out, np.arcsin(np.clip(S[2, :2], -1.0, 1.0))])
        return out

    def readings_at(self, pose: np.ndarray, guess: object, tol: float, max_iter: int) -> tuple[np.ndarray, Solution]:
        """All ``m`` readings at ``pose`` and the inverse-kinematics solution of the six legs.

        Raises:
            SolverError: the pose's inverse kinematics does not converge (outside the workspace).
        """
        sol = self.engine.inverse(pose, guess, tol, max_iter, False)
        if not sol.converged and sol.status not in BODY_STATUSES:  # cones and collisions: judged on the result
            raise ConvergenceError(sol, f"{sol.status}: inverse kinematics of a least-squares pose: {sol.message}")
        return np.concatenate([sol.lengths, self.extra_readings(pose)]), sol

    def jacobian(self, pose: np.ndarray, ik: Solution) -> np.ndarray:
        """``m x 6`` derivative of the readings in the platform-frame twist ``(v, omega)`` at ``pose``.

        Args:
            pose: 4x4 base -> platform transform (m).
            ik: the inverse-kinematics solution of ``pose`` (its configuration ``q``).

        Rows in reading order (m per m and m per rad for legs, rad per m and rad per rad for
        tilts); the twist moves the pose to ``pose @ exp6((v, omega))``, both in the platform frame.

        Raises:
            SingularityError: the legs' passive joints cannot follow the platform at ``ik.q``
                (a leg at a singular configuration).
        """
        _, G = self.engine.solver(()).evaluate(ik.q)  # closure rows, every joint's velocity column
        A, B = G[:, self._free], G[:, self._ff]
        try:
            X = np.linalg.solve(A, -B) if A.shape[0] == A.shape[1] else np.linalg.lstsq(A, -B, rcond=None)[0]
        except np.linalg.LinAlgError:
            X = np.full((A.shape[1], 6), np.nan)
        if not np.all(np.isfinite(X)):
            raise SingularityError(ik, "the legs' joints cannot follow the platform: a leg is singular")
        J = np.empty((self.m, 6))
        J[:6] = self._gain[:, None] * X[self._prismatic]  # the joint rates through the encoder model
        lay = self.layout
        R, t = pose[:3, :3], pose[:3, 3]
        k = len(lay.base)
        if k:
            u = (t + lay.platform @ R.T - lay.base) @ R  # the legs' vectors in the platform frame
            u *= ((1.0 + lay.scale) / np.sqrt(np.einsum("ij,ij->i", u, u)))[:, None]  # unit, times the gain
            P = lay.platform
            J[6 : 6 + k, :3] = u
            J[6 : 6 + k, 3] = P[:, 1] * u[:, 2] - P[:, 2] * u[:, 1]  # platform anchor x u
            J[6 : 6 + k, 4] = P[:, 2] * u[:, 0] - P[:, 0] * u[:, 2]
            J[6 : 6 + k, 5] = P[:, 0] * u[:, 1] - P[:, 1] * u[:, 0]
        if lay.tilt_rotation is not None:
            g = R[2]  # the base's z axis in the platform frame
            for j in range(2):
                c = lay.tilt_rotation[:, j]  # the inclinometer's axis j in the platform frame
                s = float(g @ c)
                w = 1.0 / np.sqrt(max(1.0 - s * s, 1e-300))
                row = J[6 + k + j]
                row[:3] = 0.0
                row[3] = w * (c[1] * g[2] - c[2] * g[1])  # (c x g) / cos(angle)
                row[4] = w * (c[2] * g[0] - c[0] * g[2])
                row[5] = w * (c[0] * g[1] - c[1] * g[0])
        return J

    def whitened_jacobian(self, pose: np.ndarray, tol: float | None = None, max_iter: int = 50) -> np.ndarray:
        """``m x 6`` Jacobian of the readings divided row-wise by their sigmas at ``pose`` (4x4, base frame, m).

        The ``A`` of :mod:`.consistency` (its minimal detectable biases, parity projector).

        Raises:
            SolverError: ``pose`` is outside the workspace (its inverse kinematics does not converge).
        """
        tol = self.engine.default_tol if tol is None else check_tolerance(tol)
        ik = self.readings_at(pose, None, tol, max_iter)[1]
        return self.jacobian(pose, ik) / self.sigmas[:, None]

    # ----- the solve -----
    def check(self, readings: object) -> np.ndarray:
        """``readings`` as ``m`` finite floats within every stroke, or the :class:`InputError` / :class:`LimitError`."""
        names = ", ".join(self.names)
        z = check_vector(f"readings ({names})", readings, self.m)
        eng = self.engine
        k = eng.kernels.first_outside(z[:6].copy(), eng.stroke_lo, eng.stroke_hi, LIMIT_SLACK)
        if k >= 0:
            raise eng.stroke_error(z[:6].copy(), k)
        lay = self.layout
        for j in range(len(lay.base)):
            lo, hi = lay.stroke[j]
            if not lo - LIMIT_SLACK <= z[6 + j] <= hi + LIMIT_SLACK:
                raise LimitError(self.names[6 + j], z[6 + j], lo, hi, what="stroke")
        return z

    def fit(
        self, z: np.ndarray, keep: np.ndarray, pose: np.ndarray, guess: Solution, tol: float, max_iter: int
    ) -> tuple[np.ndarray, Solution, np.ndarray, np.ndarray, int, bool]:
        """Gauss-Newton on the readings ``keep`` selects, from ``pose``.

        Returns the pose, its inverse-kinematics solution, the whitened Jacobian and
        normalised residuals of all readings there, the step count and whether it converged.
        """
        h_now, sol = self.readings_at(pose, guess, tol, max_iter)
        step_tol = 10.0 * tol
        done, stalled, steps = False, False, 0
        while True:  # the Jacobian and residuals at the pose reached: the returned ones at the end
            A = self.jacobian(pose, sol) / self.sigmas[:, None]
            r = (z - h_now) / self.sigmas
            if stalled or steps == MAX_GAUSS_NEWTON:
                done = stalled
                break
            steps += 1
            cost = float(r[keep] @ r[keep])
            delta = np.linalg.lstsq(A[keep], r[keep], rcond=None)[0]
            if float(np.max(np.abs(delta))) <= step_tol:  # converged: the pose moves less than step_tol
                done = True
                break
            for _ in range(HALVINGS):  # a step that raises the weighted cost is halved (gross faults)
                trial = pose @ pin.exp6(delta).homogeneous
                h_trial, sol_trial = self.readings_at(trial, sol, tol, max_iter)
                r_trial = ((z - h_trial) / self.sigmas)[keep]
                if float(r_trial @ r_trial) <= cost or float(np.max(np.abs(delta))) <= step_tol:
                    break
                delta = delta / 2.0
            pose, h_now, sol = trial, h_trial, sol_trial
            stalled = float(np.max(np.abs(delta))) <= step_tol  # halved down to nothing: a minimum
        return pose, sol, A, r, steps, done

    def forward(
        self,
        readings: object,
        guess: object,
        tol: float,
        max_iter: int,
        check: bool,
        alpha: float = DEFAULT_ALPHA,
        prove: bool = True,
    ) -> RedundantSolution:
        """Direct kinematics of ``m`` readings (module doc); see :meth:`hexapod_model.Hexapod.forward`.

        Raises:
            InputError: wrong count, NaN or inf, a bad ``alpha``.
            LimitError: a reading outside its stroke.
            SolverError: when ``check``: the six-leg solve failed, Gauss-Newton did not converge,
                or (:class:`InconsistentReadingsError`) the readings fail the test.
        """
        if not (isinstance(alpha, float) and 0.0 < alpha < 1.0):
            raise InputError("alpha", alpha, "a false-alarm rate, a float in (0, 1)")
        z = self.check(readings)
        tol, max_iter = check_tolerance(tol), check_max_iter(max_iter)
        six = self.engine.forward(z[:6].copy(), guess, tol, max_iter, False, False, prove)
        if not six.converged:
            sol = self._wrap(six, z, six.status, six.message, six.flags, None)
            return self._raise_or(sol, check)
        every = np.ones(self.m, dtype=bool)
        try:
            pose, ik, A, r, it, done = self.fit(z, every, six.pose, six, tol, max_iter)
        except SolverError as exc:  # the least-squares pose left the workspace
            msg = f"least-squares pose: {exc}"
            return self._raise_or(self._wrap(exc.result, z, exc.result.status, msg, (), None), check)
        if not done:
            msg = f"Gauss-Newton did not converge in {MAX_GAUSS_NEWTON} steps"
            return self._raise_or(self._wrap(ik, z, "max_iterations", msg, (), None, pose, it, six.det_sign), check)
        test = consistency(self.names, A, r, self.sigmas, alpha)
        if test.consistent:
            sol = self._wrap(ik, z, "converged", "", (), test, pose, six.iterations + it, six.det_sign)
            body = self.engine.body
            if body is not None:  # the cone and collision flags, as in forward
                judged = body.judged(sol, True)
                sol = replace(sol, flags=judged.flags, message=judged.message)
            return sol
        flags: tuple[str, ...] = ()
        if test.isolated is not None:  # the pose from the others: a flagged estimate
            keep = np.array([n != test.isolated for n in self.names])
            try:
                est, est_ik, _, r_est, _, est_done = self.fit(z, keep, pose, ik, tol, max_iter)
            except SolverError:  # the others' pose leaves the workspace: no estimate
                est_done = False
            # the others must pass the test themselves (the isolation above is linearised)
            bound = threshold(alpha, test.dof - 1) if test.dof > 1 else np.inf  # dof 1: the others fit exactly
            if est_done and float(r_est[keep] @ r_est[keep]) <= bound:
                pose, ik, flags = est, est_ik, ("estimate", f"without_{test.isolated}")
        msg = test.describe()
        sol = self._wrap(ik, z, "inconsistent_readings", msg, flags, test, pose, six.iterations + it, six.det_sign)
        return self._raise_or(sol, check)

    def _wrap(
        self,
        base: Solution,
        z: np.ndarray,
        status: str,
        message: str,
        flags: tuple[str, ...],
        test: Consistency | None,
        pose: np.ndarray | None = None,
        iterations: int | None = None,
        det_sign: int | None = None,
    ) -> RedundantSolution:
        return RedundantSolution(
            pose=base.pose if pose is None else pose,
            q=base.q,
            lengths=base.lengths,
            status=status,
            iterations=base.iterations if iterations is None else iterations,
            residual=base.residual,
            jacobian=base.jacobian,
            message=message,
            flags=flags or base.flags,
            candidates=base.candidates,
            det_sign=base.det_sign if det_sign is None else det_sign,
            readings=z,
            consistency=test,
        )

    @staticmethod
    def _raise_or(sol: RedundantSolution, check: bool) -> RedundantSolution:
        if check and sol.status != "converged":
            error = InconsistentReadingsError if sol.status == "inconsistent_readings" else ERRORS.get(sol.status)
            raise (error or ConvergenceError)(sol, f"{sol.status}: {sol.message}")
        return sol
