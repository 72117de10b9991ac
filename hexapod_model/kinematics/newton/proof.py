"""The proof that a warm direct-kinematics step stayed on the start's assembly (:class:`Proof`).

:class:`StepProver` runs the compiled Krawczyk test of :mod:`.krawczyk` on the readings path
from a start configuration ``q0`` (a closed configuration, e.g. the previous sample's result) to
a result ``q1``: ``l(s) = l0 + s (l1 - l0)``, ``0 <= s <= 1``, ``l`` the held prismatic joints.
When it succeeds it is a **proof**, with every floating-point rounding bounded
(:mod:`.intervals`), that

* the closure equations have, for every ``s``, exactly one solution in each of a chain of boxes,
  which form one continuous path (no fold, no branch point, no other assembly met on the way);
* the path begins at the unique solution in a box that holds ``q0`` (the assembly ``q0`` closes
  to within its tolerance), and
* it ends at the unique exact solution for the readings ``l1`` within :attr:`Proof.position_m`
  (platform origin) and :attr:`Proof.rotation_rad` (platform orientation) of ``q1``.

The numba kernels are imported by the first :class:`StepProver` (they compile on first use).
"""

from __future__ import annotations

import threading
from dataclasses import replace

import numpy as np

from ...description.model import ClosedLoopModel
from .first_compile import announce
from .legs import ChainTables
from .proven import Proof
from .solver import Solution

__all__ = ["Proof", "StepProver", "chart_coordinates", "with_proof"]


def chart_coordinates(T0: np.ndarray, T: np.ndarray) -> np.ndarray:
    """``v`` (6,) with ``T = T0 * Trans(v[:3]) * Rx(v[3]) Ry(v[4]) Rz(v[5])`` (m along ``T0``'s axes, rad)."""
    R0 = T0[:3, :3]
    M = R0.T @ T[:3, :3]
    b = np.arcsin(np.clip(M[0, 2], -1.0, 1.0))
    a = np.arctan2(-M[1, 2], M[2, 2])
    c = np.arctan2(-M[0, 1], M[0, 0])
    return np.concatenate([R0.T @ (T[:3, 3] - T0[:3, 3]), [a, b, c]])


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
        from . import krawczyk  # numba: compiled on first use

        self._prove = krawczyk.prove_path
        self._workspace = krawczyk.workspace
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

    def platform(self, q: np.ndarray) -> np.ndarray:
        """World placement (4, 4) of the platform joint at ``q`` (``home * X(q)``, as :mod:`.chains`)."""
        x = q[self.platform_q : self.platform_q + 7]
        qx, qy, qz, qw = x[3], x[4], x[5], x[6]
        X = np.eye(4)
        X[:3, :3] = [
            [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
            [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
            [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
        ]
        X[:3, 3] = x[:3]
        return self.home @ X

    def unknowns(self, q: np.ndarray, T0: np.ndarray) -> np.ndarray:
        """The Krawczyk unknowns of ``q``: the legs' free joints, then the chart coordinates about ``T0``."""
        legs = q[self.leg_q[np.arange(6)[:, None], self.free]].ravel()
        return np.concatenate([legs, chart_coordinates(T0, self.platform(q))])

    def work(self, nf: int) -> tuple:
        """The calling thread's work arrays of :func:`.krawczyk.prove_path` for ``nf`` unknowns."""
        work = getattr(self._local, "work", None)
        if work is None:
            work = self._local.work = self._workspace(nf, self.tables[4])
        return work

    def prove(self, q0: np.ndarray, q1: np.ndarray, structured: bool = True) -> Proof:
        """The proof of the readings path from ``q0`` (closed) to the result ``q1`` (see the module doc).

        Args:
            q0: the start configuration (closed).
            q1: the result.
            structured: the Krawczyk test leg by leg (:mod:`.krawczyk_blocks`); False runs the
                dense 36 x 36 reference test (same proof, several times the cost).
        """
        T0 = self.platform(q1)
        x0, x1 = self.unknowns(q0, T0), self.unknowns(q1, T0)
        l0, l1 = q0[self.held_q].astype(float), q1[self.held_q].astype(float)
        if not (np.all(np.isfinite(x0)) and np.all(np.isfinite(x1)) and np.all(np.isfinite(l0 + l1))):
            return Proof(False, np.inf, np.inf, 0, 0)
        announce(self._prove)
        proven, tests, radius, parts = self._prove(self.tables, T0, x0, x1, l0, l1, structured, self.work(x0.size))
        if not proven:
            return Proof(False, np.inf, np.inf, int(tests), 0)
        r = radius[-6:]
        slack = 1e-15  # the chart coordinates of q1 itself, computed in floating point
        position = float(np.sqrt(r[0] ** 2 + r[1] ** 2 + r[2] ** 2) * (1.0 + 1e-12)) + slack
        rotation = float((r[3] + r[4] + r[5]) * (1.0 + 1e-12)) + slack
        return Proof(True, position, rotation, int(tests), int(parts))


def with_proof(prover: StepProver | None, q0: np.ndarray, sol: Solution) -> Solution:
    """``sol`` carrying the proof of its readings path from ``q0``; ``uncertified`` if ``converged`` and not proven.

    A result that does not close (any status but ``converged`` and ``uncertified``), or a model
    without a prover, gets a proof that was not run (``tests`` 0): not proven.
    """
    if prover is None or sol.status not in ("converged", "uncertified"):
        return replace(sol, proof=Proof(False, np.inf, np.inf, 0, 0))
    proof = prover.prove(np.asarray(q0, dtype=float), sol.q)
    if proof.proven or sol.status != "converged":
        return replace(sol, proof=proof)
    why = f"the Krawczyk proof of the readings path from the guess failed ({proof.tests} tests)"
    message = f"{sol.message}; {why}" if sol.message else why
    return replace(sol, status="uncertified", message=message, proof=proof)
