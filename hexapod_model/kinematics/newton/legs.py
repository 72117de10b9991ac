"""The leg chains of a hexapod, read from its Pinocchio model as arrays for :mod:`.chains`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...description.model import ClosedLoopModel

GENERAL, SHIFT, IDENTITY = 0, 1, 2  # placement kinds (URDF joints mostly have rpy="0 0 0")


def placement_kinds(placements: np.ndarray) -> np.ndarray:
    """:attr:`ChainTables.kinds` of joint placements (..., 4, 4): exact comparisons, no tolerance."""
    rotation = np.all(placements[..., :3, :3] == np.eye(3), axis=(-2, -1))
    shift = np.any(placements[..., :3, 3] != 0.0, axis=-1)
    return np.where(rotation, np.where(shift, SHIFT, IDENTITY), GENERAL).astype(np.int64)


@dataclass(frozen=True)
class ChainTables:
    """The Pinocchio model's data that :func:`evaluate_chains` needs, as arrays (leg order).

    Attributes:
        placements: (6, n, 4, 4) joint placements in the parent joint's frame.
        kinds: (6, n) what each placement holds: :data:`GENERAL`, :data:`SHIFT` (a translation,
            the rotation exactly the identity) or :data:`IDENTITY` (both exactly zero), so
            that :func:`.chains.evaluate_chains` skips the products by exact ones and zeros.
        motions: (6, n, 6) motion subspaces ``[v; w]`` in the joint's frame.
        leg_q: (6, n) configuration index of each leg joint.
        leg_v: (6, n) velocity index (column of ``J``) of each leg joint.
        closure: (12, 4, 4) tip frames in their leg's last joint frame, then anchor frames in
            the platform joint frame.
        home: (4, 4) placement of the platform joint (the home pose).
        platform_q: configuration index of the platform's free flyer.
        platform_v: (6,) its velocity indices.
    """

    placements: np.ndarray
    kinds: np.ndarray
    motions: np.ndarray
    leg_q: np.ndarray
    leg_v: np.ndarray
    closure: np.ndarray
    home: np.ndarray
    platform_q: int
    platform_v: np.ndarray

    @classmethod
    def of(cls, clm: ClosedLoopModel) -> ChainTables | None:
        """The tables of ``clm``, or ``None`` when its legs are not all chains of ``n`` one-dof joints.

        Every leg must hold the same number of joints, each a revolute or prismatic joint whose
        motion subspace is a pure unit rotation or translation, chained parent to child from the
        root (the contract's legs); otherwise the general solver handles the model.
        """
        m = clm.model
        n = len(clm.legs[0].joints)
        if any(len(leg.joints) != n for leg in clm.legs):
            return None
        q0 = pin.neutral(m)
        placements = np.zeros((6, n, 4, 4))
        motions = np.zeros((6, n, 6))
        leg_q = np.zeros((6, n), dtype=np.int64)
        leg_v = np.zeros((6, n), dtype=np.int64)
        for i, leg in enumerate(clm.legs):
            parent = 0
            for k, j in enumerate(leg.joints):
                jm = m.joints[j]
                if jm.nq != 1 or jm.nv != 1 or m.parents[j] != parent:
                    return None
                jd = jm.createData()
                jm.calc(jd, q0)
                S = np.asarray(jd.S, dtype=float).reshape(6)
                lin, ang = np.linalg.norm(S[:3]), np.linalg.norm(S[3:])
                if not (abs(lin - 1.0) < 1e-12 and ang == 0.0) and not (abs(ang - 1.0) < 1e-12 and lin == 0.0):
                    return None
                placements[i, k] = m.jointPlacements[j].homogeneous
                motions[i, k] = S
                leg_q[i, k], leg_v[i, k] = jm.idx_q, jm.idx_v
                parent = j
        closure = np.array(
            [m.frames[leg.tip_frame].placement.homogeneous for leg in clm.legs]
            + [m.frames[leg.anchor_frame].placement.homogeneous for leg in clm.legs]
        )
        return cls(
            placements,
            placement_kinds(placements),
            motions,
            leg_q,
            leg_v,
            closure,
            m.jointPlacements[clm.platform_joint].homogeneous.copy(),
            int(clm.platform_q),
            np.arange(clm.platform_v, clm.platform_v + 6, dtype=np.int64),
        )
