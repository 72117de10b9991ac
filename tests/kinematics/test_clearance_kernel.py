"""The body kernel: exact plate distances, the check against min_clearance, the cone angles."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.kinematics.clearance import ClearanceQuery, query_of
from hexapod_model.kinematics.cones import ConeGeometry, check_cones, cone_limits

ROOT = Path(__file__).resolve().parents[2]
THICK = ROOT / "docs" / "geometries" / "thick_legs.toml"


def _cylinder_distance(a: np.ndarray, b: np.ndarray, M: np.ndarray, R: float, h: float) -> float:
    """Distance of segment ``a b`` (base frame) to a solid cylinder (placement M, radius R, half-height h).

    Dense sampling, then golden-section refinement of the convex distance around the best sample.
    """
    la, lb = M[:3, :3].T @ (a - M[:3, 3]), M[:3, :3].T @ (b - M[:3, 3])

    def f(t):
        x = la + np.multiply.outer(t, lb - la)
        r = np.hypot(x[..., 0], x[..., 1])
        return np.hypot(np.maximum(r - R, 0.0), np.maximum(np.abs(x[..., 2]) - h, 0.0))

    t = np.linspace(0.0, 1.0, 4001)
    k = int(np.argmin(f(t)))
    lo, hi = t[max(k - 1, 0)], t[min(k + 1, len(t) - 1)]
    g = (np.sqrt(5.0) - 1.0) / 2.0
    for _ in range(200):
        m1, m2 = hi - g * (hi - lo), lo + g * (hi - lo)
        lo, hi = (lo, m2) if f(m1) < f(m2) else (m1, hi)
    return float(f(np.array(0.5 * (lo + hi))))


def _placed(hexa: hm.Hexapod, q: np.ndarray, body) -> np.ndarray:
    data = hexa.model.createData()
    pin.forwardKinematics(hexa.model, data, q)
    return (data.oMi[body.parentJoint] * body.placement).homogeneous


def _capsule_to_plate(hexa: hm.Hexapod, q: np.ndarray, capsule, plate) -> float:
    """The exact distance of a capsule (or sphere) and a plate at ``q`` (m), independent of coal and the kernel."""
    Mc, Mp = _placed(hexa, q, capsule), _placed(hexa, q, plate)
    half = getattr(capsule.geometry, "halfLength", 0.0)
    a, b = Mc[:3, 3] - half * Mc[:3, 2], Mc[:3, 3] + half * Mc[:3, 2]
    cyl = plate.geometry
    return _cylinder_distance(a, b, Mp, cyl.radius, cyl.halfLength) - capsule.geometry.radius


@pytest.mark.parametrize("compiled", [False, True])
def test_plate_distances_are_exact(compiled):
    """A capsule's distance to a plate is the exact one to 1e-9 m, in the query and in ``all_pairs``.

    Coal at its default GJK tolerance (1e-6) was up to 1.2 um off for a leg near the platform's rim.
    """
    hexa = hm.Hexapod.from_preset("reference", compiled=compiled, check_body=False)
    query = query_of(hexa)
    objects = query.collision.geometry.geometryObjects
    nearest_plates = 0
    for n, pose in enumerate(box_poses(hexa.home_pose, 30, 5, translation=0.05, angle_deg=25)):
        sol = hexa.inverse(pose, check=False)
        c = query(sol.q)
        if c.pair[1].endswith("_plate"):
            nearest_plates += 1
            capsule, plate = (objects[query.collision.names.index(name)] for name in c.pair)
            assert abs(c.distance - _capsule_to_plate(hexa, sol.q, capsule, plate)) <= 1e-9
            assert abs(np.linalg.norm(c.points[1] - c.points[0]) - c.distance) <= 1e-9
        if n < 4:  # every body's distance to a plate by coal
            distances = query.all_pairs(sol.q)
            for k, (a, b) in enumerate(query.pairs):
                if b.endswith("_plate") and not a.endswith("_plate"):
                    expected = _capsule_to_plate(
                        hexa, sol.q, *(objects[query.collision.names.index(x)] for x in (a, b))
                    )
                    assert abs(distances[k] - expected) <= 1e-9, (a, b)
    assert nearest_plates >= 10  # the rods pass nearest the platform plate in most of these poses


@pytest.mark.parametrize("spec", ["reference", "3-6", "guideway", str(THICK)])
def test_check_is_the_query_below_min_clearance(spec):
    """``check`` reports exactly the poses the full query finds in collision, with the same distance and pair."""
    hexa = hm.Hexapod.load(spec, check_body=False)
    geometry = hexa.geometry
    full = query_of(hexa)
    sols = [
        hexa.inverse(pose, check=False) for pose in box_poses(hexa.home_pose, 30, 2, translation=0.04, angle_deg=30)
    ]
    qs = [sol.q for sol in sols if sol.status in ("converged", "out_of_limits")]
    bound = float(np.median([full(q).distance for q in qs]))  # half of the poses lie closer
    tight = ClearanceQuery(hexa.closed_loop, bound, cones=ConeGeometry(hexa.closed_loop), limits=cone_limits(geometry))
    seen = set()
    for q in qs:
        c, angles = tight.check(q)
        expected = replace(full(q), min_clearance=bound)
        seen.add(expected.collision)
        assert (c is not None) == expected.collision
        if c is not None:
            assert c.distance == expected.distance and c.pair == expected.pair
        cones = check_cones(hexa.closed_loop, geometry, q)
        assert (angles is None) == cones.within
        if angles is not None:
            assert np.max(np.abs(angles - cones.angles)) <= 1e-12
    assert seen == {True, False}


@pytest.mark.parametrize("name", ["reference", "3-6", "spherical", "guideway"])
def test_kernel_cone_angles_are_the_numpy_ones(name):
    """The kernel's cone angles (Cardan angles and ball legs' axes) equal :func:`check_cones` to 1e-12 rad."""
    hexa = hm.Hexapod.from_preset(name, compiled=False, check_body=False)
    geometry = hexa.geometry
    zero = np.zeros((6, 2))  # every joint beyond its cone: the check returns the angles
    query = ClearanceQuery(hexa.closed_loop, 0.0, compiled=False, cones=ConeGeometry(hexa.closed_loop), limits=zero)
    for pose in box_poses(hexa.home_pose, 6, 4, translation=0.03, angle_deg=20):
        sol = hexa.inverse(pose, check=False)
        _, angles = query.check(sol.q)
        assert angles is not None
        assert np.max(np.abs(angles - check_cones(hexa.closed_loop, geometry, sol.q).angles)) <= 1e-12


def test_body_check_verdicts_match_the_separate_checks():
    """The one-call body check flags what the NumPy cones and the full query flag, on 3-6's cones and thick legs."""
    for spec in ("3-6", str(THICK)):
        hexa = hm.Hexapod.load(spec)
        body = hexa.engine.body
        query = query_of(hexa)
        for pose in box_poses(hexa.home_pose, 25, 1, translation=0.05, angle_deg=35):
            sol = hexa.inverse(pose, check=False)
            if sol.q is None or not np.all(np.isfinite(sol.q)):
                continue
            found = dict(body.violations(sol.q))
            assert ("cone_limit" in found) == (not check_cones(hexa.closed_loop, hexa.geometry, sol.q).within)
            c = query(sol.q)
            assert ("collision" in found) == c.collision
            if c.collision:
                assert found["collision"] == c.message()


def test_one_query_shared_by_threads():
    """Each thread works in arrays of its own: answers under concurrency equal the sequential ones, bit for bit."""
    from concurrent.futures import ThreadPoolExecutor

    hexa = hm.Hexapod.load(THICK, check_body=False)
    query = query_of(hexa)
    poses = box_poses(hexa.home_pose, 40, 6, translation=0.05, angle_deg=40)
    qs = [hexa.inverse(pose, check=False).q for pose in poses]
    expected = [(c.distance, c.pair, c.points.tobytes()) for c in map(query, qs)]

    def run(offset: int) -> list:
        order = qs[offset:] + qs[:offset]
        return [(c.distance, c.pair, c.points.tobytes()) for c in map(query, order * 5)]

    with ThreadPoolExecutor(4) as pool:
        for offset, got in zip(range(4), pool.map(run, range(4))):
            assert got == (expected[offset:] + expected[:offset]) * 5


def test_a_single_collision_body_is_named():
    """A URDF with one collision body has no pair to measure: one line, and the solves skip the collision check."""
    import re

    from hexapod_model.description.model import ClosedLoopModel

    text = (ROOT / "urdf" / "reference.urdf").read_text()
    bodies = re.findall(r"\s*<collision .*?</collision>", text, flags=re.S)
    one = re.sub(r"\s*<collision_checking>.*?</collision_checking>", "", text, flags=re.S)
    for body in bodies[1:]:
        one = one.replace(body, "", 1)
    assert one.count("<collision ") == 1
    hexa = hm.Hexapod(ClosedLoopModel(one, "one.urdf"), compiled=False)
    with pytest.raises(hm.UrdfError, match="no pair of collision bodies") as err:
        hexa.clearance(hexa.q_home)
    assert "one.urdf" in str(err.value) and "\n" not in str(err.value)
    assert hexa.inverse(hexa.home_pose).converged
