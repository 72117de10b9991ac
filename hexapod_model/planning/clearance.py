"""The UR10's clearance from the hexapods: its collision meshes against bounding cylinders, with coal.

The package has no collision model of a hexapod yet: each fixture is enclosed in a vertical
cylinder on its base (axis the base frame's z, from z = 0 to the plate's top at the higher of
its start and target poses plus ``TOP_MARGIN``; radius the farthest joint centre of its model
from the axis plus ``SIDE_MARGIN``). The arm's own collision geometry (example-robot-data) is
placed by Pinocchio; distances are coal's. Self-collision and the floor are not checked.

**Between the samples of a joint-space move.** Every point of the arm is within ``ARM_RADIUS``
(1.5 m, more than the reach) of each joint axis, so a joint step ``dq`` moves it at most
``ARM_RADIUS * |dq|_1``. A move is walked by conservative advancement: from a configuration
with clearance ``d`` the next is at most ``(d - required) / ARM_RADIUS`` away in ``|dq|_1``,
so the clearance cannot drop below ``required`` anywhere between the checked configurations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.hexapod import Hexapod
from .robot import ur10_models

TOP_MARGIN = 0.03  # m above the platform frame's origin: the plate's thickness and the coupling's base
SIDE_MARGIN = 0.05  # m beyond the farthest joint centre: the legs' and joints' bodies
ARM_RADIUS = 1.5  # m: every point of the arm is this close to each of its joint axes
MIN_STEP = 1e-4  # rad of |dq|_1: a move whose clearance would need smaller steps is blocked


@dataclass(frozen=True)
class Obstacle:
    """A fixture's bounding cylinder.

    Attributes:
        fixture: its name.
        placement: 4x4 of the cylinder's centre in the robot's base frame (axis z).
        radius: m.
        height: m.
    """

    fixture: str
    placement: np.ndarray
    radius: float
    height: float


def bounding_cylinder(fixture: str, hexa: Hexapod, base_in_robot: np.ndarray, top: float) -> Obstacle:
    """The cylinder enclosing ``hexa`` on its base up to the platform height ``top`` (m, base frame)."""
    import pinocchio as pin

    clm = hexa.closed_loop
    data = clm.model.createData()
    pin.forwardKinematics(clm.model, data, clm.q_home)
    radius = max(float(np.hypot(M.translation[0], M.translation[1])) for M in data.oMi[1:]) + SIDE_MARGIN
    height = top + TOP_MARGIN
    centre = np.eye(4)
    centre[2, 3] = height / 2.0
    return Obstacle(fixture, base_in_robot @ centre, radius, height)


class Clearance:
    """Distances (m) from the UR10's collision geometry to a set of obstacles."""

    def __init__(self, obstacles: list[Obstacle]):
        import coal
        import pinocchio as pin

        self.model, self.collision = ur10_models()
        self.data, self.gdata = self.model.createData(), pin.GeometryData(self.collision)
        self.obstacles = obstacles
        self._shapes = [
            (o.fixture, coal.Cylinder(o.radius, o.height), coal.Transform3s(o.placement[:3, :3], o.placement[:3, 3]))
            for o in obstacles
        ]
        self._request = coal.DistanceRequest()

    def distance(self, q: np.ndarray, ignore: frozenset[str] = frozenset()) -> tuple[float, str, str]:
        """``(d, link, fixture)``: the smallest distance (m) at joints ``q``, and between what; ``inf`` if none."""
        import coal
        import pinocchio as pin

        pin.updateGeometryPlacements(self.model, self.data, self.collision, self.gdata, np.asarray(q, dtype=float))
        best = (float("inf"), "", "")
        result = coal.DistanceResult()
        for i, g in enumerate(self.collision.geometryObjects):
            if g.parentJoint == 0:
                continue  # the robot's base does not move
            M = self.gdata.oMg[i]
            tf = coal.Transform3s(M.rotation, M.translation)
            for name, shape, placement in self._shapes:
                if name in ignore:
                    continue
                result.clear()
                d = coal.distance(g.geometry, tf, shape, placement, self._request, result)
                if d < best[0]:
                    best = (float(d), g.name, name)
        return best

    def walk(
        self, qa: np.ndarray, qb: np.ndarray, required: float, ignore: frozenset[str] = frozenset()
    ) -> tuple[bool, float, float, str, str]:
        """The straight joint move ``qa -> qb`` by conservative advancement.

        Returns:
            ``(ok, d, fraction, link, fixture)``: whether the clearance stays above ``required``
            (m) all along (with ``MIN_STEP`` to spare), the smallest checked clearance (m), and
            where it is (the blocking place when not ``ok``).
        """
        span = float(np.abs(np.asarray(qb) - np.asarray(qa)).sum())
        floor = required + ARM_RADIUS * MIN_STEP
        sigma, worst = 0.0, (float("inf"), 0.0, "", "")
        while True:
            d, link, fixture = self.distance(qa + sigma * (qb - qa), ignore)
            if d < worst[0]:
                worst = (d, sigma, link, fixture)
            if d < floor:
                return (False, d, sigma, link, fixture)
            if sigma >= 1.0 or span == 0.0:
                return (True, *worst)
            sigma = min(1.0, sigma + (d - required) / ARM_RADIUS / span)

    def walk_path(
        self, qs: np.ndarray, required: float, ignore: frozenset[str] = frozenset()
    ) -> tuple[bool, float, int, str, str]:
        """Conservative advancement along the joint samples ``qs`` ((n, 6)), each step a straight line.

        Returns:
            ``(ok, d, index, link, fixture)`` as :meth:`walk`, with the sample's index; not ``ok``
            also when the clearance left cannot certify the step to the next sample.
        """
        step = np.r_[0.0, np.cumsum(np.abs(np.diff(qs, axis=0)).sum(axis=1))]  # |dq|_1 along the path
        floor = required + ARM_RADIUS * MIN_STEP
        k, worst = 0, (float("inf"), 0, "", "")
        while True:
            d, link, fixture = self.distance(qs[k], ignore)
            if d < worst[0]:
                worst = (d, k, link, fixture)
            if d < floor:
                return (False, d, k, link, fixture)
            if k == len(qs) - 1:
                return (True, *worst)
            reach = step[k] + (d - required) / ARM_RADIUS  # every point of the path before it is safe
            nxt = int(np.searchsorted(step, reach, side="right")) - 1
            if nxt <= k:  # not even the next sample is certified: too close to tell
                return (False, d, k, link, fixture)
            k = min(nxt, len(qs) - 1)
