"""A tracked sample of a hexapod with redundant sensors: the six legs tracked, then every reading solved.

A hexapod whose geometry declares measuring legs or an inclinometer
(:mod:`hexapod_model.kinematics.redundant`) gives the tracker all its readings, in the order of
:attr:`hexapod_model.Hexapod.reading_names`. The six legs' readings go through the tracker's
usual step (motion model, ``jump``/``stuck``, branch check, the certified six-leg solve, the
history); from that solution :meth:`hexapod_model.Hexapod.forward` solves all the readings:

* consistent readings: the sample's :attr:`~hexapod_model.tracking.types.TrackResult.solution`
  is their weighted least-squares
  :class:`~hexapod_model.kinematics.redundant.RedundantSolution` (its ``consistency`` holds the
  test), with the six-leg step's flags;
* readings failing the consistency test: the flag ``inconsistent_readings`` is added; the
  solution is the least-squares pose of all readings, or, when the data name the faulty reading
  (``solution.consistency.isolated``), that of the others, flagged ``estimate`` in
  ``solution.flags``;
* a least-squares solve that fails (Gauss-Newton leaves the workspace or does not converge):
  no pose, the failure's status.

The six-leg history stays the six legs' (the motion model predicts their readings); the
uncertainty (``sigma_translation``, ``sigma_rotation``) is the six legs': more readings only
shrink it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from ..exceptions import HexapodError
from ..kinematics.hexapod import Hexapod
from .types import TrackResult

INCONSISTENT = "inconsistent_readings"


def step_with_extra_readings(
    hexa: Hexapod, readings, six_step: Callable[[np.ndarray], TrackResult], tol: float, max_iter: int
) -> TrackResult:
    """Track the six legs of ``readings`` with ``six_step``, then solve every reading (module doc).

    Args:
        hexa: a hexapod with redundant sensors.
        readings: its ``m`` readings (m for legs, rad for tilts), reading order; NaN or a wrong
            count: an unreadable sample.
        six_step: the tracker's step of six leg readings.
        tol: the tracker's solve tolerance.
        max_iter: its iteration limit.
    """
    names = hexa.reading_names
    m = len(names)
    try:
        z = np.asarray(readings, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        z = np.full(0, np.nan)
    if z.shape != (m,) or not np.all(np.isfinite(z)):
        r = six_step(np.full(6, np.nan))  # one unreadable sample for the motion model
        why = f"expected {m} finite readings ({', '.join(names)}), got {readings!r}"
        return dataclasses.replace(r, solution=dataclasses.replace(r.solution, message=why))
    r = six_step(z[:6].copy())
    if r.failed:
        return r
    try:
        sol = hexa.forward(z, guess=r.solution, tol=tol, max_iter=max_iter, check=False)
    except HexapodError as exc:  # an extra reading outside its stroke
        bad = dataclasses.replace(r.solution, status="invalid_input", message=str(exc))
        return dataclasses.replace(r, solution=bad, status="invalid_input")
    if sol.status == "converged":
        return dataclasses.replace(r, solution=sol)
    if sol.status == INCONSISTENT:
        return dataclasses.replace(r, solution=sol, flags=(*r.flags, INCONSISTENT))
    return dataclasses.replace(r, solution=sol, status=sol.status)
