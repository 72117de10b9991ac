"""Geometric direct kinematics of the 3-6 hexapod sensor (Shi, She and Duan (2016) eqs. 1-11).

Legs ``2k`` and ``2k+1`` meet at platform point ``A_k`` (k = 0, 1, 2). With both leg lengths
known, ``A_k`` lies on a circle about the line through the base points ``B_2k``, ``B_2k+1``
(eqs. 2-8): centre ``C_k``, radius ``d_k``, and

    A_k(psi_k) = C_k + d_k (cos psi_k e_k + sin psi_k f_k),

with ``u_k = (B_2k - B_2k+1)/|.|``, ``e_k = z x u_k`` (normalised) and ``f_k = u_k x e_k`` (= z
for a planar base). The platform is rigid, so the three distances ``|A_i - A_j|`` equal their
home values (eq. 9): three equations in ``psi_0, psi_1, psi_2``.

Solving them by elimination, so that no assembly can be missed: each equation reads
``w(psi_i)^T K_ij w(psi_j) = 0`` with ``w(psi) = (1, cos psi, sin psi)``. In the half-angle
tangents ``x_1``, ``x_2`` the equations in ``(psi_0, x_1)``, ``(x_1, x_2)`` and ``(x_2, psi_0)`` are
quadratics; the resultant in ``x_1`` of the first two (closed form for two quadratics) is a
quartic in ``x_2``, and its resultant in ``x_2`` with the third (a 6x6 Sylvester determinant)
is a trigonometric polynomial of order 8 in ``psi_0`` that vanishes at every assembly. It is
sampled at 32 angles, turned into its 17 Fourier coefficients by an FFT (exact, no
interpolation error) and solved as a degree-16 polynomial in ``z = exp(i psi_0)``: the
eigenvalues of its companion matrix are all its roots at once. Roots on the unit circle (to
``1e-4``, generous so that the nearly double roots at a fold are kept) give ``psi_0``;
``psi_1``, ``psi_2`` follow from ``a cos psi + b sin psi = c``; every combination is polished by
Newton on the 3x3 system and kept only if it satisfies eq. 9 to ``ACCEPT`` (times the square of the
geometry's length scale, :func:`.newton.solver.length_scale`; duplicates merged).
Hence **at most 16 assemblies** (``MAX_ASSEMBLIES``, the degree of the polynomial; a planar base
gives them in mirror pairs about the base plane), all of them, in 1 to 2 ms.
:meth:`ThreeSixFK.solve` picks the one nearest a reference from this complete set.

The pose (eqs. 10-11): Shi, She and Duan (2016) takes ``v`` as the centroid of the ``A_k`` and
``R = ([A] - [v v v]) [A^0]^-1``, which is singular as printed when the centred home points
are used; here ``R`` maps an orthonormal frame built on the home triangle to the same frame on
the solved triangle (exact for a rigid triangle) and ``t = mean(A) - R mean(p)``.

Readings are zero at home: leg length = home anchor distance + reading (m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..description.geometry import HexapodGeometry
from ..exceptions import GeometryError, InputError, WorkspaceError
from ..lie import pose_distance
from .newton.solver import length_scale

MAX_ASSEMBLIES = 16  # roots of the order-8 trigonometric polynomial in psi_0
ACCEPT = 1e-12  # m^2 at length scale 1: largest eq. 9 error of a returned assembly (about 1e-11 m in distance)
_SAMPLES = 32  # angles at which the resultant is evaluated (>= 17 Fourier coefficients)
_CIRCLE = 1e-4  # |log |z|| below which a polynomial root counts as a real angle
_NEAR = 1e-2  # largest eq. 9 error (relative to the largest D^2) of a root's branch before polishing
_PAIRS = ((0, 1), (1, 2), (2, 0))
_T = np.array([[1.0, 0.0, 1.0], [1.0, 0.0, -1.0], [0.0, 2.0, 0.0]])  # (1 + x^2) w(psi) = _T (1, x, x^2)


@dataclass(frozen=True)
class ThreeSixSolution:
    """One assembly of the 3-6 platform.

    Attributes:
        pose: (4, 4) base -> platform transform (m).
        psi: (3,) circle angles (rad), Shi, She and Duan (2016) eq. 8.
        points: (3, 3) platform points ``A_k`` in the base frame (m).
        residual: max abs error of eq. 9 (m^2).
    """

    pose: np.ndarray
    psi: np.ndarray
    points: np.ndarray
    residual: float


def _frames(P: np.ndarray) -> np.ndarray:
    """Orthonormal frames (n, 3, 3), columns x, y, z, of the triangles ``P`` (n, 3, 3)."""
    x = P[:, 1] - P[:, 0]
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    z = np.cross(x, P[:, 2] - P[:, 0])
    z /= np.linalg.norm(z, axis=1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], -1)


class ThreeSixFK:
    """Shi, She and Duan's geometric forward kinematics for a 3-6 geometry (e.g. preset ``3-6``).

    Raises:
        GeometryError: legs ``2k``, ``2k+1`` do not share a platform anchor, or a base pair is
            vertical (``e_k`` undefined).
    """

    def __init__(self, geometry: HexapodGeometry):
        self.geometry = geometry
        b, p = geometry.base_points(), geometry.platform_points()
        self.length = float(np.max(np.linalg.norm(b[:, :2], axis=1)))  # m per rad in pose distances
        scale = length_scale(self.length) if self.length > 0.0 else 1.0
        self._accept = ACCEPT * scale * scale  # m^2: eq. 9 is in squared lengths
        for k in range(3):
            if np.linalg.norm(p[2 * k] - p[2 * k + 1]) > 1e-12 * scale:
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
        self._home_frame = _frames(self.platform[None])[0]

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

    def _equations(self, psi: np.ndarray, C: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Eq. 9 residuals (n, 3) (m^2) and their Jacobian (n, 3, 3) at angles ``psi`` (n, 3)."""
        c, s = np.cos(psi)[..., None], np.sin(psi)[..., None]
        A = C + d[:, None] * (c * self.e + s * self.f)
        dA = d[:, None] * (-s * self.e + c * self.f)
        F, G = np.empty(psi.shape), np.zeros(psi.shape + (3,))
        for row, (i, j) in enumerate(_PAIRS):
            diff = A[:, i] - A[:, j]
            F[:, row] = (diff * diff).sum(-1) - self.D2[i, j]
            G[:, row, i] = 2 * (diff * dA[:, i]).sum(-1)
            G[:, row, j] = -2 * (diff * dA[:, j]).sum(-1)
        return F, G

    def _coefficients(self, C: np.ndarray, d: np.ndarray) -> list[np.ndarray]:
        """``K_ij`` (3, 3) of the eq. 9 residuals ``w(psi_i)^T K_ij w(psi_j)``, pairs ``_PAIRS``."""
        Ks = []
        for i, j in _PAIRS:
            delta = C[i] - C[j]
            ui, uj = np.stack([self.e[i], self.f[i]]), np.stack([self.e[j], self.f[j]])
            K = np.empty((3, 3))
            K[0, 0] = delta @ delta + d[i] ** 2 + d[j] ** 2 - self.D2[i, j]
            K[1:, 0] = 2 * d[i] * (ui @ delta)
            K[0, 1:] = -2 * d[j] * (uj @ delta)
            K[1:, 1:] = -2 * d[i] * d[j] * (ui @ uj.T)
            Ks.append(K)
        return Ks

    @staticmethod
    def _resultant(Ks: list[np.ndarray], psi0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The resultant (n,) at angles ``psi0`` (n,) and Hadamard's bound (n,) on its size."""
        K01, K12, K20 = Ks
        w0 = np.stack([np.ones_like(psi0), np.cos(psi0), np.sin(psi0)], -1)
        a = w0 @ K01 @ _T  # (n, 3): (1 + x1^2) times eq. (0, 1), powers of x1
        Q = _T.T @ K12 @ _T  # Q[a, b]: coefficient of x1^a x2^b in (1 + x1^2)(1 + x2^2) eq. (1, 2)
        b = w0 @ K20.T @ _T  # (n, 3): (1 + x2^2) times eq. (2, 0), powers of x2
        # resultant in x1 of a and Q's quadratic: (a2 g0 - a0 g2)^2 - (a2 g1 - a1 g2)(a1 g0 - a0 g1)
        u = a[:, 2:3] * Q[0] - a[:, 0:1] * Q[2]
        v = a[:, 2:3] * Q[1] - a[:, 1:2] * Q[2]
        w = a[:, 1:2] * Q[0] - a[:, 0:1] * Q[1]
        quartic = np.zeros((psi0.size, 5))  # powers of x2
        for i in range(3):
            for j in range(3):
                quartic[:, i + j] += u[:, i] * u[:, j] - v[:, i] * w[:, j]
        S = np.zeros((psi0.size, 6, 6))  # Sylvester matrix of b (degree 2) and the quartic
        for k in range(4):
            S[:, k, k : k + 3] = b[:, ::-1]
        for k in range(2):
            S[:, 4 + k, k : k + 5] = quartic[:, ::-1]
        return np.linalg.det(S), np.prod(np.linalg.norm(S, axis=2), axis=1)

    def _roots(self, Ks: list[np.ndarray]) -> np.ndarray:
        """Every root ``z = exp(i psi_0)`` of the resultant (16, complex)."""
        return np.roots(self._polynomial(Ks))

    def polynomial(self, lengths) -> np.ndarray:
        """The resultant for readings ``lengths`` (m) as a polynomial in ``z = exp(i psi_0)``.

        17 complex coefficients, highest power first (``numpy.roots``' order): its roots on the
        unit circle are the assemblies' ``psi_0``, the others come in pairs ``z``, ``1 / conj(z)``.
        """
        C, d = self.circles(lengths)
        return self._polynomial(self._coefficients(C, d))

    def _polynomial(self, Ks: list[np.ndarray]) -> np.ndarray:
        """The resultant as a polynomial in ``z = exp(i psi_0)`` (17 coefficients, highest power first)."""
        values, bound = self._resultant(Ks, 2 * np.pi * np.arange(_SAMPLES) / _SAMPLES)
        c = np.fft.fft(values) / _SAMPLES  # resultant = sum_k c[k] exp(i k psi), |k| <= 8
        n = MAX_ASSEMBLIES // 2
        if not np.abs(c).max() > 1e-12 * bound.max():
            raise WorkspaceError(
                None, "the 3-6 assembly equations are degenerate for these readings (no isolated solutions)"
            )
        return np.concatenate([c[n:0:-1], c[:1], c[-1 : -n - 1 : -1]])  # z^8 times it: c_8 ... c_-8

    def _angles(self, Ks: list[np.ndarray]) -> np.ndarray:
        """Every real root ``psi_0`` of the resultant (and complex ones within ``_CIRCLE`` of real)."""
        z = self._roots(Ks)
        return np.angle(z[np.abs(np.log(np.abs(z))) < _CIRCLE])

    @staticmethod
    def _partner(k: np.ndarray) -> np.ndarray:
        """Both ``psi`` (n, 2) with ``k0 + k1 cos psi + k2 sin psi = 0``, rows ``k`` (n, 3); NaN when none."""
        r = np.hypot(k[:, 1], k[:, 2])
        ratio = -k[:, 0] / np.where(r > 0, r, np.nan)
        ratio = np.where(np.abs(ratio) <= 1 + 1e-6, np.clip(ratio, -1, 1), np.nan)
        base, spread = np.arctan2(k[:, 2], k[:, 1]), np.arccos(ratio)
        return np.stack([base + spread, base - spread], -1)

    def solve_all(self, lengths) -> list[ThreeSixSolution]:
        """Every assembly for these readings (m), at most ``MAX_ASSEMBLIES``, sorted by distance to home."""
        C, d = self.circles(lengths)
        Ks = self._coefficients(C, d)
        psi0 = self._angles(Ks)
        w0 = np.stack([np.ones_like(psi0), np.cos(psi0), np.sin(psi0)], -1)
        p1, p2 = self._partner(w0 @ Ks[0]), self._partner(w0 @ Ks[2].T)
        psi = np.stack([np.repeat(psi0, 4), np.repeat(p1, 2, axis=1).ravel(), np.tile(p2, 2).ravel()], -1)
        psi, F = self._polish(psi[np.all(np.isfinite(psi), axis=1)], C, d)
        keep = np.abs(F).max(axis=1) <= self._accept
        psi, residual = np.angle(np.exp(1j * psi[keep])), np.abs(F[keep]).max(axis=1)
        wrapped = np.abs(np.angle(np.exp(1j * (psi[:, None] - psi[None])))).max(axis=2)
        unique = [k for k in range(len(psi)) if not np.any(wrapped[k, :k] < 1e-7)]
        psi, residual = psi[unique], residual[unique]
        A = C + d[:, None] * (np.cos(psi)[..., None] * self.e + np.sin(psi)[..., None] * self.f)
        T = np.tile(np.eye(4), (len(psi), 1, 1))
        T[:, :3, :3] = _frames(A) @ self._home_frame.T
        T[:, :3, 3] = A.mean(axis=1) - T[:, :3, :3] @ self.platform.mean(axis=0)
        sols = [ThreeSixSolution(T[k], psi[k], A[k], float(residual[k])) for k in range(len(psi))]
        return sorted(sols, key=lambda s: pose_distance(self.home_pose, s.pose, self.length))

    def _polish(self, psi: np.ndarray, C: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Newton on the 3x3 system from every row of ``psi`` (n, 3); returns angles and residuals.

        Rows are dropped once they converge or stop improving (a wrong branch choice).
        """
        F, G = self._equations(psi, C, d)
        err = np.abs(F).max(axis=1)
        active = err <= _NEAR * self.D2.max()  # the other branch choices are off by ~D^2
        for _ in range(8):
            active &= err > 1e-3 * self._accept
            if not active.any():
                break
            Ga, Fa = G[active], F[active]
            singular = ~(np.abs(np.linalg.det(Ga)) > 1e-300)
            Ga[singular], Fa[singular] = np.eye(3), 0.0
            psi[active] -= np.linalg.solve(Ga, Fa[..., None])[..., 0]
            F[active], G[active] = self._equations(psi[active], C, d)
            new = np.abs(F).max(axis=1)
            active &= new < err
            err = new
        return psi, F

    def solve(self, lengths, reference: np.ndarray | None = None, max_distance: float = np.inf) -> ThreeSixSolution:
        """The assembly nearest ``reference`` (4x4 pose, default home), from the complete set.

        Args:
            lengths: six readings (m, zero at home).
            reference: the pose to be near (e.g. the previous sample's).
            max_distance: largest accepted distance to ``reference`` (m, rotations times the base
                radius).

        Raises:
            WorkspaceError: no assembly exists for these readings, or none within ``max_distance``.
        """
        sols = self.solve_all(lengths)
        if not sols:
            raise WorkspaceError(None, "no real assembly of the 3-6 platform for these readings")
        ref = self.home_pose if reference is None else np.asarray(reference, dtype=float)
        dist = [pose_distance(ref, s.pose, self.length) for s in sols]
        k = int(np.argmin(dist))
        if not dist[k] <= max_distance:
            raise WorkspaceError(
                None,
                f"the nearest of {len(sols)} assemblies is {dist[k]:.3g} m from the reference (> {max_distance:g} m)",
            )
        return sols[k]
