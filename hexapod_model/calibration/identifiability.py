"""Which parameter combinations a set of measured poses determines, and which must stay nominal.

Work in the *scaled* parameters ``y = delta / scale`` (each parameter in units of its expected
magnitude, :data:`~hexapod_model.calibration.parameters.SCALES`) and the whitened
residuals (units of the stated noise). Then, with the measuring and marker frames estimated
too (their columns projected out), a combination ``y = N v`` (unit ``v``) that the Jacobian
maps with singular value ``s`` has a 1-sigma uncertainty of ``1 / s`` times the expected
magnitude of its parameters.

* The 12 *gauge* combinations (a rigid motion of all base-side or all platform-side joints,
  indistinguishable from another measuring or marker frame) are fixed by convention:
  ``ParameterSet.gauge_constraints`` (the centres' corrections have no mean translation or
  rotation). ``N`` spans the corrections that satisfy them.
* A combination whose 1-sigma would exceed ``max_sigma`` expected magnitudes (or whose
  singular value is zero to rounding) is *unidentifiable*. For ``w`` such combinations, the
  ``w`` parameters that best span them (QR with column pivoting, the classic subset
  selection) are held at nominal, and the analysis repeats until every remaining combination
  is determined. The held parameters are never reported as identified.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import null_space, qr

RANK_TOL = 1e-9  # relative singular value below which a combination is zero to rounding


@dataclass(frozen=True)
class Combination:
    """A parameter combination the data cannot determine.

    Attributes:
        sigma: the held parameter's 1-sigma if it were identified with the others still free,
            in expected magnitudes (``inf`` when the data do not see it at all; 0 for a
            parameter the frame convention pins once the others are held).
        terms: ``(name, coefficient)``: the held parameter (coefficient 1) and the other
            parameters that move with it (scaled, largest first; none of the other held ones).
        held: the parameter held at nominal because of it.
    """

    sigma: float
    terms: tuple[tuple[str, float], ...]
    held: str

    def describe(self) -> str:
        """One line: the combination, its 1-sigma and what is held."""
        if self.sigma == 0.0:
            return f"{self.held}: fixed at nominal by the frame convention once the parameters above are held"
        combo = " ".join(f"{c:+.2f} {n}" for n, c in self.terms)
        size = "not seen by the data" if not np.isfinite(self.sigma) else f"1-sigma {self.sigma:.3g} x its tolerance"
        return f"{combo} ({size}): {self.held} held at nominal"


@dataclass(frozen=True)
class Identifiability:
    """Result of :func:`analyse`.

    Attributes:
        held: indices of the parameters held at nominal (asked for or unidentifiable).
        combinations: the unidentifiable combinations found, in the order they were held.
        basis: (P, n) orthonormal basis of the free scaled corrections (gauge fixed, held zero).
        spectrum: singular values of the scaled Jacobian with only the gauge fixed, descending.
    """

    held: tuple[int, ...]
    combinations: tuple[Combination, ...]
    basis: np.ndarray
    spectrum: np.ndarray


def frame_free(J_geometry: np.ndarray, J_frames: np.ndarray) -> np.ndarray:
    """``J_geometry`` with the span of ``J_frames`` projected out (the frames estimated too)."""
    Q, _ = np.linalg.qr(J_frames)
    return J_geometry - Q @ (Q.T @ J_geometry)


def free_basis(constraints: np.ndarray, held: list[int] | tuple[int, ...], size: int) -> np.ndarray:
    """Orthonormal basis of the scaled corrections with ``constraints @ y = 0`` and ``y[held] = 0``."""
    rows = [constraints] + [np.eye(size)[list(held)]] if held else [constraints]
    return null_space(np.vstack(rows))


def analyse(
    J_geometry: np.ndarray,
    J_frames: np.ndarray,
    constraints: np.ndarray,
    names: tuple[str, ...],
    max_sigma: float = 1.0,
    held: tuple[int, ...] = (),
) -> Identifiability:
    """Find the combinations the data cannot determine and hold a parameter for each.

    Args:
        J_geometry: (m, P) whitened residual derivative w.r.t. the *scaled* corrections.
        J_frames: (m, 12) whitened residual derivative w.r.t. the frame twists.
        constraints: (12, P) gauge constraints on the scaled corrections.
        names: the P parameter names.
        max_sigma: largest 1-sigma (in expected magnitudes) of an identified combination.
        held: parameters held at nominal from the start (asked for by the user).
    """
    size = J_geometry.shape[1]
    J = np.linalg.qr(frame_free(J_geometry, J_frames), mode="r")  # same singular values, P rows
    base = free_basis(constraints, held, size)
    spectrum = np.linalg.svd(J @ base, compute_uv=False)
    held_now, combos = list(held), []
    basis = base
    while basis.shape[1]:
        _, s, Vt = np.linalg.svd(J @ basis, full_matrices=False)
        weak = np.flatnonzero((s * max_sigma < 1.0) | (s <= RANK_TOL * max(s[0], 1e-300)))[::-1]  # weakest first
        if weak.size == 0:
            break
        Y = basis @ Vt[weak].T  # (P, w) the weak combinations, scaled parameters
        Y[held_now] = 0.0
        # the w parameters that best span the weak combinations (QR with column pivoting) ...
        pivots = [int(k) for k in qr(Y.T, pivoting=True, mode="r")[1][: weak.size]]
        # ... and the combinations rewritten with coefficient 1 on one of them, 0 on the others
        Y = Y @ np.linalg.inv(Y[pivots])
        coef = basis @ Vt.T  # parameter k's 1-sigma with all free: sqrt(sum_j (coef[k, j] / s_j)^2)
        null = s <= RANK_TOL * max(s[0], 1e-300)
        for j, k in enumerate(pivots):
            y = Y[:, j]
            unseen = bool(np.any(np.abs(coef[k, null]) > 1e-9))
            # seen: over the directions the data see (k has no part in the null ones, whose s is 0 to rounding)
            sigma = float("inf") if unseen else float(np.sqrt(np.sum((coef[k, ~null] / s[~null]) ** 2)))
            others = [m for m in np.argsort(-np.abs(y)) if abs(y[m]) >= 0.1 and m not in pivots][:5]
            terms = ((names[k], 1.0),) + tuple((names[m], float(y[m])) for m in others)
            combos.append(Combination(sigma, terms, names[k]))
        held_now += pivots
        basis = free_basis(constraints, held_now, size)
    for pinned in np.flatnonzero(np.linalg.norm(basis, axis=1) < 1e-9).tolist():  # by the gauge and the holds
        if pinned not in held_now:
            held_now.append(pinned)
            combos.append(Combination(0.0, ((names[pinned], 1.0),), names[pinned]))
    return Identifiability(tuple(held_now), tuple(combos), basis, spectrum)
