"""Every assembly accounted for where it can be: the 3-6 resultant in forward(), Hexapod.assemblies."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.lie import pose_distance

from ..conftest import hexapod, limits_only

ROOT = Path(__file__).resolve().parents[2]
SAME = 1e-6  # m, rotations times 0.2 m


def _has(poses, T) -> bool:
    return any(pose_distance(P, T, 0.2) < SAME for P in poses)


def test_cold_results_another_assembly_also_fits_are_ambiguous_with_every_assembly():
    """Readings 0.1 % short of a fold (+-100 mm / +-40 deg): the assembly connected to home and the
    one that produced the readings are 3 to 4 mm apart; the first was returned converged."""
    hexa = limits_only("3-6")
    poses = box_poses(hexa.home_pose, 600, seed=0, translation=0.1, angle_deg=40)
    for i in (13, 544):
        readings = hexa.inverse(poses[i]).lengths
        sol = hexa.forward(readings, check=False)
        assert sol.status == "ambiguous_assembly" and not sol.converged
        every = hexa.assemblies(readings)
        assert every.complete and len(every.solutions) >= 2
        assert len(sol.candidates) == len(every.solutions) and all(_has(sol.candidates, P) for P in every.poses)
        assert _has(sol.candidates, poses[i])  # the generating pose is a candidate
        assert pose_distance(sol.candidates[0], poses[i], 0.2) > 1e-3  # the connected one first, 1-5 mm away
        with pytest.raises(hm.AssemblyError, match="^ambiguous_assembly: .*resultant polynomial"):
            hexa.forward(readings)


def test_blocked_paths_list_every_assembly_within_the_limits():
    """+-150 mm / +-60 deg: the readings path from home meets a fold; two of Newton's candidate lists
    missed the assembly a tracker reaches."""
    hexa = limits_only("3-6")
    poses = box_poses(hexa.home_pose, 400, seed=1, translation=0.15, angle_deg=60)
    for i in (83, 244, 250, 335):
        readings = hexa.inverse(poses[i]).lengths
        sol = hexa.forward(readings, check=False)
        every = hexa.assemblies(readings)
        if len(every.solutions) == 1:  # the only one within the limits: the global answer
            assert sol.converged and "the only assembly" in sol.message
            assert pose_distance(sol.pose, poses[i], 0.2) < SAME
            continue
        assert sol.status == "ambiguous_assembly" and all(_has(sol.candidates, P) for P in every.poses)
        assert _has(sol.candidates, poses[i])


def test_a_cold_result_clearly_nearest_home_stays_converged():
    hexa = limits_only("3-6")
    every = hexa.assemblies(np.zeros(6))
    assert every.complete and len(every.solutions) == 4  # home and three tilted by ~85 deg
    sol = hexa.forward(np.zeros(6))
    assert sol.converged and pose_distance(sol.pose, hexa.home_pose, 0.2) < 1e-12
    T = box_poses(hexa.home_pose, 1, seed=5, translation=0.01, angle_deg=3)[0]
    assert pose_distance(hexa.forward(hexa.inverse(T).lengths).pose, T, 0.2) < 1e-9


def test_the_cones_leave_home_the_only_assembly_of_home_readings():
    """The three assemblies tilted by ~85 deg need 85-90 deg of ball-joint deflection: beyond the 45 deg cone."""
    hexa = hexapod("3-6")
    every = hexa.assemblies(np.zeros(6))
    assert len(every.solutions) == 1 and every.outside == limits_only("3-6").assemblies(np.zeros(6)).outside + 3
    assert pose_distance(every.solutions[0].pose, hexa.home_pose, 0.2) < 1e-12


def test_readings_without_any_real_assembly_are_no_assembly():
    hexa = hexapod("3-6")
    rng = np.random.default_rng(0)
    for _ in range(10):
        readings = rng.uniform(hexa.stroke[:, 0], hexa.stroke[:, 1])
        every = hexa.assemblies(readings)
        if every.solutions or every.outside:
            continue
        sol = hexa.forward(readings, check=False)
        assert sol.status == "no_assembly" and "no real assembly" in sol.message and not sol.closed
        with pytest.raises(hm.WorkspaceError, match="^no_assembly: "):
            hexa.forward(readings)
        return
    pytest.fail("no readings without an assembly drawn")


def test_warm_starts_20_mm_away_with_the_truth_as_near_are_ambiguous():
    """Warm starts 20 mm from the generating pose whose connected assembly is another one, about as
    far from the guess (a fold between them): returned converged before."""
    hexa = limits_only("3-6")
    rng = np.random.default_rng(1)
    checked = 0
    for i, T in enumerate(box_poses(hexa.home_pose, 1500, 0, 0.1, 40.0)):
        truth = hexa.inverse(T, check=False)
        if not truth.converged:
            continue
        d = rng.normal(size=3)
        if i not in (75, 406, 568, 632, 847):
            continue
        moved = T.copy()
        moved[:3, 3] += 0.02 * d / np.linalg.norm(d)
        sol = hexa.forward(truth.lengths, guess=hexa.inverse(moved), check=False)
        assert sol.status == "ambiguous_assembly" and _has(sol.candidates, T)
        checked += 1
    assert checked == 5


def test_the_multi_start_search_finds_the_generating_pose_and_says_it_is_not_complete():
    hexa = hexapod("reference")
    for T in box_poses(hexa.home_pose, 3, seed=7):
        every = hexa.assemblies(hexa.inverse(T).lengths, starts=16)
        assert not every.complete and every.method == "multi-start (16 starts)"
        assert _has(every.poses, T)
        for s in every.solutions:
            np.testing.assert_allclose(s.lengths, hexa.inverse(T).lengths, atol=1e-9)
    with pytest.raises(hm.InputError, match="starts"):
        hexa.assemblies(np.zeros(6), starts=-1)


def test_the_multi_start_search_solves_its_starts_once_and_finds_what_fresh_starts_find():
    """The starts depend on the hexapod and the seed alone: solved once, kept read-only, the same assemblies."""
    hexa, fresh = hexapod("reference"), hm.Hexapod.from_preset("reference")
    finder = hexa.engine.finder
    starts = finder.start_configurations(16, 3)
    assert finder.start_configurations(16, 3) is starts and len(starts) > 10  # home and the closed random poses
    assert not any(q.flags.writeable for q in starts)
    assert finder.start_configurations(16, 4) is not starts
    for T in box_poses(hexa.home_pose, 3, seed=8):
        x = hexa.inverse(T).lengths
        kept = hexa.assemblies(x, starts=16, seed=3)
        assert finder.start_configurations(16, 3) is starts
        new = fresh.assemblies(x, starts=16, seed=3)  # another hexapod object: its own starts, solved anew
        assert len(kept.poses) == len(new.poses) and kept.outside == new.outside
        for a, b in zip(kept.poses, new.poses):
            np.testing.assert_array_equal(a, b)  # the same code path: bit for bit


@pytest.mark.parametrize("kind", ["urdf", "mjcf"])
def test_a_3_6_hexapod_loaded_from_a_file_checks_every_assembly_as_the_preset_does(kind, tmp_path):
    """A URDF or MJCF file carries no geometry: the 3-6 layout is read off the model, so the same
    readings are ambiguous_assembly whatever the hexapod was loaded from (they came back converged)."""
    from hexapod_model.description.mjcf import geometry_to_mjcf
    from hexapod_model.description.urdf import geometry_to_urdf

    geometry = hm.get_preset("3-6")
    path = tmp_path / f"sensor.{'urdf' if kind == 'urdf' else 'xml'}"
    path.write_text(geometry_to_urdf(geometry) if kind == "urdf" else geometry_to_mjcf(geometry))
    loaded, preset = hm.Hexapod.load(path, compiled=False, check_body=False), limits_only("3-6")
    assert loaded.geometry is None
    poses = box_poses(preset.home_pose, 600, seed=0, translation=0.1, angle_deg=40)
    readings = preset.inverse(poses[13]).lengths
    a, b = loaded.forward(readings, check=False), preset.forward(readings, check=False)
    assert a.status == b.status == "ambiguous_assembly"
    assert len(a.candidates) == len(b.candidates) and all(_has(a.candidates, P) for P in b.candidates)
    assert loaded.assemblies(readings).complete


def test_a_spherical_hexapod_from_a_file_is_not_taken_for_a_3_6():
    hexa = hm.Hexapod.from_urdf(ROOT / "urdf" / "spherical.urdf", compiled=False)
    assert not hexa.assemblies(np.zeros(6), starts=4).complete


def _tracker_end(hexa, lengths, steps: int = 256):
    """Where a tracker fed the readings path from home in ``steps`` samples ends (plain Newton,
    each sample warm-started at the last, through folds and determinant sign changes alike)."""
    from hexapod_model.kinematics.newton.solver import NewtonSolver

    fk = NewtonSolver(hexa.closed_loop, hexa.engine.held_forward)
    pq = hexa.closed_loop.prismatic_q
    q = hexa.q_home.copy()
    l0, l1 = q[pq].copy(), hexa.joints_of(lengths)
    for t in np.linspace(0.0, 1.0, steps + 1)[1:]:
        q0 = q.copy()
        q0[pq] = l0 + t * (l1 - l0)
        q, status = fk.run(q0, 1e-12, 30)[:2]
        if status != "converged":
            return None
    return q


@pytest.mark.parametrize(("name", "index"), [("spherical", 494), ("spherical", 2615), ("guideway", 675)])
def test_a_blocked_path_lists_the_assembly_a_tracker_reaches_past_the_fold_first(name, index):
    """Beyond the box (+-100 mm / +-40 deg) on presets without a resultant: the readings path from
    home is blocked near a singularity; two trackers fed that path (256 and 1024 samples) cross it
    and end on one assembly, the one connected to home: the first candidate, flagged ``connected``
    (the readings path proven past the block); it was listed, unmarked. So is the generating pose."""
    hexa = limits_only(name)
    T = box_poses(hexa.home_pose, 4000, seed=7, translation=0.1, angle_deg=40)[index]
    readings = hexa.inverse(T).lengths
    sol = hexa.forward(readings, check=False)
    assert sol.status == "ambiguous_assembly", sol.message
    ends = [_tracker_end(hexa, readings, steps) for steps in (256, 1024)]
    assert all(e is not None for e in ends)
    assert pose_distance(hexa.pose_of(ends[0]), hexa.pose_of(ends[1]), 0.2) < SAME
    assert "connected" in sol.flags and "connected to the start" in sol.message
    assert pose_distance(sol.candidates[0], hexa.pose_of(ends[0]), 0.2) < SAME
    np.testing.assert_array_equal(sol.pose, sol.candidates[0])
    assert _has(sol.candidates, T)


def test_a_path_through_a_fold_marks_no_candidate_connected():
    """+-150 mm / +-60 deg, spherical: the readings path from home meets a fold (trackers of 256 and
    1024 samples end on different assemblies, or stop): no step past it is proven, no candidate marked."""
    hexa = limits_only("spherical")
    T = box_poses(hexa.home_pose, 1500, seed=7, translation=0.15, angle_deg=60)[319]
    readings = hexa.inverse(T).lengths
    sol = hexa.forward(readings, check=False)
    assert sol.status == "ambiguous_assembly" and "connected" not in sol.flags
    ends = [_tracker_end(hexa, readings, steps) for steps in (256, 1024)]
    assert any(e is None for e in ends) or pose_distance(hexa.pose_of(ends[0]), hexa.pose_of(ends[1]), 0.2) > SAME
