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
``MIN_STEP`` of the path (a fold: none goes through); a proven step lets the next one double,
up to ``MAX_STEP``. Consecutive steps share their end configuration (the end of one is the
start of the next), so the chain of proofs leads from the start's assembly to the end's: the
assembly connected to the start, which :mod:`.certificate` puts first among the candidates,
flagged ``connected``.
"""

from __future__ import annotations

import numpy as np

from .newton.proof import StepProver
from .newton.solver import NewtonSolver

FIRST_STEP = 1.0 / 64.0  # of the path: the first step tried
MAX_STEP = 1.0 / 16.0  # of the path: steps grow no longer than this
MIN_STEP = 2.0**-24  # of the path: a step this short that fails ends the attempt (a fold)
MAX_STEPS = 1000  # Newton solves tried along one path


def connected_end(
    solver: NewtonSolver, prover: StepProver, start: np.ndarray, joints: np.ndarray, tol: float, max_iter: int
) -> np.ndarray | None:
    """The end of the proven readings path from ``start`` to the prismatic values ``joints`` (m), or None.

    Args:
        solver: the direct-kinematics solver (the prismatic joints held).
        prover: the Krawczyk prover of the same model.
        start: URDF configuration closed at its own prismatic values (the path's ``l0``).
        joints: the six prismatic joint values at the path's end (m).
        tol: closure residual of each step's Newton solve.
        max_iter: Newton steps per step.

    Returns:
        The configuration (closed to ``tol``) the proven path ends at; None when a step could
        not be proven however short, or after ``MAX_STEPS`` solves.
    """
    pq = solver.clm.prismatic_q
    l0 = start[pq].copy()
    q, t, h = start.copy(), 0.0, FIRST_STEP
    for _ in range(MAX_STEPS):
        if t >= 1.0:
            return q
        tn = 1.0 if t + 1.2 * h >= 1.0 else t + h  # no sliver of a last step
        q0 = q.copy()
        q0[pq] = l0 + tn * (joints - l0)
        q1, status = solver.run(q0, tol, max_iter)[:2]
        if status == "converged" and prover.prove(q, q1).proven:
            q, t, h = q1, tn, min(2.0 * (tn - t), MAX_STEP)
        else:
            h = 0.5 * (tn - t)
            if h < MIN_STEP:
                return None
    return q if t >= 1.0 else None
