"""The assembly certificate (kinematics/certificate.py): a cold result is the assembly connected to
home, what cannot be certified is ``ambiguous_assembly``, a result near a singularity says so.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.jacobian import leg_jacobian_local
from hexapod_model.analysis.trajectories import box_poses, trajectory_poses
from hexapod_model.kinematics.newton.solver import NewtonSolver
from hexapod_model.lie import rpy_to_matrix
from hexapod_model.tracking.tracker import characteristic_length, pose_distance

from ..conftest import PRESET_NAMES, hexapod, limits_only


@functools.cache
def _fk(hexa: hm.Hexapod) -> NewtonSolver:
    """A direct-kinematics solver of its own (the plain Newton iteration, no certificate)."""
    return NewtonSolver(hexa.closed_loop, hexa.engine.held_forward)


def _sign(hexa: hm.Hexapod, q: np.ndarray) -> float:
    """Sign of det G of direct kinematics by a dense LU (numpy), independent of the Schur step."""
    return float(np.linalg.slogdet(_fk(hexa).evaluate(q)[1])[0])


def _connected_end(hexa: hm.Hexapod, lengths: np.ndarray, steps: int = 256) -> np.ndarray | None:
    """Reference: plain Newton along the readings path from home in ``steps`` substeps, the
    determinant sign checked at each; None when the path is blocked.
    """
    fk = _fk(hexa)
    pq = hexa.closed_loop.prismatic_q
    q, s0 = hexa.q_home, _sign(hexa, hexa.q_home)
    for t in np.linspace(0.0, 1.0, steps + 1)[1:]:
        q0 = q.copy()
        q0[pq] = t * hexa.joints_of(lengths)
        q, status = fk.run(q0, 1e-12, 30)[:2]
        if status != "converged" or _sign(hexa, q) != s0:
            return None
    return q


def _ok(sol) -> bool:
    """Returned as good: converged and no flag."""
    return sol.status == "converged" and not getattr(sol, "flags", ())


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_schur_sign_and_condition_bound_against_dense_linear_algebra(name):
    hexa = limits_only(name)  # poses beyond the cones too: the linear algebra does not care
    solver = _fk(hexa)
    rng = np.random.default_rng(5)
    legs = hexa.closed_loop.limited_q()
    closed = [hexa.inverse(T).q for T in box_poses(hexa.home_pose, 8, seed=9)]
    layout = None
    for q in closed + [q + np.isin(np.arange(q.size), legs) * rng.normal(scale=0.05, size=q.size) for q in closed]:
        solver.iterate(q, np.inf, 0)
        assert solver._solve_step() > 1e-9
        ratio = solver.sign * _sign(hexa, q)  # the sign of det G up to a constant of the layout
        layout = ratio if layout is None else layout
        assert ratio == layout
        s = np.linalg.svd(leg_jacobian_local(hexa, q)[0], compute_uv=False)  # M = -J_local
        assert solver.kappa >= s[0] / s[-1] * (1 - 1e-9)  # an upper bound of the condition number


def test_warm_starts_along_a_trajectory_are_certified_at_no_extra_step():
    hexa = hexapod("reference")
    _, poses = trajectory_poses("A", hexa.home_pose, characteristic_length(hexa) / 50)
    sol = hexa.forward(hexa.inverse(poses[0]).lengths)
    for T in poses[1:400]:
        sol = hexa.forward(hexa.inverse(T, guess=sol).lengths, guess=sol, tol=1e-10)
        assert sol.converged and sol.flags == () and sol.iterations == 2 and sol.det_sign == -1
        assert pose_distance(sol.pose, T, 0.25) < 1e-9


def test_cold_readings_whose_path_from_home_is_blocked_are_ambiguous():
    """+-150 mm / +-60 deg on the 3-6 preset: the straight readings path from home meets a fold
    (checked by a dense reference continuation). The plain solve returned the pose as converged.
    (The path's own verdict: without the resultant's every assembly, tests/kinematics/test_all_assemblies.py.)"""
    hexa = hm.Hexapod.from_preset("3-6", check_body=False)  # the stroke and joint limits alone
    hexa.engine.finder.exact = None  # Newton's readings path alone
    poses = box_poses(hexa.home_pose, 400, seed=1, translation=0.15, angle_deg=60)
    for i in (83, 244, 250, 335):
        lengths = hexa.inverse(poses[i]).lengths
        assert _connected_end(hexa, lengths) is None
        sol = hexa.forward(lengths, check=False)
        assert sol.status == "ambiguous_assembly" and not sol.converged
        assert any(pose_distance(P, poses[i], 0.2) < 1e-9 for P in sol.candidates)
        for P in sol.candidates:  # every candidate is an assembly for these readings
            np.testing.assert_allclose(hexa.inverse(P).lengths, lengths, atol=1e-9)
        with pytest.raises(hm.AssemblyError, match="ambiguous_assembly: cannot certify") as err:
            hexa.forward(lengths)
        assert len(err.value.result.candidates) == len(sol.candidates)


def test_cold_readings_next_to_a_fold_are_not_returned_as_ok():  # the stroke and joint limits alone
    """Readings 0.1 % short of a fold: the connected assembly and the one that produced the
    readings are 3 to 4 mm apart. The plain solve returned the former as converged."""
    hexa = limits_only("3-6")
    poses = box_poses(hexa.home_pose, 600, seed=0, translation=0.1, angle_deg=40)
    for i in (13, 544):
        sol = hexa.forward(hexa.inverse(poses[i]).lengths, check=False)
        assert 1e-3 < pose_distance(sol.pose, poses[i], 0.2) < 5e-3
        assert not _ok(sol)


def test_warm_starts_2_mm_away_that_land_on_another_assembly_say_so():
    hexa = limits_only("3-6")  # the stroke and joint limits alone
    poses = box_poses(hexa.home_pose, 5000, seed=0, translation=0.1, angle_deg=40)
    directions = np.random.default_rng(1).normal(size=(5000, 3))
    for i in (1288, 3862):
        moved = poses[i].copy()
        moved[:3, 3] += 0.002 * directions[i] / np.linalg.norm(directions[i])
        guess = hexa.inverse(moved)
        sol = hexa.forward(hexa.inverse(poses[i]).lengths, guess=guess, check=False)
        assert pose_distance(sol.pose, poses[i], 0.2) > 1e-4  # another assembly, 1 to 2 mm away
        assert not _ok(sol)
        assert sol.status == "ambiguous_assembly" or sol.flags == ("near_singular",)


@pytest.mark.parametrize("name", ["3-6", "spherical"])
def test_cold_results_beyond_the_box_are_the_truth_or_the_assembly_connected_to_home(name):
    hexa = hexapod(name)
    checked = 0
    for T in box_poses(hexa.home_pose, 150, seed=3, translation=0.1, angle_deg=40):
        truth = hexa.inverse(T, check=False)
        if not truth.converged:
            continue
        sol = hexa.forward(truth.lengths, check=False)
        if _ok(sol) and pose_distance(sol.pose, T, 0.2) > 1e-9:
            end = _connected_end(hexa, truth.lengths)
            assert end is not None and pose_distance(hexa.pose_of(end), sol.pose, 0.2) < 1e-9
            assert _sign(hexa, truth.q) != _sign(hexa, hexa.q_home)  # the truth is across a singularity
            checked += 1
        elif sol.status == "ambiguous_assembly":
            assert sol.candidates and np.array_equal(sol.pose, sol.candidates[0])
    if name == "3-6":  # every assembly is accounted for (the resultant): none converged but another
        assert checked == 0


def test_a_guess_that_does_not_close_is_followed_from_its_own_readings():
    hexa = hexapod("reference")
    rng = np.random.default_rng(2)
    for T in box_poses(hexa.home_pose, 10, seed=4):
        truth = hexa.inverse(T)
        q = truth.q.copy()
        legs = hexa.closed_loop.limited_q()
        q[legs] += rng.normal(scale=0.2, size=legs.size)  # leg joints off: the guess does not close
        q[hexa.closed_loop.prismatic_q] = truth.lengths + rng.normal(scale=0.03, size=6)
        sol = hexa.forward(truth.lengths, guess=q)
        assert _ok(sol) and pose_distance(sol.pose, T, 0.25) < 1e-9


def test_a_warm_result_at_a_singularity_is_flagged_and_not_converged():
    """The spherical preset is singular at 90 deg of yaw about its home position."""
    hexa = hexapod("spherical")

    def at(yaw_deg: float) -> hm.Solution:
        T = hexa.home_pose.copy()
        T[:3, :3] = rpy_to_matrix(0.0, 0.0, np.radians(yaw_deg))
        return hexa.inverse(T)

    before, singular = at(89.0), at(90.0)
    sol = hexa.forward(singular.lengths, guess=before, check=False)
    assert sol.status == "uncertified" and not sol.converged
    assert sol.flags == ("near_singular",) and "near a singularity" in sol.message
    far = hexa.forward(at(60.0).lengths, guess=at(59.0))
    assert far.converged and far.flags == ()


#: spherical preset, hair-thin bodies: no collision decides here, only the cones
SLIM = {"leg_radius": 1e-4, "housing_radius": 2e-4, "plate_thickness": 1e-4}
SLIM_PLATES = {"base_plate_radius": 1e-3, "platform_plate_radius": 1e-3}


def test_a_blocked_paths_candidates_are_within_the_cones():
    """A warm start 30 mm / 15 deg off: the path is blocked at once; Newton's candidates hold the assembly
    the proven path reaches and a rival whose base joints deflect 50 deg. With 45 deg base cones the
    rival is no candidate (it was listed); with the default 20 mm legs both collide: no candidate."""
    from dataclasses import replace

    T, G = np.eye(4), np.eye(4)  # the generating pose and the guess
    T[:3, 3] = [0.11601710548415842, -0.06001226601678739, 0.3710966000536987]
    T[:3, :3] = rpy_to_matrix(-0.45179485491487503, -0.8585477551993077, -0.37444946220325315)
    G[:3, 3] = [0.15271145132397554, -0.10569699214224648, 0.37259958315059577]
    G[:3, :3] = rpy_to_matrix(-0.6444145273334886, -0.9254348096504367, -0.17304477080103886)
    slim = replace(hm.get_preset("spherical"), **SLIM, **SLIM_PLATES)
    bare = hm.Hexapod.from_geometry(slim, compiled=False)
    readings = bare.inverse(T).lengths
    free = bare.forward(readings, bare.inverse(G), check=False)
    assert free.status == "ambiguous_assembly" and len(free.candidates) == 2 and "connected" in free.flags
    coned = hm.Hexapod.from_geometry(replace(slim, base_cone=np.radians(45.0)), compiled=False)
    assert [coned.inverse(C, check=False).status for C in free.candidates] == ["converged", "cone_limit"]
    sol = coned.forward(readings, coned.inverse(G), check=False)
    assert sol.status == "ambiguous_assembly" and len(sol.candidates) == 1 and "connected" in sol.flags
    assert all(coned.inverse(C, check=False).converged for C in sol.candidates)  # within every limit and cone
    np.testing.assert_allclose(sol.candidates[0], free.candidates[0], rtol=0, atol=1e-12)
    assert "1 of 2 candidates lies beyond a cone" in sol.message
    thick = hm.Hexapod.from_preset("spherical", compiled=False)
    assert [thick.inverse(C, check=False).status for C in free.candidates] == ["collision", "collision"]
    none = thick.forward(readings, thick.inverse(G, check=False), check=False)
    assert none.status == "out_of_limits" and not none.candidates and "every assembly found lies beyond" in none.message
