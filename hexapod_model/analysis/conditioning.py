"""Why the reduced closure formulation has the lower condition number (Fig. 7 of Bem, Ude and Nemec 2026).

Per leg, the full formulation (eq. 6) has 9 rotation-matrix rows ``d(R_tip - R_anchor)``; the
reduced one (eq. 14) has 3 rotation-error rows ``d vex(skew(R_tip R_anchor^T))``. For a
rotation ``w``, ``|[w] R|_F = sqrt(2) |w|``: at a closed configuration the 9 rows carry the same
information as the 3, weighted by ``sqrt(2)`` (``J9^T J9 = 2 J3^T J3``). The translation rows
are the same in both. So the two formulations differ in how rotation rows are weighted
against translation rows, which is also what changing the length unit does.

:func:`condition_numbers` measures, at solved configurations, the 2-norm condition number of
both Jacobians (free joints of direct kinematics as columns) under four row/column scalings:

* ``si``: the paper's definition (eq. 25), metres and radians;
* ``mm``: lengths in millimetres (translation rows x 1000, platform translation columns / 1000);
* ``rotation_rows_over_sqrt2``: the full formulation's rotation rows divided by ``sqrt(2)``
  (the reduced one unchanged): the same metric on both;
* ``unit_rows``: every row scaled to unit norm (row equilibration).
"""

from __future__ import annotations

import numpy as np

from ..kinematics.hexapod import Hexapod
from .full_formulation import ForwardComparison

SCALINGS = ("si", "mm", "rotation_rows_over_sqrt2", "unit_rows")


def _cond(J: np.ndarray) -> float:
    s = np.linalg.svd(J, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def condition_numbers(hexa: Hexapod, readings: np.ndarray) -> dict:
    """Mean condition numbers of the full and reduced Jacobians at the solutions of ``readings``.

    Returns ``{scaling: {"full": mean, "reduced": mean}}`` for :data:`SCALINGS` (see the module
    doc), ``"poses"`` (how many rows were solved) and ``"gram_difference"``: the largest
    relative difference between ``J9^T J9`` and ``2 J3^T J3`` over all legs and poses. Only
    for 6-D (cardan) closures.
    """
    fc = ForwardComparison(hexa)
    clm = hexa.closed_loop
    trans_cols = np.isin(fc.full.free_v, np.arange(clm.platform_v, clm.platform_v + 3))
    full_t = np.tile(np.r_[np.zeros(9, bool), np.ones(3, bool)], 6)  # translation rows of each form
    red_t = np.tile(np.r_[np.ones(3, bool), np.zeros(3, bool)], 6)
    values: dict[str, dict[str, list[float]]] = {k: {"full": [], "reduced": []} for k in SCALINGS}
    gram = 0.0
    for r in readings:
        sol = hexa.forward(r, check=False)
        if not sol.converged:
            continue
        G = {"full": fc.full.evaluate(sol.q)[1], "reduced": fc.reduced.evaluate(sol.q)[1]}
        for key, t in (("full", full_t), ("reduced", red_t)):
            J = G[key]
            values["si"][key].append(_cond(J))
            mm = J.copy()
            mm[t] *= 1e3
            mm[:, trans_cols] *= 1e-3
            values["mm"][key].append(_cond(mm))
            same = J.copy()
            if key == "full":
                same[~t] /= np.sqrt(2.0)
            values["rotation_rows_over_sqrt2"][key].append(_cond(same))
            values["unit_rows"][key].append(_cond(J / np.linalg.norm(J, axis=1, keepdims=True)))
        for i in range(6):
            J9, J3 = G["full"][12 * i : 12 * i + 9], G["reduced"][6 * i + 3 : 6 * i + 6]
            A, B = J9.T @ J9, 2.0 * J3.T @ J3
            gram = max(gram, float(np.abs(A - B).max() / np.abs(A).max()))
    out: dict = {k: {f: float(np.mean(v[f])) for f in v} for k, v in values.items()}
    out["poses"] = len(values["si"]["full"])
    out["gram_difference"] = gram
    return out
