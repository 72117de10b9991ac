"""Geometric direct kinematics of the 3-6 hexapod sensor (seed 003 eqs. 1-11).

Legs ``2k`` and ``2k+1`` meet at platform point ``A_k`` (k = 0, 1, 2). With both leg lengths
known, ``A_k`` lies on a circle about the line through the base points ``B_2k``, ``B_2k+1``
(eqs. 2-8): centre ``C_k``, radius ``d_k``, and

    A_k(psi_k) = C_k + d_k (cos psi_k e_k + sin psi_k f_k),

with ``u_k = (B_2k - B_2k+1)/|.|``, ``e_k = z x u_k`` (normalised) and ``f_k = u_k x e_k`` (= z
for a planar base). The platform is rigid, so the three distances ``|A_i - A_j|`` equal their
home values (eq. 9): three equations in ``psi_0, psi_1, psi_2``.

Solving them: for a given ``psi_0`` each of ``|A_0 - A_1|`` and ``|A_0 - A_2|`` fixes
``psi_1``/``psi_2`` up to a sign choice (``a cos psi + b sin psi = c``), which leaves one scalar
equation ``|A_1 - A_2|^2 = D_12^2`` on four branches. It is scanned over ``psi_0`` for sign
changes, each bracket refined by Brent's method and polished by Newton on the full 3x3
system; duplicates are merged. All solutions are returned (a planar base always gives them in
mirror pairs about the base plane); :meth:`ThreeSixFK.solve` picks the one nearest a reference.

The pose (eqs. 10-11): seed 003 takes ``v`` as the centroid of the ``A_k`` and
``R = ([A] - [v v v]) [A^0]^-1``, which is singular as printed when the centred home points
are used; here ``R`` maps an orthonormal frame built on the home triangle to the same frame on
the solved triangle (exact for a rigid triangle) and ``t = mean(A) - R mean(p)``.

Readings are zero at home: leg length = home anchor distance + reading (m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..description.geometry import HexapodGeometry
from ..exceptions import GeometryError, InputError, WorkspaceError
from .tracking import pose_distance

_SCAN = 720


@dataclass(frozen=True)
class ThreeSixSolution:
    """One assembly of the 3-6 platform.

    Attributes:
        pose: (4, 4) base -> platform transform (m).
        psi: (3,) circle angles (rad), seed 003 eq. 8.
        points: (3, 3) platform points ``A_k`` in the base frame (m).
        residual: max abs error of eq. 9 (m^2).
    """

    pose: np.ndarray
    psi: np.ndarray
    points: np.ndarray
    residual: float


def _frame(P: np.ndarray) -> np.ndarray:
    x = P[1] - P[0]
    x /= np.linalg.norm(x)
    z = np.cross(x, P[2] - P[0])
    z /= np.linalg.norm(z)
    return np.column_stack([x, np.cross(z, x), z])


class ThreeSixFK:
    """Seed 003's geometric forward kinematics for a 3-6 geometry (e.g. preset ``3-6``).

    Raises:
        GeometryError: legs ``2k``, ``2k+1`` do not share a platform anchor, or a base pair is
            vertical (``e_k`` undefined).
    """

    def __init__(self, geometry: HexapodGeometry):
        self.geometry = geometry
        b, p = geometry.base_points(), geometry.platform_points()
        for k in range(3):
            if np.linalg.norm(p[2 * k] - p[2 * k + 1]) > 1e-12:
                raise GeometryError(
                    f"legs[{2 * k + 1}].platform_anchor",
                    tuple(p[2 * k + 1]),
                    f"a 3-6 hexapod needs legs {2 * k} and {2 * k + 1} to share a platform point",
                )
        self.base = b
        self.platform = p[::2].copy()  # (3, 3) platform frame
        self.home_lengths = np.array([geometry.home_leg_axis(i)[1] for i in range(6)])
        D = self.platform[:, None, :] - self.platform[None, :, :]
        self.D2 = np.einsum("ijk,ijk->ij", D, D)
        self.u = np.empty((3, 3))
        self.e = np.empty((3, 3))
        self.f = np.empty((3, 3))
        self.k1 = np.empty(3)
        z = np.array([0.0, 0.0, 1.0])
        for k in range(3):
            d = b[2 * k] - b[2 * k + 1]
            self.k1[k] = np.linalg.norm(d)
            self.u[k] = d / self.k1[k]
            e = np.cross(z, self.u[k])
            if np.linalg.norm(e) < 1e-9:
                raise GeometryError(
                    f"legs[{2 * k}].base_anchor", tuple(b[2 * k]), "base pair line must not be vertical"
                )
            self.e[k] = e / np.linalg.norm(e)
            self.f[k] = np.cross(self.u[k], self.e[k])
        self.home_pose = np.eye(4)
        self.home_pose[:3, 3] = geometry.home_translation

    def circles(self, lengths) -> tuple[np.ndarray, np.ndarray]:
        """Centres ``C_k`` (3, 3) and radii ``d_k`` (3,) (m) for readings ``lengths`` (eqs. 6-7)."""
        r = np.asarray(lengths, dtype=float).reshape(-1)
        if r.size != 6 or not np.all(np.isfinite(r)):
            raise InputError("lengths", lengths, "expected 6 finite readings (m)")
        L = self.home_lengths + r
        C, d = np.empty((3, 3)), np.empty(3)
        for k in range(3):
            L1, L2, k1 = L[2 * k], L[2 * k + 1], self.k1[k]
            c = (k1**2 + L2**2 - L1**2) / (2 * k1 * L2)
            if not -1.0 < c < 1.0 or L1 <= 0 or L2 <= 0:
                raise WorkspaceError(
                    None,
                    f"legs {2 * k} and {2 * k + 1} ({L1:.6g} m, {L2:.6g} m) cannot meet "
                    f"over a base pair {k1:.6g} m apart",
                )
            C[k] = self.base[2 * k + 1] + L2 * c * self.u[k]
            d[k] = L2 * np.sqrt(1.0 - c * c)
        return C, d

    def points(self, psi, C, d) -> np.ndarray:
        """Platform points ``A_k`` (3, 3) for circle angles ``psi`` (eq. 8)."""
        psi = np.asarray(psi, dtype=float)
        return C + d[:, None] * (np.cos(psi)[:, None] * self.e + np.sin(psi)[:, None] * self.f)

    def _equations(self, psi, C, d):
        A = self.points(psi, C, d)
        dA = d[:, None] * (-np.sin(psi)[:, None] * self.e + np.cos(psi)[:, None] * self.f)
        F, G = np.empty(3), np.zeros((3, 3))
        for row, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
            diff = A[i] - A[j]
            F[row] = diff @ diff - self.D2[i, j]
            G[row, i] = 2 * diff @ dA[i]
            G[row, j] = -2 * diff @ dA[j]
        return F, G

    def _partner(self, A0, C, d, k, sign):
        """``psi_k`` with ``|A0 - A_k| = D_0k`` on branch ``sign`` (nan when none)."""
        w = A0 - C[k]
        a, b = 2 * d[k] * (w @ self.e[k]), 2 * d[k] * (w @ self.f[k])
        c = w @ w + d[k] ** 2 - self.D2[0, k]
        r = np.hypot(a, b)
        if r == 0.0 or abs(c) > r:
            return np.nan
        return np.arctan2(b, a) + sign * np.arccos(c / r)

    def _branch(self, s0, C, d, s1, s2):
        A0 = self.points(np.array([s0, 0.0, 0.0]), C, d)[0]
        p1, p2 = self._partner(A0, C, d, 1, s1), self._partner(A0, C, d, 2, s2)
        if np.isnan(p1) or np.isnan(p2):
            return np.nan, p1, p2
        A = self.points(np.array([s0, p1, p2]), C, d)
        return (A[1] - A[2]) @ (A[1] - A[2]) - self.D2[1, 2], p1, p2

    def solve_all(self, lengths) -> list[ThreeSixSolution]:
        """Every assembly for these readings (m), sorted by distance to the home pose."""
        C, d = self.circles(lengths)
        grid = np.linspace(-np.pi, np.pi, _SCAN + 1)
        found: list[np.ndarray] = []
        for s1 in (-1.0, 1.0):
            for s2 in (-1.0, 1.0):
                g = np.array([self._branch(x, C, d, s1, s2)[0] for x in grid])
                for a, b, ga, gb in zip(grid[:-1], grid[1:], g[:-1], g[1:]):
                    if np.isnan(ga) or np.isnan(gb) or ga * gb > 0:
                        continue
                    x0 = (
                        a
                        if ga == 0
                        else b
                        if gb == 0
                        else brentq(
                            lambda x, s1=s1, s2=s2: self._branch(x, C, d, s1, s2)[0], a, b, xtol=1e-15, rtol=1e-15
                        )
                    )
                    _, p1, p2 = self._branch(x0, C, d, s1, s2)
                    found.append(self._polish(np.array([x0, p1, p2]), C, d))
        sols: list[ThreeSixSolution] = []
        for psi in found:
            psi = np.angle(np.exp(1j * psi))
            if any(np.abs(np.angle(np.exp(1j * (psi - s.psi)))).max() < 1e-7 for s in sols):
                continue
            sols.append(self._solution(psi, C, d))
        length = float(np.max(np.linalg.norm(self.base[:, :2], axis=1)))
        return sorted(sols, key=lambda s: pose_distance(self.home_pose, s.pose, length))

    def _polish(self, psi, C, d, steps: int = 6):
        for _ in range(steps):
            F, G = self._equations(psi, C, d)
            try:
                psi = psi - np.linalg.solve(G, F)
            except np.linalg.LinAlgError:
                break
        return psi

    def _solution(self, psi, C, d) -> ThreeSixSolution:
        A = self.points(psi, C, d)
        R = _frame(A) @ _frame(self.platform).T
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = A.mean(axis=0) - R @ self.platform.mean(axis=0)
        return ThreeSixSolution(T, psi, A, float(np.abs(self._equations(psi, C, d)[0]).max()))

    def solve(self, lengths, reference: np.ndarray | None = None) -> ThreeSixSolution:
        """The assembly nearest ``reference`` (4x4 pose, default home).

        Raises:
            WorkspaceError: no assembly exists for these readings.
        """
        sols = self.solve_all(lengths)
        if not sols:
            raise WorkspaceError(None, "no real assembly of the 3-6 platform for these readings")
        if reference is None:
            return sols[0]
        length = float(np.max(np.linalg.norm(self.base[:, :2], axis=1)))
        return min(sols, key=lambda s: pose_distance(np.asarray(reference, dtype=float), s.pose, length))
