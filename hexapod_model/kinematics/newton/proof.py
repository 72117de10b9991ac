"""The proof that a warm direct-kinematics step stayed on the start's assembly (:class:`Proof`).

:class:`StepProver` runs the compiled Krawczyk test of :mod:`.krawczyk` on the readings path
from a start configuration ``q0`` (a closed configuration, e.g. the previous sample's result) to
a result ``q1``: ``l(s) = l0 + s (l1 - l0)``, ``0 <= s <= 1``, ``l`` the held prismatic joints.
When it succeeds it is a **proof**, with every floating-point rounding bounded
(:mod:`.intervals`, :mod:`.enclosure`), that

* the closure equations have, for every ``s``, exactly one solution in each of a chain of boxes,
  which form one continuous path (no fold, no branch point, no other assembly met on the way);
* the path begins at the unique solution in a box that holds ``q0`` (the assembly ``q0`` closes
  to within its tolerance), and
* it ends at the unique exact solution for the readings ``l1`` within :attr:`Proof.position_m`
  (platform origin) and :attr:`Proof.rotation_rad` (platform orientation) of ``q1``.

Step after step, the per-leg test keeps its preconditioner (any matrix proves, a close inverse
of the Jacobian proves most): the thread's next test of a whole step close by tries the one it
holds before it builds its own (:func:`.krawczyk.prove_whole`).

A fixture at rest or moving slowly sends readings that hardly change: the per-leg test first
proves a **region** about a short step, a box of readings (about +-0.1 mm a reading on a model
of 0.15 m anchor radius, narrowed where that fails) with one solution for every reading in it
(:func:`.krawczyk.prove_region`). The next steps of the same thread whose readings lie in it
and whose start lies in its box of unknowns are proven by it: only the box about their result
is tested (:attr:`Proof.in_region`), at about a third of the cost of a step's own test.

The region and the preconditioner a thread holds are those of the last step it proved. A thread
that solves the steps of several streams in turn (the service's cycle, several fixtures of one
hexapod) gives each stream a :class:`ProofState` of its own (:meth:`StepProver.new_state`) and
makes it the thread's while it solves that stream's step (:meth:`StepProver.use`), as
:class:`~hexapod_model.tracking.tracker.Tracker` does: otherwise each step finds the region and
the preconditioner of another stream's pose, and proves itself afresh (and builds a region
again where the readings rest).

The numba kernels are imported by the first :class:`StepProver` (they compile on first use).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ...description.model import ClosedLoopModel
from .entries import direct, plain
from .first_compile import announce
from .legs import ChainTables
from .proven import Proof, new_proof
from .solver import Solution

__all__ = ["Proof", "ProofState", "StepProver", "attach_proof", "chart_coordinates", "with_proof"]


def chart_coordinates(T0: np.ndarray, T: np.ndarray) -> np.ndarray:
    """``v`` (6,) with ``T = T0 * Trans(v[:3]) * Rx(v[3]) Ry(v[4]) Rz(v[5])`` (m along ``T0``'s axes, rad)."""
    from .proof_kernel import chart_coordinates_into  # numba: compiled on first use

    v = np.empty(6)
    chart_coordinates_into(np.asarray(T0, dtype=float), np.asarray(T, dtype=float), v)
    return v


class ProofState:
    """The work arrays of one stream of proven steps: its region, its preconditioner, the scratch.

    Made by :meth:`StepProver.new_state` for the prover that uses it (:meth:`StepProver.use`);
    used by one thread at a time.
    """

    __slots__ = ("packed", "prover")

    def __init__(self, prover: StepProver, packed: tuple):
        self.prover, self.packed = prover, packed


class StepProver:
    """The Krawczyk proof of warm direct-kinematics steps of one closed-loop model.

    Args:
        clm: the model (every leg a chain of one-dof joints, one prismatic joint held per leg).
        tables: its :class:`.legs.ChainTables` (:meth:`of` reads them, or returns None).
    """

    @classmethod
    def of(cls, clm: ClosedLoopModel) -> StepProver | None:
        """The prover of ``clm``, or None when its legs are not chains :class:`.legs.ChainTables` reads."""
        tables = ChainTables.of(clm)
        return None if tables is None else cls(clm, tables)

    def __init__(self, clm: ClosedLoopModel, tables: ChainTables):
        from . import krawczyk, proof_kernel  # numba: compiled on first use

        self._kernel = proof_kernel
        self._entry: Callable | None = None  # the machine code of the first proof, called directly after it
        self._workspace = krawczyk.workspace
        self._held = krawczyk.HELD  # the work's row that notes a preconditioner held
        self._local = threading.local()  # the work arrays, one set per thread
        self.leg_q = tables.leg_q
        n = tables.leg_q.shape[1]
        held = np.array([list(tables.leg_q[i]).index(clm.prismatic_q[i]) for i in range(6)], dtype=np.int64)
        rows = 6 if clm.kind == "6d" else 3
        self.tables = (tables.placements, tables.motions, tables.closure, held, rows)
        self.free = np.array([[k for k in range(n) if k != held[i]] for i in range(6)], dtype=np.int64)
        self.held_q = np.asarray(clm.prismatic_q, dtype=np.int64)
        self.platform_q = int(clm.platform_q)
        self.home = tables.home
        self.nf = 6 * (n - 1) + 6
        # the unknowns' units: lengths (the free prismatic joints, the chart's translations) in a
        # length of the model (its largest anchor radius), so that boxes compare across scales
        length = float(np.max(np.linalg.norm(tables.closure[:, :3, 3], axis=1))) or 1.0
        lengths = [np.linalg.norm(tables.motions[i, k, :3]) > 0.5 for i in range(6) for k in self.free[i]]
        self.units = np.array([length if t else 1.0 for t in lengths] + [length] * 3 + [1.0] * 3)
        #: False: every step is proven by a test of its own, its bounds the step's alone: no region,
        #: no preconditioner kept from the thread's earlier proofs (see the module doc)
        self.regions = True

    def platform(self, q: np.ndarray) -> np.ndarray:
        """World placement (4, 4) of the platform joint at ``q`` (``home * X(q)``, as :mod:`.chains`)."""
        T = np.empty((4, 4))
        self._kernel.platform_placement(self.home, np.asarray(q, dtype=float), self.platform_q, T)
        return T

    def unknowns(self, q: np.ndarray, T0: np.ndarray) -> np.ndarray:
        """The Krawczyk unknowns of ``q``: the legs' free joints, then the chart coordinates about ``T0``."""
        x = np.empty(self.nf)
        q, T0 = np.asarray(q, dtype=float), np.asarray(T0, dtype=float)
        self._kernel.unknowns_into(q, T0, np.empty((4, 4)), self.home, self.platform_q, self.leg_q, self.free, x)
        return x

    def work(self) -> tuple:
        """The calling thread's work arrays: :func:`.krawczyk.workspace` and the path's ends.

        A caller that runs the kernels on them itself overwrites the region and the preconditioner
        they hold: both are dropped here.
        """
        work = self._packed()[0]
        work[1][7][0] = 0.0
        work[0][0][self._held][0] = 0.0
        return work

    def buffers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The calling thread's ``(floats, ints, spec)``: the buffers that :meth:`work` views."""
        return self._packed()[1]

    def new_state(self) -> ProofState:
        """Work arrays of a stream of steps of its own: no region, no preconditioner yet (see :meth:`use`)."""
        return ProofState(self, self._pack())

    def use(self, state: ProofState | None) -> ProofState | None:
        """Make ``state`` the calling thread's until the next call; returns the one it replaces.

        The proofs the thread runs meanwhile (:meth:`prove`, and every solve that proves through
        this prover) keep their region and preconditioner in ``state``. Hand the returned state
        back when the stream's step is done. None: the thread's own (a new one when it had none).

        Raises:
            ValueError: ``state`` was made by another prover (another model).
        """
        if state is not None and state.prover is not self:
            raise ValueError("this proof state was made by the prover of another model: make one with new_state()")
        previous = getattr(self._local, "state", None)
        self._local.state = state
        return previous

    def _packed(self) -> tuple:
        """The calling thread's ``((work, ends), (floats, ints, spec))``: the arrays, and the buffers they view."""
        state = getattr(self._local, "state", None)
        if state is None:
            state = self._local.state = self.new_state()
        return state.packed

    def _pack(self) -> tuple:
        """New ``((work, ends), (floats, ints, spec))``: the arrays, and the buffers they view."""
        nf = self.nf
        # the path's ends (the readings at the end: NaN until a step was proven, then its own, the
        # readings' motion to the next); a proven region's chart origin and its state (held, width
        # scale, steps before a try, whether the last step lay in it)
        path = (np.zeros((4, 4)), np.zeros((4, 4)), np.zeros(nf), np.zeros(nf), np.zeros(6), np.full(6, np.nan))
        ends = (*path, np.zeros((4, 4)), np.array([0.0, 1.0, 0.0, 0.0]))
        V, Jm, Jr, Y, H, blocks, ew = self._workspace(self.nf, self.tables[4])
        placements, motions, closure, held, _ = self.tables
        model = (placements, motions, closure, held, self.home, self.leg_q, self.free, self.held_q)
        floats, ints, spec, views = self._kernel.pack((V, Jm, Jr, Y, H, *blocks, *ew, *ends, *model))
        views[0][21] = self.units
        work = (*views[:5], tuple(views[5:21]), tuple(views[21:27]))
        return (work, tuple(views[27:35])), (floats, ints, spec)

    def prove(self, q0: np.ndarray, q1: np.ndarray, structured: bool = True, subdivide: bool = True) -> Proof:
        """The proof of the readings path from ``q0`` (closed) to the result ``q1`` (see the module doc).

        Args:
            q0: the start configuration (closed).
            q1: the result.
            structured: the Krawczyk test leg by leg (:mod:`.krawczyk_blocks`); False runs the
                dense 36 x 36 reference test (the same proof at several times the cost).
            subdivide: when one test of the whole path fails, halve the path into sub-intervals
                (:func:`.krawczyk.prove_path`, at most 32 tests); False: one test only (a caller
                that shortens the step itself).
        """
        (work, ends), (floats, ints, spec) = self._packed()
        state = ends[7]
        if not self.regions:  # no region held, none tried; the preconditioner built afresh
            state[0], state[2] = 0.0, np.inf
            work[0][self._held][0] = 0.0
        elif state[2] == np.inf:
            state[2] = 0.0
        # one compiled signature (.entries.plain): a strided, read-only or float32 configuration (a
        # column, a row of a Fortran array) would compile the proof again, unannounced: a minute and more
        args = (
            floats,
            ints,
            spec,
            self.tables[4],
            self.platform_q,
            plain(q0),
            plain(q1),
            bool(structured),
            bool(subdivide),
        )
        if self._entry is None:
            kernel = self._kernel.prove_packed
            announce(kernel)
            proven, tests, position, rotation, parts = kernel(*args)
            self._entry = direct(kernel, args)  # the same types on every later call
        else:
            proven, tests, position, rotation, parts = self._entry(*args)
        in_region = bool(proven) and bool(state[3] > 0.0)
        return new_proof(bool(proven), float(position), float(rotation), int(tests), int(parts), in_region)


def attach_proof(sol: Solution, proof: Proof) -> Solution:
    """``sol`` carrying ``proof``; a ``converged`` result whose proof failed becomes ``uncertified``."""
    if proof.proven or sol.status != "converged":
        return replace(sol, proof=proof)
    why = f"the Krawczyk proof of the readings path from the guess failed ({proof.tests} tests)"
    message = f"{sol.message}; {why}" if sol.message else why
    return replace(sol, status="uncertified", message=message, proof=proof)


def with_proof(prover: StepProver | None, q0: np.ndarray, sol: Solution) -> Solution:
    """``sol`` carrying the proof of its readings path from ``q0``; ``uncertified`` if ``converged`` and not proven.

    A result that does not close (any status but ``converged`` and ``uncertified``), or a model
    without a prover, gets a proof that was not run (``tests`` 0): not proven.
    """
    if prover is None or sol.status not in ("converged", "uncertified"):
        return replace(sol, proof=Proof(False, np.inf, np.inf, 0, 0))
    return attach_proof(sol, prover.prove(np.asarray(q0, dtype=float), sol.q))
