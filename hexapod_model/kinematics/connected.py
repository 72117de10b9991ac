"""The assembly connected to the start past a blocked readings path, each step proven.

:func:`.certificate.solve_forward` follows the readings path ``l(t) = l0 + t (l - l0)`` from the
start in substeps its contraction and determinant checks accept; near a singularity they
refuse (the Newton balls shrink) and the result is ``ambiguous_assembly``. The path may still
go on: it is blocked only at a fold of the readings map, where two assemblies meet and no
continuous path of solutions goes through.

:func:`connected_end` follows it again from the start, in plain Newton steps along the path,
and accepts a step only with the Krawczyk proof of :class:`.newton.proof.StepProver`: the
solutions for the readings between the step's ends form one continuous path in boxes where
each is unique, from the assembly of the step's start to the exact solution next to its end
(within about 1e-10 m). A step whose Newton solve or proof fails is halved, down to
``MIN_STEP`` of the path (a fold: none goes through). A proven step sets the next one's length
from the sub-intervals its proof split the readings path into (:func:`.krawczyk.prove_path`),
aiming at ``TARGET_PARTS``: at most twice and at least half as long, up to ``MAX_STEP``. Both
extremes cost more: a step longer than its proof reaches fails after ``MAX_TESTS`` tests
(:mod:`.newton.krawczyk`) and is tried again at half the length, and a step that one test
proves costs a Newton solve and two enclosures (the path's and its end's) for a short piece
of the path; about six sub-intervals a step took the fewest tests along the presets' paths
(``benchmarks/certificate.py``, far guesses). Consecutive steps share
their end configuration (the end of one is the start of the next), so the chain of proofs
leads from the start's assembly to the end's: the assembly connected to the start, which
:mod:`.certificate` puts first among the candidates, flagged ``connected``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .newton.proof import StepProver
from .newton.solver import NewtonSolver

FIRST_STEP = 1.0 / 64.0  # of the path: the first step tried
MAX_STEP = 1.0 / 4.0  # of the path: steps grow no longer than this
TARGET_PARTS = 6  # sub-intervals of the readings path a step's proof aims at (the next step's length)
MIN_STEP = 2.0**-24  # of the path: a step this short that fails ends the attempt (a fold)
MAX_STEPS = 1000  # Newton solves tried along one path


class Chain(NamedTuple):
    """A readings path followed in proven steps (:func:`connected_chain`)."""

    before: np.ndarray  #: the last proven step's start (closed, connected to the path's start)
    end: np.ndarray  #: the configuration the proven path ends at (closed to the solves' tolerance)
    steps: int  #: proven steps
    tests: int  #: Krawczyk tests run, the failed steps' included


def connected_chain(
    solver: NewtonSolver,
    prover: StepProver,
    start: np.ndarray,
    joints: np.ndarray,
    tol: float,
    max_iter: int,
    min_step: float = MIN_STEP,
    max_steps: int = MAX_STEPS,
) -> Chain | None:
    """The readings path from ``start`` to the prismatic values ``joints`` (m), followed in proven steps.

    Args:
        solver: the direct-kinematics solver (the prismatic joints held).
        prover: the Krawczyk prover of the same model.
        start: URDF configuration closed at its own prismatic values (the path's ``l0``).
        joints: the six prismatic joint values at the path's end (m).
        tol: closure residual of each step's Newton solve.
        max_iter: Newton steps per step.
        min_step: shortest step tried, as a fraction of the path (a step this short that fails
            ends the attempt: a fold).
        max_steps: Newton solves tried along the path.

    Returns:
        The :class:`Chain` whose ``end`` the proven path ends at; None when a step could not be
        proven however short, or after ``max_steps`` solves.
    """
    pq = solver.clm.prismatic_q
    l0 = start[pq].copy()
    q, before, t, h = start.copy(), start, 0.0, FIRST_STEP
    steps = tests = 0
    for _ in range(max_steps):
        if t >= 1.0:
            return Chain(before, q, steps, tests)
        tn = 1.0 if t + 1.2 * h >= 1.0 else t + h  # no sliver of a last step
        q0 = q.copy()
        q0[pq] = l0 + tn * (joints - l0)
        q1, status = solver.run(q0, tol, max_iter)[:2]
        proof = prover.prove(q, q1) if status == "converged" else None
        tests += 0 if proof is None else proof.tests
        if proof is not None and proof.proven:  # the next step's proof aims at TARGET_PARTS sub-intervals
            grow = min(2.0, max(0.5, TARGET_PARTS / max(proof.subdivisions, 1)))
            before, q, t, h = q, q1, tn, min(max(grow * (tn - t), min_step), MAX_STEP)
            steps += 1
        else:
            h = 0.5 * (tn - t)
            if h < min_step:
                return None
    return Chain(before, q, steps, tests) if t >= 1.0 else None


def connected_end(
    solver: NewtonSolver, prover: StepProver, start: np.ndarray, joints: np.ndarray, tol: float, max_iter: int
) -> np.ndarray | None:
    """The end of the proven readings path from ``start`` to the prismatic values ``joints`` (m), or None.

    :func:`connected_chain` with its default limits: the configuration (closed to ``tol``) the
    proven path ends at; None when a step could not be proven however short, or after
    ``MAX_STEPS`` solves.
    """
    chain = connected_chain(solver, prover, start, joints, tol, max_iter)
    return None if chain is None else chain.end
