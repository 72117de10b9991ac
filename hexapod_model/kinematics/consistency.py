"""The consistency test of over-determined readings: chi-square, isolation, the smallest detectable fault.

With ``m`` readings of standard deviation ``sigma_j`` and 6 pose coordinates, the weighted
least-squares pose leaves the normalised residual ``r_j = (z_j - h_j(pose)) / sigma_j``;
for independent Gaussian noise and a right model its statistic ``chi2 = sum r_j^2`` is
chi-square distributed with ``dof = m - 6`` degrees of freedom. The test rejects a set of
readings when ``chi2 > chi2.ppf(1 - alpha, dof)``: clean sets fail it at the rate ``alpha``
(the false-alarm rate).

Linearised at the solution (``A``: the whitened Jacobian ``dh/dpose / sigma``, ``m x 6``), the
residual is ``r = P e`` with ``P = I - A (A^T A)^-1 A^T`` the parity projector and ``e`` the
whitened errors. A bias ``b`` on reading ``j`` shifts the statistic's mean by the
non-centrality ``(b / sigma_j)^2 P_jj``; the **minimal detectable bias** (Baarda) of reading
``j`` is ``sigma_j sqrt(lambda0 / P_jj)``, ``lambda0`` the non-centrality that the test
detects with probability ``power`` at false-alarm rate ``alpha``. ``P_jj = 0``: a fault on
reading ``j`` cannot be seen at all.

**Isolation.** Leaving reading ``j`` out removes exactly the part of the statistic a bias on
``j`` explains: ``chi2_j = chi2 - r_j^2 / P_jj`` with ``dof - 1`` degrees of freedom. A single
faulty reading is the one whose exclusion restores consistency; with one redundant
measurement (``dof = 1``) every exclusion leaves ``chi2_j = 0`` (the parity space is one
line, each fault moves the single parity residual only by its own gain), so the data name
the set of readings the fault may be on, not one of them. With ``dof >= 2`` the residual is a
vector and each reading's fault moves it along its own direction ``P e_j``: the fault is
named when exactly one exclusion passes the test.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

DEFAULT_ALPHA = 1e-3  # false-alarm rate of the consistency test
DEFAULT_POWER = 0.8  # detection probability of the minimal detectable bias
OBSERVABLE = 1e-9  # P_jj below this: a fault on reading j leaves no trace in the residual


@functools.cache
def threshold(alpha: float, dof: int) -> float:
    """The chi-square test's bound ``chi2.ppf(1 - alpha, dof)`` (0 for ``dof = 0``).

    ``scipy.special.chdtri``, the function behind ``scipy.stats.chi2.isf``: the same number, at
    a fifth of the import (the first redundant solve of a process pays it).
    """
    from scipy.special import chdtri

    return float(chdtri(dof, alpha)) if dof > 0 else 0.0


@functools.cache
def noncentrality(alpha: float, power: float, dof: int) -> float:
    """The non-centrality ``lambda0`` that the test at ``alpha`` detects with probability ``power``."""
    from scipy.optimize import brentq
    from scipy.stats import ncx2

    bound = threshold(alpha, dof)
    return float(brentq(lambda lam: ncx2.sf(bound, dof, lam) - power, 1e-9, 1e4, xtol=1e-12))


def parity_diagonal(A: np.ndarray) -> np.ndarray:
    """Diagonal of the parity projector ``I - A (A^T A)^-1 A^T`` of the whitened ``m x 6`` Jacobian ``A``."""
    Q, _ = np.linalg.qr(A)
    return np.clip(1.0 - np.sum(Q * Q, axis=1), 0.0, 1.0)


def minimal_detectable_bias(
    A: np.ndarray, sigmas: np.ndarray, alpha: float = DEFAULT_ALPHA, power: float = DEFAULT_POWER
) -> np.ndarray:
    """Smallest bias on each reading the test detects with probability ``power`` (reading units; inf: none).

    Args:
        A: ``m x 6`` whitened Jacobian (``dh/dpose`` divided row-wise by ``sigmas``).
        sigmas: (m,) standard deviations of the readings (m or rad).
        alpha: false-alarm rate of the test.
        power: detection probability.
    """
    dof = A.shape[0] - A.shape[1]
    if dof <= 0:
        return np.full(A.shape[0], np.inf)
    return _detectable(parity_diagonal(A), sigmas, alpha, power, dof)


def _detectable(p: np.ndarray, sigmas: np.ndarray, alpha: float, power: float, dof: int) -> np.ndarray:
    """:func:`minimal_detectable_bias` from the parity diagonal ``p`` (``dof > 0``)."""
    lam = noncentrality(alpha, power, dof)
    with np.errstate(divide="ignore"):
        return np.where(p > OBSERVABLE, np.asarray(sigmas) * np.sqrt(lam / np.maximum(p, OBSERVABLE)), np.inf)


@dataclass(frozen=True)
class Consistency:
    """The consistency test of one redundant solve (see the module doc).

    Attributes:
        names: the readings' names, reading order.
        residuals: (m,) normalised residuals ``(z - h(pose)) / sigma`` at the least-squares pose.
        statistic: ``chi2 = sum residuals^2``.
        dof: degrees of freedom ``m - 6``.
        alpha: the false-alarm rate the test is run at.
        threshold: its bound ``chi2.ppf(1 - alpha, dof)``.
        exclusion: (m,) the statistic with each reading left out (``dof - 1`` degrees of freedom;
            nan for a reading whose fault leaves no trace).
        suspects: the readings whose exclusion restores consistency (empty when consistent).
        isolated: the faulty reading's name when the data single it out, else ``None``.
        detectable: (m,) minimal detectable bias of each reading at this pose (m or rad; inf: none),
            at ``alpha`` and power :data:`DEFAULT_POWER`.
    """

    names: tuple[str, ...]
    residuals: np.ndarray = field(repr=False)
    statistic: float
    dof: int
    alpha: float
    threshold: float
    exclusion: np.ndarray = field(repr=False)
    suspects: tuple[str, ...]
    isolated: str | None
    detectable: np.ndarray = field(repr=False)

    @property
    def consistent(self) -> bool:
        """Whether the readings pass the test (``statistic <= threshold``)."""
        return self.statistic <= self.threshold

    def describe(self) -> str:
        """One line: the statistic against its bound and, when it fails, where the fault may be."""
        head = f"chi-square {self.statistic:.4g} {'<=' if self.consistent else '>'} {self.threshold:.4g}"
        head += f" (dof {self.dof}, false-alarm rate {self.alpha:g})"
        if self.consistent:
            return head
        if self.isolated is not None:
            j = self.names.index(self.isolated)
            return f"{head}; faulty reading {self.isolated}: without it chi-square {self.exclusion[j]:.4g}"
        if not self.suspects:
            return f"{head}; no single reading's exclusion restores consistency (more than one fault?)"
        why = "one redundant measurement detects a fault but cannot isolate it" if self.dof == 1 else "not isolable"
        return f"{head}; the fault is on one of {', '.join(self.suspects)} ({why})"


def consistency(
    names: tuple[str, ...], A: np.ndarray, residuals: np.ndarray, sigmas: np.ndarray, alpha: float
) -> Consistency:
    """The test of normalised ``residuals`` at the least-squares solution with whitened Jacobian ``A``.

    Args:
        names: the readings' names.
        A: ``m x 6`` whitened Jacobian at the solution.
        residuals: (m,) normalised residuals there.
        sigmas: (m,) the readings' standard deviations (m or rad).
        alpha: false-alarm rate, in (0, 1).
    """
    m = len(names)
    dof = m - A.shape[1]
    stat = float(residuals @ residuals)
    bound = threshold(alpha, dof)
    p = parity_diagonal(A)
    seen = p > OBSERVABLE
    with np.errstate(divide="ignore", invalid="ignore"):
        excl = np.where(seen, np.maximum(stat - residuals**2 / np.maximum(p, OBSERVABLE), 0.0), np.nan)
    suspects: tuple[str, ...] = ()
    isolated = None
    if stat > bound:
        if dof == 1:
            suspects = tuple(n for n, s in zip(names, seen, strict=True) if s)
        else:
            sub = threshold(alpha, dof - 1)
            suspects = tuple(n for n, s, x in zip(names, seen, excl, strict=True) if s and x <= sub)
        isolated = suspects[0] if len(suspects) == 1 else None
    mdb = _detectable(p, sigmas, alpha, DEFAULT_POWER, dof) if dof > 0 else np.full(m, np.inf)
    return Consistency(names, residuals, stat, dof, alpha, bound, excl, suspects, isolated, mdb)
