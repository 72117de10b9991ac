"""Which assembly the platform left a singular neighbourhood on: candidates tested against a smooth motion.

Near a singularity of the eliminated Jacobian two assemblies of the same readings meet; a
platform that crosses the singular surface comes out on the assembly whose determinant sign
changed, one that only nears it on the other one. The readings are the same for both, but
only the platform's own pose sequence is smooth through the passage: the other candidate
reflects off the singular surface (a kink in its pose velocity, the two separating linearly
in time after the passage).

:class:`BranchResolver` keeps the candidates after the passage: the tracker's solution and its
*mirror*, found by Newton from the tracked pose reflected along the singular direction at the
most singular sample of the passage, then followed by warm starts. After each later sample
each candidate's pose sequence, the trusted poses before the passage followed by its own poses
after it (only samples with a condition number under the tracker's limit), is fitted by a
cubic in time per pose coordinate, weighted by the reading noise propagated through each
sample's Jacobian (``chi^2 = sum |J_i D_i^-1 (y_i - p(t_i))|^2 / noise^2``, ``y`` the tangent
coordinates at the newest pre-passage pose and ``D_i`` their derivative). Under the noise
model the true candidate's ``chi^2`` follows a chi-square law with ``6 n - 24`` degrees of
freedom; a candidate is rejected when its ``chi^2`` exceeds the ``1 - alpha`` quantile
(``alpha = branch_alpha``, default 1e-6). A candidate is chosen only when it is consistent and
every other one is rejected; otherwise the samples stay ``branch_uncertain``, and after
``resolve_samples`` samples without a decision the tracker gives up (until ``reset()``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .types import predict

_MIN_POST = 3  # samples of the other candidate before a decision (the motion model needs 3)
_PROBE = 1e-3  # m (rotations x length): the step that measures the fold's curvature
_GAUSS_NEWTON = 3  # iterations of the fit
_EVERY = 4  # samples between two decisions (each costs two fits)
_FIT_POINTS = 24  # post-passage samples in a fit at most
_DISTINCT = 1e-9  # m (rotations x length): two candidates closer than this are the same pose


def mirror_guess(model, ff: slice, length: float, q: np.ndarray, J: np.ndarray, moved) -> np.ndarray | None:
    """A configuration near the other assembly that meets ``q``'s at a fold.

    Along the singular direction ``v`` of ``J`` (smallest singular value, rotations scaled
    by the length) the reading along the matching left direction ``u`` is locally
    ``r(c) = sigma c + a c^2``, zero at ``c = 0`` (``q``) and at ``c = -sigma / a`` (the
    mirror); ``sigma`` and ``a`` come from the readings at ``c = +-h``.

    Args:
        model: the hexapod's Pinocchio model (unused; for symmetry with the resolver).
        ff: the platform's velocity slice (unused).
        length: m per rad.
        q: a configuration.
        J: the eliminated Jacobian at ``q``.
        moved: ``moved(q, twist)`` -> ``(configuration, readings)`` of ``q``'s platform
            pose moved by the LOCAL ``twist`` (inverse kinematics).
    """
    if not np.all(np.isfinite(J)):
        return None
    scale = np.r_[np.ones(3), np.full(3, length)]
    U, _, Vt = np.linalg.svd(J / scale)
    u, v = U[:, -1], Vt[-1] / scale
    h = _PROBE * max(length, 1.0)
    l0 = moved(q, np.zeros(6))[1]
    rp, rm = (float(u @ (moved(q, c * v)[1] - l0)) for c in (h, -h))
    a, sigma = (rp + rm) / (2.0 * h * h), (rp - rm) / (2.0 * h)
    if not (math.isfinite(a) and abs(a) > 0.0):
        return None
    return moved(q, (-sigma / a) * v)[0]


@dataclass
class Candidate:
    """One assembly's samples: indices, configurations, eliminated Jacobians, calm or not."""

    ks: list[int] = field(default_factory=list)
    qs: list[np.ndarray] = field(default_factory=list)
    Js: list[np.ndarray] = field(default_factory=list)
    calm: list[bool] = field(default_factory=list)  # condition number under the limit
    ls: list[np.ndarray] = field(default_factory=list)  # readings (the before-samples only)

    def add(self, k: int, q: np.ndarray, J: np.ndarray, calm: bool = True) -> None:
        """Append the configuration ``q`` at sample ``k`` (``J`` is copied)."""
        self.ks.append(k)
        self.qs.append(q)
        self.Js.append(J.copy())
        self.calm.append(calm)

    def at(self, k: int) -> tuple[np.ndarray, np.ndarray] | None:
        """``(q, J)`` of the calm sample ``k`` (``None`` when there is none)."""
        for i in range(len(self.ks) - 1, -1, -1):
            if self.ks[i] == k:
                return (self.qs[i], self.Js[i]) if self.calm[i] else None
            if self.ks[i] < k:
                break
        return None


class BranchResolver:
    """The candidates of one passage near a singularity and the test between them.

    Args:
        model: the hexapod's Pinocchio model.
        ff: the platform's velocity slice.
        before: ``(k, q, J)`` of the trusted, certified samples before the passage (oldest first).
        length: m per rad of the tracker.
        noise: reading standard deviation (m).
        alpha: significance at which a candidate is rejected.
    """

    def __init__(self, model, ff: slice, before, length: float, noise: float, alpha: float):
        self.model, self.ff, self.length, self.noise, self.alpha = model, ff, length, noise, alpha
        self.before = Candidate()
        self.before.ls = []
        for k, q, J, l in before:
            self.before.add(k, q, J)
            self.before.ls.append(l)
        self.main = Candidate()
        self.alt: Candidate | None = None
        self.post = 0  # samples since the passage was left
        self.readings: dict[int, np.ndarray] = {}

    def mirror_guess(self, q: np.ndarray, J: np.ndarray, moved) -> np.ndarray | None:
        """:func:`mirror_guess` with this resolver's model."""
        return mirror_guess(self.model, self.ff, self.length, q, J, moved)

    def distinct(self, qa: np.ndarray, qb: np.ndarray) -> bool:
        """Whether two configurations are different platform poses."""
        d = pin.difference(self.model, qa, qb)[self.ff]
        return math.hypot(np.linalg.norm(d[:3]), self.length * np.linalg.norm(d[3:])) > _DISTINCT * max(
            1.0, self.length
        )

    def follow(self, k: int, q, J, l, calm: bool, solve, measure, moved, at) -> str | None:
        """Add the tracker's configuration ``q`` at sample ``k`` after the passage; follow the mirror.

        Args:
            k: sample index.
            q: the tracker's configuration.
            J: its eliminated Jacobian.
            l: the sample's readings.
            calm: ``q``'s condition number is under the limit.
            solve: ``solve(guess)`` -> the configuration Newton reaches from ``guess`` for the
                sample's readings, or ``None``.
            measure: ``measure(q)`` -> ``(calm, J)`` at a configuration.
            moved: see :meth:`mirror_guess`.
            at: see :meth:`fit`.

        Returns:
            ``"main"``, ``"alt"`` (see :meth:`decide`) or ``None``.
        """
        self.post += 1
        self.main.add(k, q, J, calm)
        self.readings[k] = l
        alt = self.alt
        guess = self.mirror_guess(q, J, moved) if alt is None else predict(self.model, alt.qs[::-1][:3], "eq22")
        qa = solve(guess) if guess is not None else None
        if qa is None or not self.distinct(qa, q):
            self.alt = None  # not found, or merged with the tracker's: look again from the mirror
            return None
        if alt is None:
            alt = self.alt = Candidate()
        alt.add(k, qa, *measure(qa)[::-1])
        return self.decide(at) if len(alt.qs) % _EVERY == 0 else None

    def fit(self, cand: Candidate, ks: list[int], at) -> tuple[np.ndarray, float, np.ndarray]:
        """The smooth motion nearest ``cand`` that best explains the readings.

        A cubic in time per pose coordinate (tangent coordinates at the newest before-pose)
        through the before-samples and ``cand``'s samples ``ks``, fitted to the readings by
        Gauss-Newton from ``cand``'s poses (the fitted poses' readings by inverse kinematics).

        Args:
            cand: the candidate.
            ks: the post-passage samples.
            at: ``at(q)`` -> ``(configuration, readings, J)`` at ``q``'s platform pose.

        Returns:
            ``(theta, chi^2, covariance of theta)``: ``theta`` (4, 6) the coefficients,
            ``chi^2 = sum |l_i - f(x(t_i))|^2 / noise^2``.
        """
        pts = [(k, q, l) for k, q, l in zip(self.before.ks, self.before.qs, self.before.ls, strict=True)]
        pts += [(k, cand.at(k)[0], self.readings[k]) for k in ks]  # type: ignore[index]
        k0, q0 = self.before.ks[-1], self.before.qs[-1]
        V = np.vander(np.array([(k - k0) / 10.0 for k, _, _ in pts]), 4, increasing=True)
        y = np.array([pin.difference(self.model, q0, q)[self.ff] for _, q, _ in pts])
        theta = np.linalg.lstsq(V, y, rcond=None)[0]
        n = len(pts)
        value, cov = math.nan, np.full((24, 24), np.nan)
        for _ in range(_GAUSS_NEWTON):
            rows, rhs = np.zeros((6 * n, 24)), np.zeros(6 * n)
            for i, ((_, q, l), v) in enumerate(zip(pts, V, strict=True)):
                qf, lf, J = at(self.pose(q0, q, v @ theta))
                D = pin.dDifference(self.model, q0, qf, pin.ARG1)[self.ff, self.ff]
                rows[6 * i : 6 * i + 6] = np.kron(v, J @ np.linalg.inv(D) / self.noise)
                rhs[6 * i : 6 * i + 6] = (l - lf) / self.noise
            value = float(rhs @ rhs)
            cov = np.linalg.pinv(rows.T @ rows)
            theta = theta + (cov @ (rows.T @ rhs)).reshape(4, 6)
        return theta, value, cov

    def pose(self, q0: np.ndarray, q: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``q`` with its platform moved to ``q0 (+) y``."""
        dv = pin.difference(self.model, q0, q)
        dv[self.ff] = y
        return pin.integrate(self.model, q0, dv)

    def decide(self, at) -> str | None:
        """``"main"`` or ``"alt"`` when the readings single out that candidate, else ``None``.

        The smooth motion that best explains the readings near one candidate (:meth:`fit` from
        its poses) must be consistent (``chi^2`` under the ``1 - alpha`` quantile), end at the
        newest sample on that candidate's side of the midpoint between the two by ``z_alpha`` of
        its own standard deviation (from its coefficients' covariance), and the fit from the
        other candidate must be worse by ``2 ln(1 / alpha)`` (a likelihood ratio of
        ``1 / alpha`` against it).
        """
        if self.alt is None or len(self.alt.qs) < _MIN_POST:
            return None
        ks = [k for k in self.alt.ks if self.main.at(k) is not None and self.alt.at(k) is not None]
        if len(ks) < _MIN_POST:
            return None
        if len(ks) > _FIT_POINTS:  # evenly spread, the newest kept: bounded work per decision
            ks = [ks[round(i)] for i in np.linspace(0, len(ks) - 1, _FIT_POINTS)]
        k, k0, q0 = ks[-1], self.before.ks[-1], self.before.qs[-1]
        v = np.vander([(k - k0) / 10.0], 4, increasing=True)[0]
        ya = pin.difference(self.model, q0, self.main.at(k)[0])[self.ff]  # type: ignore[index]
        d = pin.difference(self.model, q0, self.alt.at(k)[0])[self.ff] - ya  # type: ignore[index]
        sides = []
        for cand in (self.main, self.alt):
            theta, value, cov = self.fit(cand, ks, at)
            lam = float(d @ (v @ theta - ya)) / float(d @ d)  # 0 at main, 1 at alt
            B = np.kron(v, np.eye(6))
            sd = math.sqrt(max(float(d @ B @ cov @ B.T @ d), 0.0)) / float(d @ d)
            sides.append((value, lam, sd))
        from scipy.special import chdtri, ndtri  # loaded with the tracker (Tracker.__init__): no import here

        # scipy.stats's norm.isf and chi2.isf are these functions (the same numbers)
        z, dof = float(-ndtri(self.alpha)), 6 * (len(self.before.ks) + len(ks)) - 24
        limit = float(chdtri(dof, self.alpha)) if dof > 0 else -math.inf
        margin = 2.0 * math.log(1.0 / self.alpha)
        for name, own, other, target in (("main", sides[0], sides[1], 0.0), ("alt", sides[1], sides[0], 1.0)):
            value, lam, sd = own
            # consistent, on its own candidate's side, and the other's best fit worse by 1 / alpha
            if value <= limit and abs(lam - target) < 0.5 - z * sd and other[0] - value >= margin:
                return name
        return None
