"""A hexapod scaled by 0.05 (a 1 cm base radius) or by 10 (2 m) gets the same answers, to scale.

On every path of a solve (the compiled one, the NumPy kernels, the general Pinocchio solver) and
in the batch loops: the same statuses, flags and candidates as the preset's, poses equal to the
preset's scaled ones, the same Newton step counts. The solver's constants in metres (stopping
tolerance, step cap, one-step threshold, intermediate tolerance of the readings path, assembly
distances) scale with the geometry's length scale, its angles do not.

The length scale is the power of two nearest the size ratio (the presets' constants stay exact),
so a geometry scaled by 8 or 1/16 has exactly the preset's thresholds, to scale: equal step
counts. Scaled by 10 or 0.05 its thresholds are the preset's times 0.8 or 1.25 (``s / k``): a
residual that lands between the two (a few solves in a hundred) costs or saves one Newton step,
so the counts of converged results are compared to one step there. A result that is not
converged (out of reach, no assembly, a blocked readings path) spent tens of readings-path
substeps, each refused or accepted on such thresholds, and its count is not compared off the
powers of two. Nor, in the batch, which failure its random readings end in (``not_found`` or
``out_of_limits``: where the stalled iteration stops): only that it is not ``converged``.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.description.geometry import geometry_from_dict
from hexapod_model.kinematics.newton.solver import NewtonSolver, Solution
from hexapod_model.lie import pose_distance

PATHS = ("compiled", "numpy", "general")
POSE_TOL = 1e-10  # m per unscaled metre, rad: a scaled result, unscaled, against the preset's
UNSETTLED_SLACK = 10**6  # steps of a result not converged, off the powers of two: not compared (module doc)
FACTORS = [0.05, 10.0, 1 / 16, 8.0]  # the sizes, and two whose length scale is the factor itself


def scaled(geometry: hm.HexapodGeometry, factor: float) -> hm.HexapodGeometry:
    """``geometry`` with every length (its body's and its encoder noise too) times ``factor`` (angles unchanged)."""
    d = geometry.to_dict()
    for key in ("home_height", "base_offset", "platform_offset"):
        d[key] *= factor
    for leg in d["legs"]:
        for key in ("base_anchor", "platform_anchor", "stroke"):
            leg[key] = [v * factor for v in leg[key]]
        for key in ("base_offset", "platform_offset", "encoder_zero"):
            if key in leg:
                leg[key] *= factor
    for key in ("leg_radius", "housing_radius", "plate_thickness", "min_clearance"):  # the body, too
        d[key] = getattr(geometry, key) * factor
    for key in ("base_plate_radius", "platform_plate_radius"):
        if getattr(geometry, key) is not None:
            d[key] = getattr(geometry, key) * factor
    for leg in d["legs"]:
        if "leg_radius" in leg:
            leg["leg_radius"] *= factor
    d["encoder_sigma"] = geometry.encoder_sigma * factor  # the sensor's noise too (the 3-6 near-fold reach)
    d["name"] = f"{geometry.name}_scaled"
    return geometry_from_dict(d)


@functools.cache
def on_path(name: str, factor: float, path: str) -> hm.Hexapod:
    """Preset ``name`` scaled by ``factor`` (1: the preset), solved on ``path``.

    ``general``: the calling thread's direct- and inverse-kinematics solvers are the general
    (Pinocchio) ones, as for a model the compiled layout does not fit.
    """
    geometry = hm.get_preset(name) if factor == 1.0 else scaled(hm.get_preset(name), factor)
    hexa = hm.Hexapod.from_geometry(geometry, compiled=path == "compiled")
    if path == "general":
        held = (hexa.engine.held_forward, hexa.engine.held_inverse)
        hexa.engine.local.solvers = {h: NewtonSolver(hexa.closed_loop, h) for h in held}
    return hexa


def step_slack(unit: hm.Hexapod, big: hm.Hexapod, factor: float) -> int:
    """Newton steps two solves may differ by: 0 when the length scales are in the ratio ``factor``, else 1."""
    return 0 if big.scale == unit.scale * factor else 1


def assert_same_to_scale(a: Solution, b: Solution, factor: float, slack: int) -> None:
    """``b`` (scaled geometry) is ``a`` (the preset) to scale: status, flags, candidates, steps (to ``slack``), pose."""
    assert (b.status, b.flags, len(b.candidates)) == (a.status, a.flags, len(a.candidates))
    assert abs(b.iterations - a.iterations) <= (slack if a.converged or not slack else UNSETTLED_SLACK)
    if a.closed:
        Pb = b.pose.copy()
        Pb[:3, 3] /= factor
        assert pose_distance(Pb, a.pose, 0.2) < POSE_TOL
        np.testing.assert_allclose(b.lengths / factor, a.lengths, rtol=0, atol=POSE_TOL)


def pair(name: str, factor: float, path: str) -> tuple[hm.Hexapod, hm.Hexapod, int]:
    """The preset, it scaled by ``factor``, both on ``path``, and the step counts' slack (:func:`step_slack`)."""
    unit, big = on_path(name, 1.0, path), on_path(name, factor, path)
    return unit, big, step_slack(unit, big, factor)


sizes = pytest.mark.parametrize("factor", FACTORS)
presets = pytest.mark.parametrize("name", ["reference", "3-6", "spherical"])


@pytest.mark.slow
@pytest.mark.parametrize("path", PATHS)
@sizes
@presets
def test_scaled_geometries_give_the_same_statuses_steps_and_poses_to_scale(name, factor, path):
    unit, big, slack = pair(name, factor, path)
    rng = np.random.default_rng(3)
    statuses = set()
    for T in box_poses(unit.home_pose, 25, seed=11, translation=0.1, angle_deg=40):
        S = T.copy()
        S[:3, 3] *= factor
        a, b = unit.inverse(T, check=False), big.inverse(S, check=False)
        assert_same_to_scale(a, b, factor, slack)
        statuses.add(a.status)
        if not a.closed:
            continue
        la = np.clip(a.lengths, *unit.stroke.T)
        fa, fb = unit.forward(la, check=False), big.forward(la * factor, check=False)  # cold, from home
        assert_same_to_scale(fa, fb, factor, slack)
        statuses.add(fa.status)
        for spread in (1e-5, 3e-3):  # warm: 10 um and 3 mm (times the factor) from the guess's readings
            lw = np.clip(la + rng.normal(scale=spread, size=6), *unit.stroke.T)
            fa, fb = unit.forward(lw, a, check=False), big.forward(lw * factor, b, check=False)
            assert_same_to_scale(fa, fb, factor, slack)
    assert "converged" in statuses and len(statuses) > 1  # the box reaches beyond the workspace


@pytest.mark.slow
@pytest.mark.parametrize("path", PATHS[:2])
@sizes
@presets
def test_scaled_geometries_give_the_same_batch_results_to_scale(name, factor, path):
    unit, big, slack = pair(name, factor, path)
    rng = np.random.default_rng(4)
    poses = box_poses(unit.home_pose, 20, seed=12, translation=0.1, angle_deg=40)
    reachable = unit.inverse_batch(poses).lengths
    readings = np.vstack([reachable[np.isfinite(reachable[:, 0])], rng.uniform(*unit.stroke.T, size=(8, 6))])
    for warm in (False, True):
        a, b = unit.forward_batch(readings, warm=warm), big.forward_batch(readings * factor, warm=warm)
        settled = (a.status == "converged") | (slack == 0)
        assert np.all((b.status == a.status) | (~settled & (b.status != "converged")))
        assert [f for f, ok in zip(b.flags, settled) if ok] == [f for f, ok in zip(a.flags, settled) if ok]
        assert np.all(np.abs(b.iterations - a.iterations) <= np.where(settled, slack, UNSETTLED_SLACK))
        ok = np.isfinite(a.poses[:, 0, 0])
        np.testing.assert_array_equal(np.isfinite(b.poses[:, 0, 0]), ok)
        for Pa, Pb in zip(a.poses[ok], b.poses[ok]):
            Pb = Pb.copy()
            Pb[:3, 3] /= factor
            assert pose_distance(Pb, Pa, 0.2) < POSE_TOL
    S = poses.copy()
    S[:, :3, 3] *= factor
    a, b = unit.inverse_batch(poses), big.inverse_batch(S)
    assert list(b.status) == list(a.status) and np.all(np.abs(b.iterations - a.iterations) <= slack)
    np.testing.assert_allclose(b.lengths / factor, a.lengths, rtol=0, atol=POSE_TOL)


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("factor", [1 / 16, 8.0])
@presets
def test_condition_figures_are_scale_free(name, factor, path):
    # the home conditioning check and the near_singular flag's condition bound (relative to home's)
    unit, big, _ = pair(name, factor, path)
    assert big.home_condition_number == pytest.approx(unit.home_condition_number, rel=1e-9)
    su, sb = unit.engine.solver(unit.engine.held_forward), big.engine.solver(big.engine.held_forward)
    assert sb.home_kappa == pytest.approx(su.home_kappa, rel=1e-9)
    for T in box_poses(unit.home_pose, 10, seed=13, translation=0.1, angle_deg=40):
        S = T.copy()
        S[:3, 3] *= factor
        a, b = unit.inverse(T, check=False), big.inverse(S, check=False)
        if a.converged:
            fa, fb = unit.forward(a.lengths, a, check=False), big.forward(b.lengths, b, check=False)
            assert (fa.status, fb.status) == ("converged", "converged")
            assert sb.kappa == pytest.approx(su.kappa, rel=1e-6)


@pytest.mark.parametrize("factor", [1 / 64, 256.0])  # a 3 mm and a 51 m base radius
def test_three_six_assemblies_and_solves_to_scale_far_from_the_presets(factor):
    unit, big, slack = pair("3-6", factor, "numpy")
    assert slack == 0
    for T in box_poses(unit.home_pose, 8, seed=5, translation=0.05, angle_deg=20):
        a = unit.inverse(T, check=False)
        if not a.converged:
            continue
        A, B = unit.assemblies(a.lengths), big.assemblies(a.lengths * factor)
        assert len(B.solutions) == len(A.solutions) and B.complete == A.complete
        for sa, sb in zip(A.solutions, B.solutions):
            assert_same_to_scale(sa, sb, factor, 0)
        fa, fb = unit.forward(a.lengths, check=False), big.forward(a.lengths * factor, check=False)
        assert_same_to_scale(fa, fb, factor, 0)


def held_values(hexa: hm.Hexapod, q: np.ndarray, passive: str, step: np.ndarray, factor: float) -> dict:
    """Five prismatic joints (not leg 5's) and joint ``passive`` of ``q``, moved by ``step`` (m times ``factor``, rad).

    Within their limits.
    """
    clm = hexa.closed_loop
    legs = [0, 1, 2, 3, 5]  # leg 5 free, leg 6 holds two joints: no structured step, the general solver
    pq, iq = clm.prismatic_q[legs], hexa.model.joints[hexa.model.getJointId(passive)].idx_q
    values = np.clip(q[pq] + step[:5] * factor, clm.lower[pq], clm.upper[pq])
    return dict(zip([hexa.prismatic_names[i] for i in legs], values)) | {
        passive: float(np.clip(q[iq] + step[5], clm.lower[iq], clm.upper[iq]))
    }


@pytest.mark.parametrize("factor", FACTORS)
@presets
def test_hybrid_solves_on_the_general_path_to_scale(name, factor):
    # five prismatic joints and a Cardan angle of leg 6 held: the general solver (no structured step)
    unit, big, slack = pair(name, factor, "compiled")
    assert unit.engine.solver(held_ids(unit)).one_call is None
    passive = "leg6_cardan_base_1"
    rng, statuses = np.random.default_rng(6), []
    for T in box_poses(unit.home_pose, 10, seed=14, translation=0.1, angle_deg=40):
        a, b = unit.inverse(T, check=False), big.inverse(scaled_pose(T, factor), check=False)
        if not a.converged:
            continue
        # each held set from its own hexapod's solution (the scaled geometry file rounds its numbers)
        for step in (np.zeros(6), rng.normal(scale=3e-3, size=6)):  # cold from home; warm, 3 mm / 3 mrad away
            guesses = (None, None) if not step.any() else (a, b)
            sa = unit.solve(held_values(unit, a.q, passive, step, 1.0), guesses[0], check=False)
            sb = big.solve(held_values(big, b.q, passive, step, factor), guesses[1], check=False)
            assert_same_to_scale(sa, sb, factor, slack)
            statuses.append(sa.status)
    assert statuses.count("converged") >= len(statuses) // 2


def held_ids(hexa: hm.Hexapod) -> tuple[int, ...]:
    """The joint ids :func:`held_values` holds."""
    names = [hexa.prismatic_names[i] for i in (0, 1, 2, 3, 5)] + ["leg6_cardan_base_1"]
    return tuple(sorted(hexa.model.getJointId(n) for n in names))


def scaled_pose(T: np.ndarray, factor: float) -> np.ndarray:
    """``T`` with its translation times ``factor``."""
    S = T.copy()
    S[:3, 3] *= factor
    return S
