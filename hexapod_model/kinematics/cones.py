"""Joint cones: how far each joint is deflected from its home axis, against its cone half-angle.

A catalogue ball joint or Cardan joint bounds the *angle* its two sides make, not each revolute
separately. The cone angle of a joint in a configuration ``q``:

* a **Cardan joint** (two revolutes, the first two of a leg's chain at the base, the last two at
  the platform end when the leg ends in one): the combined deflection
  ``arccos(cos a1 cos a2)`` of its angles ``a1``, ``a2`` (rad): the angle between its common
  normal at home and now, which is what the yoke sees;
* a **ball joint** (a leg whose chain does not end in two revolutes): the angle between the leg
  axis (from the second base Cardan axis to the ball centre) and its home direction, both seen
  from the platform.

The half-angles come from the geometry (``base_cone``, ``platform_cone``, per leg or for all;
``None``: no cone, an infinite limit here). A joint beyond its cone is a ``cone_limit``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..description.geometry import HexapodGeometry
from ..description.model import ClosedLoopModel

ENDS = ("base", "platform")


@dataclass(frozen=True)
class ConeAngles:
    """Each joint's cone angle and limit in one configuration.

    Attributes:
        angles: (6, 2) deflection of each leg's base and platform joint from its home axis (rad).
        limits: (6, 2) their cone half-angles (rad; ``inf``: no cone).
    """

    angles: np.ndarray
    limits: np.ndarray

    @property
    def margins(self) -> np.ndarray:
        """(6, 2) ``limits - angles`` (rad): negative beyond the cone."""
        return self.limits - self.angles

    @property
    def within(self) -> bool:
        """Whether every joint lies inside its cone."""
        return bool(np.all(self.angles <= self.limits))

    def worst(self) -> tuple[int, str, float]:
        """The joint with the smallest margin: leg index (0..5), ``"base"`` or ``"platform"``, margin (rad)."""
        k = int(np.argmin(self.margins))
        return k // 2, ENDS[k % 2], float(self.margins.flat[k])

    def message(self) -> str:
        """One line naming the joint nearest (or beyond) its cone, in degrees."""
        leg, end, _ = self.worst()
        angle, limit = np.degrees(self.angles[leg, ENDS.index(end)]), np.degrees(self.limits[leg, ENDS.index(end)])
        verb = "cone_limit" if angle > limit else "cone"
        return f"{verb}: leg{leg + 1} {end} joint deflected {angle:.3f} deg, cone half-angle {limit:.6g} deg"


def _revolutes(clm: ClosedLoopModel, joints: tuple[int, ...]) -> list[int]:
    return [j for j in joints if clm.model.joints[j].shortname().startswith("JointModelR")]


class ConeGeometry:
    """What :func:`cone_angles` needs of a model, prepared once (a check on every solve reuses it).

    ``angles(q, data)`` takes a Pinocchio ``data`` of the model as a buffer (one per thread).
    """

    def __init__(self, clm: ClosedLoopModel):
        m = clm.model
        self.clm = clm
        base, platform, ball, second, tips = [], [], [], [], []
        for k, leg in enumerate(clm.legs):
            rev = _revolutes(clm, leg.joints)
            base.append([m.joints[j].idx_q for j in rev[:2]])
            if len(leg.joints) >= 2 and leg.joints[-1] in rev and leg.joints[-2] in rev and len(rev) >= 4:
                platform.append((k, [m.joints[j].idx_q for j in leg.joints[-2:]]))
            else:
                ball.append(k)
                second.append(rev[1])
                tips.append(leg.tip_frame)
        self.base = np.array(base, dtype=np.int64)  # (6, 2) q indices of the base Cardan angles
        self.platform = platform  # (leg, [q indices]) of the platform Cardan joints
        self.ball, self.second, self.tips = ball, second, tips
        self.home = self._directions(clm.q_home, m.createData()) if ball else np.zeros((0, 3))

    def kernel_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """What the body kernel (:func:`~.placement_kernel.cones`) reads of the joints.

        Returns:
            ``cardan`` (n, 3) the two angles' q indices and the slot (leg * 2 + end) of each
            Cardan joint; ``ball`` (n, 3) the slot, the second base revolute's joint id and the
            tip frame's joint id of each ball-jointed leg; ``tips`` (n, 3) each tip frame's
            position in its joint's frame (m); ``home`` (n, 3) the home leg axes (platform frame).
        """
        m = self.clm.model
        cardan = [(int(a), int(b), 2 * k) for k, (a, b) in enumerate(self.base)]
        cardan += [(int(idx[0]), int(idx[1]), 2 * k + 1) for k, idx in self.platform]
        ball = [(2 * k + 1, j, m.frames[f].parentJoint) for k, j, f in zip(self.ball, self.second, self.tips)]
        tips = np.array([m.frames[f].placement.translation for f in self.tips]).reshape(-1, 3)
        return (
            np.array(cardan, dtype=np.int64).reshape(-1, 3),
            np.array(ball, dtype=np.int64).reshape(-1, 3),
            tips,
            self.home.reshape(-1, 3),
        )

    def _directions(self, q: np.ndarray, data: pin.Data) -> np.ndarray:
        """(n_ball, 3) unit leg axes of the ball-jointed legs in the platform frame."""
        m = self.clm.model
        pin.forwardKinematics(m, data, q)
        R = data.oMi[self.clm.platform_joint].rotation
        d = np.array([pin.updateFramePlacement(m, data, f).translation for f in self.tips])
        d -= np.array([data.oMi[j].translation for j in self.second])
        d = d @ R  # R^T d per row
        return d / np.sqrt(np.einsum("ij,ij->i", d, d))[:, None]

    def angles(self, q: np.ndarray, data: pin.Data) -> np.ndarray:
        """(6, 2) the base and platform joint deflections (rad) of configuration ``q``."""
        out = np.empty((6, 2))
        c = np.cos(q[self.base])
        out[:, 0] = np.arccos(np.minimum(1.0, c[:, 0] * c[:, 1]))
        for k, idx in self.platform:
            b1, b2 = np.cos(q[idx])
            out[k, 1] = np.arccos(min(1.0, b1 * b2))
        if self.ball:
            now, home = self._directions(q, data), self.home
            cross = np.cross(now, home)
            sin, cos = np.sqrt(np.einsum("ij,ij->i", cross, cross)), np.einsum("ij,ij->i", now, home)
            out[self.ball, 1] = np.arctan2(sin, cos)
        return out


def cone_angles(clm: ClosedLoopModel, q: np.ndarray) -> np.ndarray:
    """(6, 2) the base and platform joint deflections (rad) of configuration ``q`` (see the module doc)."""
    return ConeGeometry(clm).angles(np.asarray(q, dtype=float), clm.model.createData())


def cone_limits(geometry: HexapodGeometry | None) -> np.ndarray:
    """(6, 2) the cone half-angles (rad) of ``geometry``'s joints; ``inf`` where none (or no geometry)."""
    out = np.full((6, 2), np.inf)
    if geometry is not None:
        for k in range(6):
            for end, limit in enumerate(geometry.cones_of(k)):
                if limit is not None:
                    out[k, end] = limit
    return out


def check_cones(clm: ClosedLoopModel, geometry: HexapodGeometry | None, q: np.ndarray) -> ConeAngles:
    """:class:`ConeAngles` of configuration ``q``: the check a pose-returning path calls."""
    return ConeAngles(cone_angles(clm, np.asarray(q, dtype=float)), cone_limits(geometry))
