"""The step rules of the readings path (:mod:`.certificate`), shared by its Python and compiled followers.

Plain Python, so that :mod:`.certificate` imports no numba for a hexapod solved with the NumPy
kernels; :mod:`.follow` compiles :func:`rescale` for the compiled follower.
"""

from __future__ import annotations

from .solver import THETA_MAX

MIN_STEP = 1.0 / 1024  # smallest substep of the readings path before giving up
MAX_SUBSTEPS = 64
INTERMEDIATE_TOL = 1e-4  # closure residual (m, rad) of the substeps before the last one, times the length scale


def rescale(theta: float, accepted: bool, order: int) -> float:
    """Factor for the next substep after one with largest contraction ``theta``.

    The contraction grows like ``h ** order`` (1 from the last path point, 2 with a
    first-order predictor); the next substep aims at ``0.8 THETA_MAX``, at most doubles and
    at least halves after a rejection.
    """
    factor = (0.8 * THETA_MAX / theta) ** (1.0 / order) if theta > 0.0 else 2.0
    return min(2.0, max(0.5, factor)) if accepted else max(0.1, min(0.5, factor))
