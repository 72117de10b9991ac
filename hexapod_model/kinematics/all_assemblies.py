"""Every assembly for a set of readings, where it can be had: the global answer of direct kinematics.

:meth:`.hexapod.Hexapod.forward` returns the assembly connected to its start. Where the question
is which assembly the platform is in (a cold start after power-on), :meth:`.hexapod.Hexapod.assemblies`
answers it globally:

* **3-6 hexapods** (legs meeting in pairs at three platform points, e.g. preset ``3-6``): the
  resultant polynomial of :mod:`.three_six` gives *every* real assembly (at most 16, 1-2 ms);
  the set is complete (``complete``). :meth:`.hexapod.Hexapod.forward` uses it by itself
  (:func:`review`). Only the assemblies within the stroke and joint limits, and, with the body
  check on (:mod:`.body_check`), within the joint cones, the collision-free set and the operating
  envelope, compete. A cold result stays ``converged`` only when it is the one such assembly;
  a warm one with a reading more than ``WARM_CHECK`` base radii from the guess's (or a cold one
  with the body check off, where the stroke and joint limits alone rarely decide), when no other
  lies within ``MARGIN`` times its distance from the start (poses compared by
  :func:`hexapod_model.lie.pose_distance`, rotations times the base radius); otherwise it is
  ``ambiguous_assembly`` with all of them as candidates, the connected one first (flagged
  ``connected``; a blocked path's when :mod:`.connected` proved it past the block). A connected
  result beyond a cone, in collision or outside the envelope does not compete: the one
  assembly that does is returned (several: ``ambiguous_assembly``; none: the connected result
  with its flags). Readings the
  polynomial has no real root for are ``no_assembly``; when Newton found nothing or could not
  follow the path from home, the one assembly within the limits is returned as ``converged``
  (several: ``ambiguous_assembly``). Warm starts closer than ``WARM_CHECK`` base radii (a
  tracker's samples) keep the connected assembly unchecked; a warm ``out_of_limits``, however
  near, is settled by every assembly (``settle``: near a singularity the path from the guess may
  end past a limit while another assembly, the only one within the limits, is the platform's).
  Every distance here is relative to the base radius, so a hexapod scaled by any factor gets the
  same answers. (At home's readings the ``3-6`` preset has four assemblies within its stroke and
  joint limits: home and three tilted by about 85 deg, 60 mm lower, beyond its 45 deg ball-joint
  cones.)
* **other hexapods**: a multi-start search: plain Newton from home and from ``starts``
  configurations of random poses (translation within the largest stroke, roll, pitch and yaw
  within ``SAMPLE_ANGLE``); every distinct closed configuration it reaches. It finds what its
  starts lead to and **proves nothing** about the assemblies it did not reach (``complete`` is
  False): more starts find more of them, at ~30 us a start.

Each assembly is checked against the stroke and joint limits (and the body check's cones,
collisions and envelope) by inverse kinematics of its pose (the leg joints of an offset-Cardan
leg follow from the pose); those outside are counted.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
import pinocchio as pin

from ..description.geometry import HexapodGeometry, LegGeometry
from ..description.model import ClosedLoopModel
from ..description.sensors import DEFAULT_ENCODER_SIGMA
from ..exceptions import GeometryError, WorkspaceError
from ..lie import pose_distance, rpy_to_matrix
from .body_check import BodyCheck
from .newton.solver import NewtonSolver, Solution
from .noise_assemblies import noise_assemblies, noise_reach
from .three_six import ThreeSixFK

SAME = 5e-7  # times the base radius (1e-7 m on the presets): two poses closer than this are one assembly
SAMPLE_ANGLE = np.radians(40.0)  # rad: roll, pitch, yaw range of the multi-start search's poses
DEFAULT_STARTS = 64  # starts of the multi-start search besides home
MARGIN = 3.0  # a result competes with the assemblies within this many times its distance from the start
#: what an assembly must lie within to compete (the last three with the body check on)
LIMITS = "the stroke and joint limits, the cones, the collision-free set and the envelope"
WARM_CHECK = 5e-3  # times the base radius (1 mm on the presets): a warm start farther in a reading is checked


@dataclass(frozen=True)
class Assemblies:
    """The assemblies found for one set of readings.

    Attributes:
        solutions: the assemblies within the stroke and joint limits, each a converged
            :class:`Solution` of inverse kinematics of its pose, nearest the reference first.
        outside: how many real assemblies found lie outside the stroke or joint limits.
        complete: True when ``solutions`` are provably all of them (the 3-6 resultant), False
            for the multi-start search.
        method: ``"resultant"`` or ``"multi-start (N starts)"``.
        near: (3-6 hexapods) the assemblies within the limits of readings within the noise
            reach of these (:func:`.noise_assemblies.noise_assemblies`: a complex root pair of
            the resultant that such a reading change makes real), nearest the reference first.
    """

    solutions: tuple[Solution, ...]
    outside: int
    complete: bool
    method: str
    near: tuple[Solution, ...] = ()

    @property
    def poses(self) -> tuple[np.ndarray, ...]:
        """The (4, 4) base -> platform poses (m) of :attr:`solutions`."""
        return tuple(s.pose for s in self.solutions)


class PoseSolver(Protocol):
    """What the global direct kinematics asks of the solve engine (:class:`.engine.SolveEngine`).

    Lengths in metres, poses 4x4 base -> platform transforms.
    """

    closed_loop: ClosedLoopModel
    geometry: HexapodGeometry | None
    #: (6, 2) reading limits (m)
    stroke: np.ndarray
    #: m: rotations count times this in pose distances
    base_radius: float
    #: the closure residual a solve stops at by default (m, rad)
    default_tol: float
    #: joint ids held by direct kinematics
    held_forward: tuple[int, ...]
    #: the cones, collision and envelope check (None: off)
    body: BodyCheck | None

    @property
    def home_pose(self) -> np.ndarray:
        """Platform pose at home."""
        ...

    def pose_of(self, q: np.ndarray) -> np.ndarray:
        """Platform pose of configuration ``q``."""
        ...

    def lengths_of(self, q: np.ndarray) -> np.ndarray:
        """Leg readings of configuration ``q``."""
        ...

    def joints_of(self, readings: np.ndarray) -> np.ndarray:
        """Prismatic joint values of leg readings."""
        ...

    def solver(self, held: tuple[int, ...]) -> NewtonSolver:
        """The calling thread's solver for these held joint ids."""
        ...

    def inverse(
        self, pose: object, guess: object = ..., tol: float | None = ..., max_iter: int = ..., check: bool = ...
    ) -> Solution:
        """Inverse kinematics of ``pose``."""
        ...


def three_six_geometry(hexa: PoseSolver) -> HexapodGeometry | None:
    """The 3-6 layout of a hexapod loaded without its geometry (a URDF or MJCF file), or None.

    A 3-6 hexapod here has point (``3d``) closures whose platform anchors coincide for legs
    ``2k``, ``2k+1``, and a home pose that is a pure translation along z. Each leg's base point is
    its first joint's origin at home (the universal joint's centre), its platform point the
    anchor frame's position in the platform frame. The derived layout is accepted only when the
    resultant's assemblies at home's readings include the model's home pose (1e-9 base radii),
    so a layout the model does not follow is never used.
    """
    clm = hexa.closed_loop
    if any(c.kind != "3d" for c in clm.closures):
        return None
    m = clm.model
    R, t = clm.home.rotation, clm.home.translation
    if not np.allclose(R, np.eye(3), atol=1e-12) or np.hypot(t[0], t[1]) > 1e-12 * hexa.base_radius:
        return None
    data = m.createData()
    pin.forwardKinematics(m, data, clm.q_home)
    legs = []
    for i, leg in enumerate(clm.legs):
        base = data.oMi[leg.joints[0]].translation
        anchor = m.frames[leg.anchor_frame].placement.translation
        lo, hi = (float(v) for v in hexa.stroke[i])
        b = (float(base[0]), float(base[1]), float(base[2]))
        a = (float(anchor[0]), float(anchor[1]), float(anchor[2]))
        legs.append(LegGeometry(base_anchor=b, platform_anchor=a, stroke=(lo, hi)))
    try:
        geometry = HexapodGeometry(
            name=m.name or "urdf", joint_type="spherical", legs=tuple(legs), home_height=float(t[2])
        )
        exact = ThreeSixFK(geometry)
        homes = [s.pose for s in exact.solve_all(np.zeros(6))]
    except (GeometryError, WorkspaceError):
        return None
    near = [pose_distance(hexa.home_pose, T, hexa.base_radius) for T in homes]
    return geometry if near and min(near) <= 1e-9 * hexa.base_radius else None


class AssemblyFinder:
    """The global direct kinematics of one hexapod (see the module doc)."""

    def __init__(self, hexa: PoseSolver):
        self.hexa = hexa
        self.exact: ThreeSixFK | None = None
        geometry = hexa.geometry if hexa.geometry is not None else three_six_geometry(hexa)
        if geometry is not None:
            try:
                self.exact = ThreeSixFK(geometry)
            except GeometryError:  # not a 3-6 layout
                self.exact = None
        self.length = hexa.base_radius  # m: rotations count times this in pose distances
        sigma = DEFAULT_ENCODER_SIGMA if geometry is None else geometry.encoder_sigma
        #: m, how far each prismatic joint may lie from the measured readings' (the noise reach of
        #: :func:`.noise_assemblies.noise_reach`, the geometry's ``encoder_sigma``, through the encoder model)
        self.reach = np.abs(hexa.joints_of(np.full(6, noise_reach(sigma))) - hexa.joints_of(np.zeros(6)))
        #: the multi-start search's start configurations per ``(starts, seed)``: they depend on the
        #: hexapod alone, not on the readings (read-only; the last few kept)
        self._starts: dict[tuple[int, int], tuple[np.ndarray, ...]] = {}

    def find(
        self, readings: np.ndarray, reference: np.ndarray | None = None, starts: int = DEFAULT_STARTS, seed: int = 0
    ) -> Assemblies:
        """Every assembly found for ``readings`` (m, checked), nearest ``reference`` (4x4, default home) first."""
        if self.exact is not None:
            try:
                joints = self.hexa.joints_of(readings)
                poses = [s.pose for s in self.exact.solve_all(joints)]
            except WorkspaceError:  # two legs of a pair cannot meet: no assembly
                poses = []
            method, complete = "resultant", True
            near = [self.hexa.inverse(s.pose, check=False) for s in noise_assemblies(self.exact, joints, self.reach)]
        else:
            poses = self._search(readings, starts, seed)
            method, complete, near = f"multi-start ({starts} starts)", False, []
        inside: list[Solution] = []
        body = self.hexa.body
        for T in poses:
            sol = self.hexa.inverse(T, check=False)  # cone_limit or collision when the body check is on
            if sol.converged and np.max(np.abs(sol.lengths - readings)) <= 5e-9 * self.length:
                if body is None or body.within_envelope(sol.pose):
                    inside.append(sol)
        ref = self.hexa.home_pose if reference is None else reference
        inside.sort(key=lambda s: pose_distance(ref, s.pose, self.length))
        near = [s for s in near if s.converged and (body is None or body.within_envelope(s.pose))]  # as ``inside``
        near.sort(key=lambda s: pose_distance(ref, s.pose, self.length))
        return Assemblies(tuple(inside), len(poses) - len(inside), complete, method, tuple(near))

    def start_configurations(self, starts: int, seed: int) -> tuple[np.ndarray, ...]:
        """Home and the closed configurations of ``starts`` random poses (seeded by ``seed``): the search's starts.

        The poses lie within the stroke's span of home in position and ``SAMPLE_ANGLE`` in each
        angle; each is solved by inverse kinematics once per ``(starts, seed)`` and kept
        (read-only arrays).
        """
        key = (starts, seed)
        kept = self._starts.get(key)
        if kept is not None:
            return kept
        hexa = self.hexa
        rng = np.random.default_rng(seed)
        span = float(np.max(np.abs(hexa.stroke)))
        configurations = [hexa.closed_loop.q_home.copy()]
        for _ in range(starts):
            T = hexa.home_pose.copy()
            T[:3, 3] += rng.uniform(-span, span, 3)
            T[:3, :3] = T[:3, :3] @ rpy_to_matrix(*rng.uniform(-SAMPLE_ANGLE, SAMPLE_ANGLE, 3))
            start = hexa.inverse(T, check=False)
            if np.all(np.isfinite(start.q)) and start.closed:
                configurations.append(start.q.copy())
        for q in configurations:
            q.setflags(write=False)
        if len(self._starts) >= 4:  # a few seeds at a time: the others made again when asked
            self._starts.clear()
        self._starts[key] = kept = tuple(configurations)
        return kept

    def _search(self, readings: np.ndarray, starts: int, seed: int) -> list[np.ndarray]:
        """Poses of the distinct closed configurations plain Newton reaches from home and ``starts`` random poses."""
        hexa = self.hexa
        solver = hexa.solver(hexa.held_forward)
        pq = hexa.closed_loop.prismatic_q
        joints = hexa.joints_of(readings)
        found: list[np.ndarray] = []
        for q in self.start_configurations(starts, seed):
            q0 = q.copy()
            q0[pq] = joints
            q1, status = solver.run(q0, hexa.default_tol, 30)[:2]
            if status != "converged":
                continue
            T = hexa.pose_of(q1)
            if all(pose_distance(T, P, self.length) > SAME * self.length for P in found):
                found.append(T)
        return found


def review(
    finder: AssemblyFinder, sol: Solution, readings: np.ndarray, guess: object, *, settle: bool = False
) -> Solution:
    """A 3-6 hexapod's direct-kinematics result checked against every assembly (see the module doc).

    ``settle``: a warm failure (``sol`` not ``converged``) is judged too, however near the
    guess: its status is then the global answer's (the solve engine settles a warm workspace
    verdict so).
    """
    if finder.exact is None or sol.status == "invalid_input":
        return sol
    hexa, cold = finder.hexa, guess is None
    if not cold and sol.status != "converged" and not settle:
        return sol  # warm failures keep their own status (the tracker judges its passages)
    q_guess = None if cold else np.asarray(getattr(guess, "q", guess), dtype=float)
    near = q_guess is not None and np.max(np.abs(hexa.lengths_of(q_guess) - readings)) <= WARM_CHECK * finder.length
    if near and not settle:
        return sol
    reference = hexa.home_pose if q_guess is None else hexa.pose_of(q_guess)
    found = finder.find(readings, reference)
    within, length = found.solutions + found.near, finder.length
    same = SAME * length
    body = hexa.body
    if sol.status == "converged" and body is not None and not body.acceptable(sol):
        if not within:
            return sol  # no assembly the machine can take: the connected one, with its flags
        sol = _replace(sol, "not_found", sol.message, ())  # beyond a cone, in collision or outside the envelope
    if not within:
        if found.outside == 0:
            why = "the resultant polynomial of the 3-6 platform has no real root for these readings"
            return _replace(sol, "no_assembly", f"no real assembly: {why}", ("not_closed",) if not sol.closed else ())
        msg = f"all {found.outside} real assemblies for these readings lie outside {LIMITS}"
        return _replace(sol, "out_of_limits", msg, sol.flags if sol.status == "out_of_limits" else ("not_closed",))
    if sol.status == "converged":
        d = pose_distance(reference, sol.pose, length)
        rivals = [s for s in within if pose_distance(s.pose, sol.pose, length) > same]
        strict = cold and body is not None  # the machine's limits decide a cold answer, not a distance
        if not rivals or not strict and not any(pose_distance(reference, s.pose, length) <= MARGIN * d for s in rivals):
            return sol  # the only assembly, or (warm, or the body check off) clearly the one nearest the start
        first = [sol]
    else:  # the path was blocked; proven past the block (flag ``connected``), its end is the first candidate
        connected = "connected" in sol.flags
        first = [s for s in within if connected and pose_distance(s.pose, sol.pose, length) <= same][:1]
        if len(within) == 1:  # Newton missed it or could not certify it; it is the only one within the limits
            only = within[0]
            msg = f"the only assembly within {LIMITS} (resultant polynomial of the 3-6 platform)"
            return Solution(only.pose, only.q, only.lengths, "converged", sol.iterations, 0.0, only.jacobian, msg)
    ordered = first + [s for s in within if all(pose_distance(s.pose, f.pose, length) > same for f in first)]
    start = "home" if cold else "the guess"
    msg = (
        f"{len(ordered)} assemblies within {LIMITS} fit these readings (resultant polynomial "
        f"of the 3-6 platform){'' if cold and body else f', another as near {start} as {MARGIN:g} times the nearest'}; "
        + (f"the one connected to {start} is first" if first else f"none is certified as connected to {start}")
    )
    if sol.status == "ambiguous_assembly":
        msg = f"{sol.message}; {msg}"
    head = ordered[0]
    return Solution(
        head.pose,
        head.q,
        head.lengths,
        "ambiguous_assembly",
        sol.iterations,
        head.residual,
        head.jacobian,
        msg,
        ("connected",) if first else (),
        tuple(s.pose for s in ordered),
        sol.det_sign if first else 0,
    )


def _replace(sol: Solution, status: str, message: str, flags: tuple[str, ...]) -> Solution:
    """``sol`` with another status, message and flags."""
    return Solution(
        sol.pose, sol.q, sol.lengths, status, sol.iterations, sol.residual, sol.jacobian, message, flags, (), 0
    )
