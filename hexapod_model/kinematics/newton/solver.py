"""Newton solver on the constraint manifold, for any set of held joints.

Unknowns are the velocities of the free joints; each step solves the reduced closure system
``G dq = -r`` (36 rows for 6-D closures, 18 for 3-D ones) and moves along the manifold with
``pin.integrate``. Direct kinematics holds the six measured prismatic joints, inverse
kinematics holds the platform's floating joint, a hybrid problem holds any joints named.

The stopping rule is on the closure residual itself (``tol``, mixed metres/radians), checked
after every step (a warm start 1 ms away takes two steps to 1e-10). A step with an entry
larger than ``MAX_STEP`` is shortened along its direction: cold starts far from home
otherwise overshoot into a spurious 180-degree-flipped closure.

The step's size is measured scale-free (:func:`velocity_weights`): its entries in radians as
they are, those in metres (prismatic joints, the platform's translation) divided by the
geometry's length scale (:func:`size_of`: the base radius over ``REFERENCE_RADIUS``, to the
nearest power of two, 1 on the presets). So ``MAX_STEP``, ``ONE_STEP`` and ``THETA_FLOOR``
mean the same on a 1 cm and on a 2 m hexapod. Likewise the residual's norm counts a 6-D
closure's rotation rows (rad) times the length scale, so that it and the tolerance (scaled by
the caller, :attr:`.hexapod.Hexapod.default_tol`) are metres at that scale.
:meth:`NewtonSolver.iterate` also records what :mod:`~hexapod_model.kinematics.certificate` certifies.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np
import pinocchio as pin

from ...description.model import ClosedLoopModel
from .kernel_sets import KernelSet, kernel_set

if TYPE_CHECKING:
    from .proven import Proof

STATUSES = (
    "converged",
    "uncertified",
    "ambiguous_assembly",
    "max_iterations",
    "not_found",
    "no_assembly",
    "singular",
    "out_of_limits",
    "cone_limit",
    "collision",
    "invalid_input",
    "inconsistent_readings",
)
SINGULAR_PIVOT_RATIO = 1e-13
#: m: the base radius the solver's constants in metres are stated for (their length scale 1)
REFERENCE_RADIUS = 0.25
# The step sizes below are of the weighted step (rad, and m per length scale: velocity_weights)
MAX_STEP = 0.5  # rad or m at the reference radius: largest entry of one Newton step (cold starts far away)
THETA_MAX = 0.25  # largest Newton contraction |dx_k+1| / |dx_k| of a checked solve (an estimate, not a bound)
THETA_FLOOR, ONE_STEP = 1e-9, 1e-6  # rounding-level step (no contraction); largest step a solve may end on


def size_of(clm: ClosedLoopModel) -> tuple[float, float]:
    """``(base radius, length scale)`` of a hexapod: what its constants in metres scale by.

    The base radius (m) is the largest horizontal distance of a leg's first joint from the base
    origin (``REFERENCE_RADIUS`` when all lie on the axis); the length scale is its ratio to
    ``REFERENCE_RADIUS`` rounded to the nearest power of two (1 on every preset), so that
    scaling a constant by it is exact.
    """
    anchors = np.array([clm.model.jointPlacements[leg.joints[0]].translation for leg in clm.legs])
    radius = float(np.max(np.linalg.norm(anchors[:, :2], axis=1))) or REFERENCE_RADIUS
    return radius, length_scale(radius)


def length_scale(radius: float) -> float:
    """``radius`` (m) over ``REFERENCE_RADIUS``, rounded to the nearest power of two (:func:`size_of`)."""
    return 2.0 ** round(math.log2(radius / REFERENCE_RADIUS))


def velocity_weights(clm: ClosedLoopModel, scale: float) -> np.ndarray:
    """(nv,) weights that make a velocity (or step) scale-free: ``1 / scale`` for entries in metres, else 1.

    Metres: the prismatic joints and the first three (linear) entries of the platform's free
    flyer; radians: the revolute joints and the free flyer's angular entries.
    """
    m = clm.model
    w = np.ones(m.nv)
    for j in range(1, m.njoints):
        joint = m.joints[j]
        if j == clm.platform_joint:
            w[joint.idx_v : joint.idx_v + 3] = 1.0 / scale
        elif joint.shortname().startswith("JointModelP"):  # PX, PY, PZ, PrismaticUnaligned
            w[joint.idx_v : joint.idx_v + joint.nv] = 1.0 / scale
    return w


@dataclass(frozen=True)
class Solution:
    """Result of one solve. Check :attr:`converged` before using :attr:`pose`.

    Attributes:
        pose: (4, 4) homogeneous transform base -> platform (metres).
        q: Pinocchio configuration of the URDF model (``nq``), free-flyer part relative to home.
        lengths: (6,) measured-joint readings, leg order (metres, zero at home).
        status: one of ``STATUSES`` (docs/solver.md says what each means and what to do).
        iterations: Newton steps taken.
        residual: final closure residual norm (metres; a 6-D closure's rotation rows in radians
            times the geometry's length scale, 1 on the presets).
        jacobian: reduced constraint Jacobian at the final configuration (rows: closures,
            columns: free velocities), or ``None`` if the input was rejected.
        message: human-readable detail when ``status != "converged"`` or a flag is set.
        flags: ``("near_singular",)`` for a direct-kinematics result close to a singularity
            (another assembly may be close; the CLI writes the flag instead of ``ok``); always
            with status ``uncertified``. ``"cone_limit"`` / ``"collision"`` on a direct-kinematics
            result beyond a joint cone or in collision (the message names the joint or pair;
            :mod:`~hexapod_model.kinematics.body_check`). ``("not_closed",)`` for an ``out_of_limits`` result whose
            iteration stopped outside the limits before closing the loops (``q`` closes nothing).
            ``"connected"`` on an ``ambiguous_assembly`` result whose first candidate is the
            assembly connected to the start (the readings path proven past its block, or a
            certified result that another assembly rivals).
        candidates: with status ``ambiguous_assembly``, the (4, 4) poses of the assemblies
            found (``pose`` is the first).
        det_sign: sign of the direct-kinematics Jacobian's determinant at the result (0: none).
        proof: the Krawczyk proof of a warm step (:class:`~.proof.Proof`): set on every warm
            ``converged`` (or ``uncertified``) result of
            :meth:`~hexapod_model.kinematics.hexapod.Hexapod.forward` and by
            :meth:`~hexapod_model.kinematics.hexapod.Hexapod.prove_step`; ``None`` when no
            proof was run (a cold solve, ``prove=False``, a batch row away from a singularity).
    """

    pose: np.ndarray
    q: np.ndarray
    lengths: np.ndarray
    status: str
    iterations: int
    residual: float
    jacobian: np.ndarray | None = field(default=None, repr=False)
    message: str = ""
    flags: tuple[str, ...] = ()
    candidates: tuple[np.ndarray, ...] = field(default=(), repr=False)
    det_sign: int = 0
    proof: Proof | None = field(default=None, repr=False)

    @property
    def converged(self) -> bool:
        """True for a closed configuration within all joint limits (FK: the certified assembly).

        Never for ``uncertified``, ``ambiguous_assembly`` or any other status.
        """
        return self.status == "converged"

    @property
    def closed(self) -> bool:
        """True when :attr:`q` closes every loop to the solve's tolerance (whatever its limits or assembly).

        ``converged``, ``uncertified``, ``ambiguous_assembly`` and ``out_of_limits`` without the
        flag ``not_closed``.
        """
        closing = ("converged", "uncertified", "ambiguous_assembly", "out_of_limits")
        return self.status in closing and "not_closed" not in self.flags

    @property
    def condition_number(self) -> float:
        """2-norm condition number of :attr:`jacobian` (``inf`` when singular, ``nan`` if none)."""
        if self.jacobian is None:
            return float("nan")
        s = np.linalg.svd(self.jacobian, compute_uv=False)
        return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")

    @property
    def position(self) -> np.ndarray:
        """Platform origin in the base frame (m)."""
        return self.pose[:3, 3]

    @property
    def rotation(self) -> np.ndarray:
        """Platform orientation in the base frame (3x3)."""
        return self.pose[:3, :3]

    @property
    def placement(self) -> pin.SE3:
        """:attr:`pose` as a Pinocchio ``SE3`` (base -> platform, metres)."""
        return pin.SE3(self.pose)


#: a compiled certified attempt's result: ``(q, pose, jacobian, iterations, residual, first joint outside
#: its limits or -1)`` when it converged certified, else ``(status, iterations, residual, message)``
Attempt = tuple[np.ndarray, np.ndarray, np.ndarray, int, float, int] | tuple[str, int, float, str]


class OneCallSolver(Protocol):
    """The one-call solves of a solver whose whole iteration runs compiled (:class:`.compiled.CompiledSolver`).

    :attr:`NewtonSolver.one_call` is one of these, or ``None`` on the general path: the typed
    choice between the two paths.
    """

    #: whether a float64 configuration ``(q, platform_q, tol)`` is finite with a unit platform quaternion
    check_start: Callable[..., bool]
    #: the settings of the next certified attempt (:data:`.packing.SETTINGS`)
    forward_settings: np.ndarray
    #: ``(ints, floats, work, iwork)``: the packed tables and buffers the compiled loops take
    arrays: tuple
    home_sign: float
    home_kappa: float
    sign: float
    kappa: float

    def certified_forward(
        self, start: np.ndarray, joints: np.ndarray, tol: float, max_iter: int, sign: float
    ) -> Attempt:
        """The certified first attempt of direct kinematics from ``start`` holding ``joints`` (m)."""
        ...

    def hold_stroke(self, lower: np.ndarray, upper: np.ndarray, slack: float) -> None:
        """The stroke (m) that :meth:`attempt_readings` checks its readings against."""
        ...

    def attempt_readings(
        self, start: np.ndarray, readings: np.ndarray, tol: float, max_iter: int, sign: float
    ) -> Attempt | int:
        """The stroke check of six readings (m) and the certified attempt holding them; an int: the first outside."""
        ...

    def run_checked(self, q0: np.ndarray, tol: float, max_iter: int) -> tuple[tuple, np.ndarray, int] | None:
        """A plain solve, the pose and the limit check in one call; ``None`` where it has none."""
        ...


class NewtonSolver:
    """Newton iteration for one choice of held joints on a :class:`ClosedLoopModel`.

    Args:
        clm: the loaded hexapod.
        held_joints: Pinocchio joint ids whose values stay as given.
        kernels: the step's kernels (default: the numba-compiled ones; see
            :mod:`~hexapod_model.kinematics.newton.kernel_sets`).

    Buffers are allocated once here; :meth:`run` allocates only the new configuration
    returned by ``pin.integrate``. ``length_scale`` and ``weights`` (:func:`size_of`,
    :func:`velocity_weights`) make the step's limits scale-free; ``step_weights`` are the free
    velocities' ``weights``; ``residual_weights`` weigh the residual's rows in its norm.
    """

    #: the one-call solves of a solver whose iteration runs compiled (:class:`.compiled.CompiledSolver`
    #: sets itself here), ``None`` for the general solver
    one_call: OneCallSolver | None = None

    def __init__(self, clm: ClosedLoopModel, held_joints: tuple[int, ...], kernels: KernelSet | None = None):
        self.clm = clm
        self.kernels = kernel_set(True) if kernels is None else kernels
        self.model = clm.model
        self.data = self.model.createData()  # a Data of its own: one per solver, per thread
        self.J = self.data.J  # a view on Pinocchio's buffer, refreshed by computeJointJacobians
        #: Pinocchio frame ids of the closure frames: the six leg tips, then the six anchors
        self.frame_ids = tuple(leg.tip_frame for leg in clm.legs) + tuple(leg.anchor_frame for leg in clm.legs)
        m = clm.model
        held_v = np.zeros(clm.nv, dtype=bool)
        for j in held_joints:
            held_v[m.joints[j].idx_v : m.joints[j].idx_v + m.joints[j].nv] = True
        self.held_joints = tuple(held_joints)
        self.free_v = np.flatnonzero(~held_v).astype(np.int64)
        self.colmap = np.full(self.model.nv, -1, dtype=np.int64)
        self.colmap[self.free_v] = np.arange(self.free_v.size)
        self.length_scale = size_of(clm)[1]
        self.weights = velocity_weights(clm, self.length_scale)
        self.step_weights = np.ascontiguousarray(self.weights[self.free_v])
        nmax = max(len(leg.joints) for leg in clm.legs)
        self.leg_cols = np.full((6, nmax), -1, dtype=np.int64)
        for i, leg in enumerate(clm.legs):
            cols = [m.joints[j].idx_v for j in leg.joints]
            self.leg_cols[i, : len(cols)] = cols
        self.ff_cols = np.arange(clm.platform_v, clm.platform_v + 6, dtype=np.int64)
        self.rows = 6 if clm.kind == "6d" else 3
        #: (6 rows,) weights of the residual's rows in its norm: 1 (m), the length scale for rotation rows (rad)
        self.residual_weights = np.tile(
            [1.0, 1.0, 1.0, self.length_scale, self.length_scale, self.length_scale][: self.rows], 6
        )
        n_res, n_free = 6 * self.rows, self.free_v.size
        self.square = n_res == n_free
        self.R = np.zeros((12, 3, 3))
        self._H = np.zeros((12, 4, 4))
        self.p = np.zeros((12, 3))
        self.E = np.zeros((6, 3, 3))
        self.r = np.zeros(n_res)
        self.G = np.zeros((n_res, n_free))
        self.x = np.zeros(n_free)
        self.LU = np.zeros((n_res, n_free))
        self.piv = np.zeros(n_free, dtype=np.int64)
        self.block_cols = self._blocks(held_v)
        self.held_pos = self._schur(held_v)
        if self.held_pos is not None:
            self.LB = np.zeros((6, self.rows, self.rows))
            self.PB = np.zeros((6, self.rows), dtype=np.int64)
            self.A = np.zeros((6, self.rows, 6))
            self.M = np.zeros((6, 6))
            self.pm = np.zeros(6, dtype=np.int64)
            self.nb, self.wb = np.zeros(6), np.zeros(6)
        if self.block_cols is not None:
            self.LUb = np.zeros((self.rows, self.rows))
            self.rb, self.xb = np.zeros(self.rows), np.zeros(self.rows)
        self.dv = np.zeros(self.model.nv)
        self.q_aug = pin.neutral(self.model)
        self.jac_args = (self.J, self.leg_cols, self.ff_cols, self.colmap, self.rows, self.p, self.E, self.G)
        self.sign, self.kappa, self.det_sign, self.theta, self.certified = 0.0, np.inf, 0.0, 0.0, False  # last step
        self.home_sign, self.home_kappa = 0.0, np.inf
        if self.held_pos is not None:  # Schur path: arguments bound once (17 attribute loads cost 1 us)
            s = self
            a = [s.J, s.leg_cols, s.held_pos, s.ff_cols, s.colmap, s.rows, s.p, s.E, s.r, s.x, s.LB, s.PB]
            self._schur_args = tuple(a + [s.A, s.M, s.pm, s.nb, s.wb, s.length_scale])
            self.iterate(clm.q_home, np.inf, 0)  # converged at once: one Schur step at home
            self.home_sign, self.home_kappa = self.sign, self.kappa

    def _blocks(self, held_v: np.ndarray) -> np.ndarray | None:
        """Columns of each block when the closure Jacobian is block diagonal.

        (6, rows) columns of G per closure when G is block diagonal and square per block
        (platform held, every leg with as many free joints as closure rows), else None.
        """
        if not held_v[self.clm.platform_v]:
            return None
        blocks = []
        for row in self.leg_cols:
            cols = [int(self.colmap[c]) for c in row if c >= 0 and self.colmap[c] >= 0]
            if len(cols) != self.rows:
                return None
            blocks.append(cols)
        return np.array(blocks, dtype=np.int64)

    def _schur(self, held_v: np.ndarray) -> np.ndarray | None:
        """Held joint of each leg when the Schur path applies.

        Position of the held joint in each leg when the Schur path applies (platform free,
        every leg with ``rows`` one-dof joints of which exactly one is held), else None.
        """
        if held_v[self.clm.platform_v] or not self.square:
            return None
        pos = []
        for row in self.leg_cols:
            cols = [int(c) for c in row if c >= 0]
            held = [k for k, c in enumerate(cols) if self.colmap[c] < 0]
            if len(cols) != self.rows or len(held) != 1:
                return None
            pos.append(held[0])
        return np.array(pos, dtype=np.int64)

    def _solve_step(self) -> float:
        """Solve the Newton system into ``self.x``.

        Fill ``self.x`` with the solution of ``G x = r``; return the smallest pivot ratio
        (0 when singular, 1 for the least-squares path of non-square hybrid problems). On the
        Schur path ``self.sign`` becomes the sign of ``det G`` (up to a constant of the layout)
        and ``self.kappa`` a bound of the condition number of the eliminated 6x6 Jacobian
        ``M = -dl/dxi`` (leg-reading rates per platform twist).
        """
        kernels = self.kernels
        if self.held_pos is not None:
            ratio, self.kappa = kernels.schur_solve(*self._schur_args)
            self.sign = 1.0 if ratio > 0.0 else -1.0
            return abs(ratio)
        kernels.jacobian(*self.jac_args)
        if not self.square:
            self.x[:] = np.linalg.lstsq(self.G, self.r, rcond=None)[0]
            return 1.0
        if self.block_cols is not None:
            return kernels.block_solve(
                self.G, self.r, self.rows, self.block_cols, self.LUb, self.piv, self.rb, self.xb, self.x
            )
        ratio = kernels.lu_factor(self.G, self.LU, self.piv)
        if ratio >= SINGULAR_PIVOT_RATIO:
            kernels.lu_apply(self.LU, self.piv, self.r, self.x)
        return ratio

    def _frames(self) -> None:
        """Closure frame placements into ``R``, ``p`` (after ``computeJointJacobians`` set the joints').

        Twelve reads of ``data.oMf`` (a few microseconds each); the previous releases read them
        from the Jacobian of an internal copy of the model with a free-flyer "probe" at every
        closure frame, in one call, but its Pinocchio ``Data`` took 90 MB per solver.
        """
        pin.updateFramePlacements(self.model, self.data)
        oMf, H = self.data.oMf, self._H
        for k, f in enumerate(self.frame_ids):
            H[k] = oMf[f].homogeneous
        self.R[:] = H[:, :3, :3]
        self.p[:] = H[:, :3, 3]

    def evaluate(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual (copy) and reduced Jacobian (copy) at URDF configuration ``q``."""
        self.q_aug[: self.clm.nq] = q
        pin.computeJointJacobians(self.model, self.data, self.q_aug)
        self._frames()
        self.kernels.closure_residual(self.R, self.p, self.rows, self.E, self.r, self.length_scale)
        self.kernels.jacobian(*self.jac_args)
        return self.r.copy(), self.G.copy()

    def iterate(
        self,
        q0: np.ndarray,
        tol: float,
        max_iter: int,
        sign: float = 0.0,
        offset: np.ndarray | None = None,
        scale: float = 0.0,
        certify: bool = False,
    ) -> tuple[str, int, float, str]:
        """Newton from ``q0`` (held joints set) on ``r - scale * offset``: ``(status, iterations, residual, message)``.

        Leaves the result in ``self.q_aug``. With ``certify``, ``self.certified``: no shortened,
        singular or flipped step, every ``|dx_k+1| / |dx_k| <= THETA_MAX`` (``self.theta``; one step
        above ``ONE_STEP`` is followed by a second), the sign ``sign`` (or the first's) at every
        Schur step; the solve stops (status ``uncertified``) once that fails.
        """
        model, data = self.model, self.data
        rows, R, p, E, r, frames = self.rows, self.R, self.p, self.E, self.r, self._frames
        x, free_v, dv, solve_step, weights = self.x, self.free_v, self.dv, self._solve_step, self.step_weights
        length = self.length_scale
        kernels = self.kernels
        q = self.q_aug
        q[: self.clm.nq] = q0
        status, message, it = "max_iterations", "", 0
        theta, previous, certified, inf = 0.0, 0.0, True, np.inf
        while True:
            pin.computeJointJacobians(model, data, q)
            frames()
            norm, min_trace = kernels.closure_residual(R, p, rows, E, r, length)  # rotations times length
            if scale != 0.0:
                norm = kernels.shift_residual(r, offset, scale, rows, length)
            if norm <= tol and (it != 1 or previous <= ONE_STEP):  # one large step: measure a contraction
                status = "converged"
                if min_trace < 1.0:
                    status, message = "max_iterations", "converged to a spurious closure flipped by 180 deg"
                    certified = False
                elif it == 0 and (ratio := solve_step()) < SINGULAR_PIVOT_RATIO:
                    # no step factored the Jacobian: check the start itself is not singular
                    status, certified = "singular", False
                    message = f"start is singular (pivot ratio {ratio:.2g} < {SINGULAR_PIVOT_RATIO:g}), no step taken"
                break
            if it >= max_iter or not norm < inf:  # also stops on NaN
                message = f"no convergence to {tol:g} in {it} iterations (residual {norm:.3g})"
                break
            ratio = solve_step()
            if ratio < SINGULAR_PIVOT_RATIO:
                status, certified = "singular", False
                message = f"constraint Jacobian singular (pivot ratio {ratio:.2g} < {SINGULAR_PIVOT_RATIO:g})"
                break
            biggest = kernels.scatter_step(x, free_v, dv, MAX_STEP, weights)  # weighted: scale-free
            if certify:
                certified = sign == 0.0 or self.sign == sign  # the sign is only known on the Schur path
                sign = sign or self.sign
                if previous > THETA_FLOOR and biggest > theta * previous:
                    theta = biggest / previous
                previous = biggest
                if not (certified and biggest <= MAX_STEP and theta <= THETA_MAX):
                    status, message, certified = "uncertified", "contraction or determinant sign check failed", False
                    break
            q = pin.integrate(model, q, dv)
            it += 1
        self.q_aug = q
        self.theta, self.det_sign, self.certified = theta, sign, certified
        return status, it, float(norm), message

    def run(self, q0: np.ndarray, tol: float, max_iter: int) -> tuple[np.ndarray, str, int, float, np.ndarray, str]:
        """Iterate from URDF configuration ``q0`` (held joints already set), no certificate.

        Returns ``(q, status, iterations, residual, jacobian, message)``.
        """
        status, it, norm, message = self.iterate(q0, tol, max_iter)
        self.kernels.jacobian(*self.jac_args)
        return self.q_aug[: self.clm.nq].copy(), status, it, norm, self.G.copy(), message
