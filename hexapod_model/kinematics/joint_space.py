"""The joint space of one loaded hexapod: readings, joint values, configurations, poses, and their limits.

:class:`JointSpace` holds the model's encoder model (reading = zero + gain * prismatic joint
value), the stroke and joint limits and the one-line errors naming them, and the conversions
between leg readings (m), configurations (Pinocchio ``q``) and platform poses (4x4, base ->
platform, m). :class:`.engine.SolveEngine` adds the solvers to it.
"""

from __future__ import annotations

import functools

import numpy as np

from ..description.geometry import HexapodGeometry
from ..description.model import ClosedLoopModel
from ..exceptions import LimitError
from .input_checks import LIMIT_SLACK, MAX_TOL, check_guess, check_pose, check_vector
from .newton.kernel_sets import KernelSet, kernel_set
from .newton.solver import Solution, size_of

DEFAULT_TOL = 1e-12  # closure residual (m, rad) at a 0.25 m base radius: pose errors below 1e-9 on every preset


class JointSpace:
    """Readings, configurations and poses of one hexapod, their limits and conversions (see the module doc).

    Args:
        model: the loaded closed-loop model.
        geometry: the geometry it was generated from, if any.
        compiled: convert with the numba-compiled kernels (else the NumPy ones).
    """

    def __init__(self, model: ClosedLoopModel, geometry: HexapodGeometry | None = None, *, compiled: bool = True):
        self.closed_loop = model
        #: whether the solves run the numba-compiled kernels
        self.compiled = bool(compiled)
        self.geometry = geometry
        self.nq = model.model.nq
        #: the URDF's joint names (Pinocchio order, the universe excluded)
        self.joint_names: tuple[str, ...] = tuple(model.model.names[1:])
        #: each leg's encoder model ``(zero, gain)`` (reading = zero + gain * prismatic value), None when the identity
        self.encoder: tuple[np.ndarray, np.ndarray] | None = (
            None
            if not (np.any(model.encoder_zero) or np.any(model.encoder_scale))
            else (model.encoder_zero.copy(), 1.0 + model.encoder_scale)
        )
        #: (6, 2) reading limits (m): the prismatic joint limits, through the encoder model if any
        self.stroke = self.readings_of(np.array([[model.lower[i], model.upper[i]] for i in model.prismatic_q]).T).T
        self.prismatic_names = tuple(model.model.names[leg.prismatic] for leg in model.legs)
        self.home_h = model.home.homogeneous
        self.q_shape = (self.nq,)
        self.prismatic_q = model.prismatic_q
        #: (6,) lower and upper reading limits (m), contiguous, for the compiled stroke check
        self.stroke_lo = np.ascontiguousarray(self.stroke[:, 0])
        self.stroke_hi = np.ascontiguousarray(self.stroke[:, 1])
        #: configuration indices with limits, and their lower and upper limits (m or rad)
        self.limited = model.limited_q()
        self.limited_lo = model.lower[self.limited].copy()
        self.limited_hi = model.upper[self.limited].copy()
        #: the joint-limit check's arguments (limited q indices, lower, upper, slack)
        self.limits = (self.limited, self.limited_lo, self.limited_hi, LIMIT_SLACK)
        #: largest horizontal distance of a leg's first joint from the base origin (m), and the length scale
        self.base_radius, self.scale = size_of(model)
        #: the closure residual a solve stops at by default (m, rad): ``DEFAULT_TOL * scale``
        self.default_tol = min(DEFAULT_TOL * self.scale, MAX_TOL)

    @functools.cached_property
    def kernels(self) -> KernelSet:
        """The kernels of :attr:`compiled`: numba is imported at the first solve, not on loading."""
        return kernel_set(self.compiled)

    # ----- conversions -----
    @property
    def home_pose(self) -> np.ndarray:
        """Platform pose at home (4x4, base frame, metres)."""
        return self.closed_loop.home.homogeneous

    def pose_of(self, q: np.ndarray) -> np.ndarray:
        """Platform pose (4x4, base frame, metres) of configuration ``q``."""
        i = self.closed_loop.platform_q
        T = np.empty((4, 4))
        self.kernels.xyzquat_to_pose(q[i : i + 7], self.home_h, T)
        return T

    def lengths_of(self, q: np.ndarray) -> np.ndarray:
        """Leg readings (m) of configuration ``q``, leg order."""
        joints = q[self.prismatic_q]  # a new array already
        return joints if self.encoder is None and joints.dtype == np.float64 else self.readings_of(joints)

    def readings_of(self, joints: np.ndarray) -> np.ndarray:
        """Leg readings (m) of prismatic joint values (m, leg order, last axis): the encoder model."""
        if self.encoder is None:
            return np.array(joints, dtype=float)
        return self.encoder[0] + self.encoder[1] * np.asarray(joints, dtype=float)

    def joints_of(self, readings: np.ndarray) -> np.ndarray:
        """Prismatic joint values (m) of leg readings (m, leg order): the inverse of :meth:`readings_of`."""
        if self.encoder is None:
            return np.array(readings, dtype=float)
        return (np.asarray(readings, dtype=float) - self.encoder[0]) / self.encoder[1]

    def set_pose(self, q: np.ndarray, pose: object) -> None:
        """Write the checked platform pose ``pose`` (4x4, base frame, m) into configuration ``q``."""
        T = check_pose(pose, self.kernels.rigid_error)
        i = self.closed_loop.platform_q
        self.kernels.pose_to_xyzquat(T, self.home_h, q[i : i + 7])

    def start(self, guess: object, copy: bool = True) -> np.ndarray:
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

    # ----- limits and their messages -----
    def stroke_error(self, lengths: np.ndarray, k: int) -> LimitError:
        """The error for reading ``k`` (m) outside its stroke (an :class:`InputError` first for NaN / inf)."""
        check_vector("lengths", lengths, 6)  # names NaN / inf first
        return LimitError(self.prismatic_names[k], lengths[k], self.stroke[k, 0], self.stroke[k, 1], what="stroke")

    def limit_error(self, iq: int, value: float) -> LimitError:
        """The error for configuration entry ``iq`` at ``value`` (m or rad) outside its limits."""
        clm = self.closed_loop
        if iq in clm.prismatic_q and self.encoder is not None:  # in readings, as the user gives them
            k = int(np.flatnonzero(clm.prismatic_q == iq)[0])
            zero, gain = self.encoder[0][k], self.encoder[1][k]
            value, lo, hi = zero + gain * value, zero + gain * clm.lower[iq], zero + gain * clm.upper[iq]
            return LimitError(clm.joint_name_of_q(iq), value, lo, hi, "stroke")
        what = "stroke" if iq in clm.prismatic_q else "joint"
        return LimitError(clm.joint_name_of_q(iq), value, clm.lower[iq], clm.upper[iq], what)

    def outside(self, q: np.ndarray) -> str | None:
        """The limit error of configuration ``q`` (one line), ``None`` when within the limits (or not finite)."""
        bad = self.kernels.first_outside_at(q, self.limited, self.limited_lo, self.limited_hi, LIMIT_SLACK)
        if bad < 0 or not np.all(np.isfinite(q)):
            return None
        k = int(self.limited[bad])
        return str(self.limit_error(k, q[k]))
