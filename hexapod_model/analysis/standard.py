"""The textbook spherical-joint Stewart-Gough model, vectorised over many poses.

Bem et al. (2026) eqs. 1-4, Jakobović and Jelenković (2002) eqs. 14-16: leg vectors, lengths and
residuals are numpy array operations on chunks of poses; the per-pose 6x6 Newton solve and update
run in a small numba kernel (``benchmarks/standard_model.py`` prints the throughput).

Frames and units: poses are 4x4 base -> platform transforms (metres); ``base_points`` are the
joint centres ``b_i`` in the base frame, ``platform_points`` the centres ``p_i`` in the platform
frame. The model's leg length is the centre distance ``l_i = ||t + R p_i - b_i||`` (eqs. 1-2);
the *reading* (what the encoder gives, zero at home, as everywhere in this package) maps to it
by ``l_i = home_lengths[i] + reading_i``.

Equivalent centres of a Cardan hexapod (:meth:`StandardModel.from_geometry`): the geometry's
anchors, which for a Cardan joint with offset (non-intersecting) axes are by definition the
midpoint of the common normal of its two axes. For ideal universal joints (zero offset) and
ball joints this is the exact joint centre and the model is exact; with offset axes the true
distance between the two midpoints is no longer ``home + reading`` once the joints bend, which
is the ~mm error that Bem et al. (2026) measures (Table 1).

Velocities (Jacobian columns, Newton steps) are ``(dt, dtheta)``: ``dt`` moves the platform
origin in the base frame (m), ``dtheta`` is a base-frame rotation vector (rad) applied as
``R <- exp([dtheta]) R``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numba import njit

from ..description.geometry import HexapodGeometry
from ..exceptions import GeometryError, InputError, UrdfError
from ..kinematics.newton.linalg import lu_apply, lu_factor
from ..lie.compiled import exp3 as exp3_compiled


@dataclass(frozen=True)
class StandardResult:
    """Batch direct-kinematics result (N poses).

    Attributes:
        poses: (N, 4, 4) base -> platform transforms (m).
        converged: (N,) True where ``max |l(x) - l_measured| <= tol``.
        iterations: (N,) Newton steps taken by each pose.
        residual: (N,) final ``max_i |l_i(x) - l_i^m|`` (m).
    """

    poses: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray


@dataclass(frozen=True, eq=False)
class StandardModel:
    """Spherical-joint Stewart-Gough model.

    Attributes:
        base_points: (6, 3) joint centres ``b_i`` in the base frame (m).
        platform_points: (6, 3) joint centres ``p_i`` in the platform frame (m).
        home_lengths: (6,) centre distances at home (m): ``l_i = home_lengths[i] + reading_i``.
        home_pose: (4, 4) home pose, the default start of :meth:`forward` (``None``: pass a guess).
    """

    base_points: np.ndarray
    platform_points: np.ndarray
    home_lengths: np.ndarray
    home_pose: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name, shape in (("base_points", (6, 3)), ("platform_points", (6, 3)), ("home_lengths", (6,))):
            arr = np.array(getattr(self, name), dtype=float)
            if arr.shape != shape or not np.all(np.isfinite(arr)):
                raise InputError(name, getattr(self, name), f"expected a finite array of shape {shape}")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if np.any(self.home_lengths <= 0):
            raise InputError("home_lengths", self.home_lengths, "centre distances must be positive")
        if self.home_pose is not None:
            T = np.array(self.home_pose, dtype=float)
            if T.shape != (4, 4):
                raise InputError("home_pose", self.home_pose, "expected a 4x4 transform")
            T.setflags(write=False)
            object.__setattr__(self, "home_pose", T)

    # ----- construction -----
    @classmethod
    def from_geometry(cls, geom: HexapodGeometry) -> StandardModel:
        """Equivalent spherical centres of a geometry.

        Equivalent spherical centres of a geometry: its anchors (for Cardan joints the
        midpoint of the common normal of the two axes) and their distances at home.
        """
        if geom.joint_type == "guideway":
            raise GeometryError(
                "joint_type", geom.joint_type, "the standard model needs variable-length legs (cardan or spherical)"
            )
        home = np.eye(4)
        home[:3, 3] = geom.home_translation
        b, p = geom.base_points(), geom.platform_points()
        return cls(b, p, np.linalg.norm(geom.home_translation + p - b, axis=1), home)

    @classmethod
    def from_hexapod(cls, hexa) -> StandardModel:
        """Standard model of a loaded hexapod.

        From a loaded :class:`~hexapod_model.hexapod.Hexapod`: its geometry when it has one,
        otherwise centres read off the URDF at home (common-normal midpoints of the first two
        and, for 6-D closures, the last two revolute axes of each leg; the anchor origin for
        3-D closures).
        """
        if hexa.geometry is not None:
            return cls.from_geometry(hexa.geometry)
        clm = hexa.closed_loop
        m, d = clm.model, clm.model.createData()
        pin.computeJointJacobians(m, d, clm.q_home)
        pin.updateFramePlacements(m, d)
        home = clm.home.homogeneous
        b, p = np.zeros((6, 3)), np.zeros((6, 3))
        for i, leg in enumerate(clm.legs):
            kinds = [m.joints[j].shortname() for j in leg.joints]
            k_p = leg.joints.index(leg.prismatic)
            revs = [j for j, k in zip(leg.joints, kinds) if "Revolute" in k or k.startswith("JointModelR")]
            if k_p < 2 or any(j not in revs for j in leg.joints[:2]):
                raise UrdfError(
                    clm.source, leg.name, "the standard model needs two revolute base axes before the prismatic joint"
                )
            b[i] = _centre(d.J[:, m.joints[leg.joints[0]].idx_v], d.J[:, m.joints[leg.joints[1]].idx_v])
            if clm.kind == "6d":
                after = [j for j in leg.joints[k_p + 1 :] if j in revs]
                if len(after) < 2:
                    raise UrdfError(
                        clm.source,
                        leg.name,
                        "the standard model needs two revolute platform axes after the prismatic joint",
                    )
                c = _centre(d.J[:, m.joints[after[-2]].idx_v], d.J[:, m.joints[after[-1]].idx_v])
            else:
                c = d.oMf[leg.anchor_frame].translation
            p[i] = home[:3, :3].T @ (c - home[:3, 3])
        return cls(b, p, np.linalg.norm(home[:3, 3] + p @ home[:3, :3].T - b, axis=1), home)

    # ----- kinematics -----
    def _legs(self, R: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``R p_i`` and ``t + R p_i - b_i`` as (N, 3, 6) arrays (component, leg)."""
        n = R.shape[0]
        Rp = (np.ascontiguousarray(R).reshape(3 * n, 3) @ self.platform_points.T).reshape(n, 3, 6)
        v = Rp + (t[:, :, None] - self.base_points.T)
        return Rp, v

    def centre_distances(self, poses: np.ndarray) -> np.ndarray:
        """(N, 6) centre distances ``l_i = ||t + R p_i - b_i||`` (eq. 2), metres."""
        poses = _poses(poses)
        p, b = self.platform_points, self.base_points
        out = np.zeros((poses.shape[0], 6))
        for a in range(3):
            va = poses[:, a, 0:1] * p[:, 0] + poses[:, a, 1:2] * p[:, 1] + poses[:, a, 2:3] * p[:, 2]
            va += poses[:, a, 3:4] - b[:, a]
            va *= va
            out += va
        return np.sqrt(out, out=out)

    def inverse(self, poses: np.ndarray) -> np.ndarray:
        """(N, 6) leg readings (m, zero at home) of (N, 4, 4) or one (4, 4) pose."""
        out = self.centre_distances(poses)
        out -= self.home_lengths
        return out

    @staticmethod
    def _jacobian(Rp: np.ndarray, v: np.ndarray, dist: np.ndarray) -> np.ndarray:
        u = v / dist[:, None, :]
        J = np.empty((v.shape[0], 6, 6))
        J[:, :, 0:3] = np.swapaxes(u, 1, 2)
        J[:, :, 3] = Rp[:, 1] * u[:, 2] - Rp[:, 2] * u[:, 1]
        J[:, :, 4] = Rp[:, 2] * u[:, 0] - Rp[:, 0] * u[:, 2]
        J[:, :, 5] = Rp[:, 0] * u[:, 1] - Rp[:, 1] * u[:, 0]
        return J

    def jacobian(self, poses: np.ndarray) -> np.ndarray:
        """(N, 6, 6) ``d l / d (dt, dtheta)`` (eq.

        4): row ``i`` is ``[u_i, (R p_i) x u_i]`` with ``u_i`` the unit leg direction (base frame).
        """
        poses = _poses(poses)
        Rp, v = self._legs(poses[:, :3, :3], poses[:, :3, 3])
        return self._jacobian(Rp, v, np.sqrt(np.einsum("nak,nak->nk", v, v)))

    def forward(
        self,
        readings: np.ndarray,
        guess: np.ndarray | None = None,
        *,
        tol: float = 1e-12,
        max_iter: int = 30,
        callback: Callable[[int, np.ndarray, np.ndarray], None] | None = None,
        chunk: int = 4096,
    ) -> StandardResult:
        """Batch Newton direct kinematics (eq. 3) for (N, 6) or (6,) readings (m, zero at home).

        Poses are processed ``chunk`` at a time (the working arrays stay in cache); inside a
        chunk a pose leaves the iteration as soon as it has converged.

        Args:
            readings: leg readings; ``home_lengths + readings`` are the centre distances.
            guess: (4, 4) or (N, 4, 4) start poses (default: :attr:`home_pose`).
            tol: a pose has converged when ``max_i |l_i(x) - l_i^m| <= tol`` (m).
            max_iter: step limit.
            callback: called as ``callback(k, index, steps)`` after step ``k`` (1-based) with
                the indices of the poses that moved and their (n, 6) steps ``(dt, dtheta)``.
            chunk: poses solved together.
        """
        lm = np.asarray(readings, dtype=float)
        lm = lm.reshape(1, 6) if lm.shape == (6,) else lm
        if lm.ndim != 2 or lm.shape[1] != 6:
            raise InputError("readings", lm.shape, "expected shape (N, 6) or (6,)")
        lm = lm + self.home_lengths
        n = lm.shape[0]
        if guess is None:
            if self.home_pose is None:
                raise InputError("guess", None, "this model has no home pose; pass a start pose")
            guess = self.home_pose
        guess = np.broadcast_to(np.asarray(guess, dtype=float), (n, 4, 4))
        poses = np.zeros((n, 4, 4))
        poses[:, 3, 3] = 1.0
        iterations = np.zeros(n, dtype=int)
        residual = np.full(n, np.nan)
        for s in range(0, n, chunk):
            idx = np.arange(s, min(s + chunk, n))
            R, t, target = np.array(guess[idx, :3, :3]), np.array(guess[idx, :3, 3]), lm[idx]
            for k in range(max_iter + 1):
                Rp, v = self._legs(R, t)
                dist = np.sqrt(np.einsum("nak,nak->nk", v, v))
                f = dist - target
                res = np.abs(f).max(axis=1)
                done = res <= tol
                if k == max_iter:
                    done[:] = True
                if done.any():  # retire converged (or, at the end, all) poses
                    out = idx[done]
                    poses[out, :3, :3], poses[out, :3, 3], residual[out] = R[done], t[done], res[done]
                    keep = ~done
                    if not keep.any():
                        break
                    idx, R, t, target, Rp, v, dist, f = (a[keep] for a in (idx, R, t, target, Rp, v, dist, f))
                step = np.empty((idx.size, 6))
                _newton_steps(Rp, v, dist, f, step, R, t)
                iterations[idx] += 1
                if callback is not None:
                    callback(k + 1, idx, step)
        return StandardResult(poses, residual <= tol, iterations, residual)


@njit(cache=True)
def _newton_steps(Rp, v, dist, f, step, R, t):
    """Newton steps of the standard model, applied in place.

    Newton steps ``step[n] = -J[n]^-1 f[n]`` with ``J`` the rows ``[u_i, (R p_i) x u_i]``
    assembled from (N, 3, 6) ``Rp``, ``v`` and (N, 6) ``dist``; applies them in place:
    ``t += dt``, ``R <- exp([dtheta]) R`` (Rodrigues).
    """
    E = np.empty((3, 3))
    Rn = np.empty((3, 3))
    J = np.empty((6, 6))
    piv = np.empty(6, dtype=np.int64)
    rhs = np.empty(6)
    x = np.empty((1, 6))
    for n in range(f.shape[0]):
        for i in range(6):
            ux, uy, uz = v[n, 0, i] / dist[n, i], v[n, 1, i] / dist[n, i], v[n, 2, i] / dist[n, i]
            px, py, pz = Rp[n, 0, i], Rp[n, 1, i], Rp[n, 2, i]
            J[i, 0], J[i, 1], J[i, 2] = ux, uy, uz
            J[i, 3], J[i, 4], J[i, 5] = py * uz - pz * uy, pz * ux - px * uz, px * uy - py * ux
            rhs[i] = -f[n, i]
        if lu_factor(J, J, piv) == 0.0:  # singular: the step (and so the pose) becomes NaN
            x[0, :] = np.nan
        else:
            lu_apply(J, piv, rhs, x[0])
        step[n, :] = x[0]
        exp3_compiled(x[0, 3], x[0, 4], x[0, 5], E)
        for r in range(3):
            t[n, r] += x[0, r]
            for q in range(3):
                Rn[r, q] = E[r, 0] * R[n, 0, q] + E[r, 1] * R[n, 1, q] + E[r, 2] * R[n, 2, q]
        R[n] = Rn


def _poses(poses: np.ndarray) -> np.ndarray:
    poses = np.asarray(poses, dtype=float)
    if poses.shape == (4, 4):
        return poses[None]
    if poses.ndim != 3 or poses.shape[1:] != (4, 4):
        raise InputError("poses", poses.shape, "expected shape (N, 4, 4) or (4, 4)")
    return poses


def _centre(col_a: np.ndarray, col_b: np.ndarray) -> np.ndarray:
    """Midpoint of the common normal of two revolute axes.

    Midpoint of the common normal of two revolute axes given by their WORLD Jacobian
    columns ``[v_o; w]`` (a point on the axis is ``w x v_o / |w|^2``).
    """
    lines = []
    for col in (col_a, col_b):
        w = col[3:] / np.linalg.norm(col[3:])
        lines.append((np.cross(w, col[:3]), w))
    (pa, wa), (pb, wb) = lines
    n = np.cross(wa, wb)
    if np.linalg.norm(n) < 1e-9:
        raise UrdfError("<urdf>", "cardan axes", "the two axes of a Cardan joint are parallel")
    # solve pa + s wa + m n = pb + t wb
    s, t, _ = np.linalg.solve(np.column_stack([wa, -wb, n]), pb - pa)
    return 0.5 * (pa + s * wa + pb + t * wb)
