"""What a Krawczyk proof of a warm step established (:class:`Proof`), apart from the prover.

:class:`~.solver.Solution` carries it; :mod:`.proof` computes it.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Proof:
    """What the Krawczyk test proved about a warm step (:mod:`hexapod_model.kinematics.newton.proof`).

    Attributes:
        proven: True when the readings path from the start to the result was proven to stay
            on one assembly, ending within the bounds below of the returned pose.
        position_m: bound of the distance (m) between the returned platform origin and the
            exact one the path ends at (``inf`` when not proven).
        rotation_rad: bound of the rotation angle (rad) between the returned platform
            orientation and the exact one (``inf`` when not proven).
        tests: Krawczyk tests of the readings path run (one per sub-interval tried; the final
            box about the result reuses the last one's Jacobian enclosure).
        subdivisions: sub-intervals the proven path was split into (0 when not proven).
    """

    proven: bool
    position_m: float
    rotation_rad: float
    tests: int
    subdivisions: int
