"""What a Krawczyk proof of a warm step established (:class:`Proof`), apart from the prover.

:class:`~.solver.Solution` carries it; :mod:`.proof` computes it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar


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
            box about the result reuses the last one's Jacobian enclosure); 0 when the step
            lay in a region an earlier step proved (``in_region``).
        subdivisions: sub-intervals the proven path was split into (0 when not proven).
        in_region: the path was proven by the test of a **region**, a box of readings that holds
            the step's (built by this step or an earlier one of the same thread): one solution
            for every reading in it, in one box of the unknowns that holds the start
            (:func:`~hexapod_model.kinematics.newton.krawczyk.prove_region`).
    """

    proven: bool
    position_m: float
    rotation_rad: float
    tests: int
    subdivisions: int
    in_region: bool = False


_new = object.__new__
_set = object.__setattr__
_T = TypeVar("_T")


def built(cls: type[_T], fields: dict[str, object]) -> _T:
    """An instance of the frozen dataclass ``cls`` whose ``__dict__`` is ``fields`` (all of them, in order).

    ``cls(**fields)``, the same object, without ``__init__``'s frozen ``__setattr__`` per field:
    for the results of the hot paths (:func:`new_proof`, :func:`.outcomes.new_solution`).
    """
    obj = _new(cls)
    _set(obj, "__dict__", fields)
    return obj


def new_proof(
    proven: bool, position_m: float, rotation_rad: float, tests: int, subdivisions: int, in_region: bool = False
) -> Proof:
    """``Proof(...)``, the same object, built at half the frozen dataclass's ``__init__`` cost (one a warm step)."""
    fields: dict[str, object] = {"proven": proven, "position_m": position_m, "rotation_rad": rotation_rad}
    fields["tests"], fields["subdivisions"], fields["in_region"] = tests, subdivisions, in_region
    return built(Proof, fields)
