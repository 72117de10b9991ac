"""Standard Stewart-Gough model, full (eq. 6) vs reduced formulation, and `hexapod reproduce`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import hexapod_model as hm
from hexapod_model.analysis.full_formulation import ForwardComparison, FullFormulation, pinv_step
from hexapod_model.analysis.standard import StandardModel
from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.cli.main import main
from hexapod_model.description.model import ClosedLoopModel
from hexapod_model.description.urdf import geometry_to_urdf
from hexapod_model.exceptions import InputError
from hexapod_model.lie import exp3
from hexapod_model.studies.paper_table import ttest_rel
from hexapod_model.studies.reproduce import load_measured, pose_errors, simulate

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "measured.csv"
REPORT_KEYS = {"translation_mean_mm", "translation_std_mm", "rotation_mean_deg", "rotation_std_deg"}


@pytest.fixture(scope="module")
def reference():
    return hm.Hexapod.from_preset("reference")


def feasible(hexa, n, seed, **kw):
    """Poses of the Bem et al. (2026) box that the Cardan-aware IK accepts, with their tight solutions."""
    out = []
    for T in box_poses(hexa.home_pose, 3 * n, seed=seed, **kw):
        sol = hexa.inverse(T, tol=1e-13, max_iter=50, check=False)
        if sol.converged:
            out.append((T, sol))
        if len(out) == n:
            return out
    raise AssertionError("too few feasible poses")


@pytest.mark.parametrize("preset", ["intersecting", "spherical"])
def test_standard_model_is_exact_without_offsets(preset):
    hexa = hm.Hexapod.from_preset(preset)
    sm = StandardModel.from_geometry(hexa.geometry)
    pairs = feasible(hexa, 15, seed=3)
    poses = np.array([T for T, _ in pairs])
    lengths = np.array([s.lengths for _, s in pairs])
    np.testing.assert_allclose(sm.inverse(poses), lengths, atol=1e-9)
    fk = sm.forward(lengths)
    assert fk.converged.all()
    np.testing.assert_allclose(fk.poses, poses, atol=1e-9)
    for T, l in zip(poses[:5], sm.inverse(poses[:5])):  # and the other way round
        np.testing.assert_allclose(hexa.forward(l, tol=1e-13, max_iter=50).pose, T, atol=1e-9)


def test_standard_model_is_off_by_millimetres_with_offset_cardans(reference):
    sm = StandardModel.from_geometry(reference.geometry)
    pairs = feasible(reference, 20, seed=4)
    fk = sm.forward(np.array([s.lengths for _, s in pairs]))
    err = np.linalg.norm(fk.poses[:, :3, 3] - np.array([T[:3, 3] for T, _ in pairs]), axis=1)
    assert fk.converged.all()
    assert 1e-4 < err.max() < 2e-2  # 0.1 mm .. 2 cm: a real but modest model error


def test_centres_read_from_the_urdf_match_the_geometry(reference):
    bare = hm.Hexapod(ClosedLoopModel(geometry_to_urdf(reference.geometry)))  # no geometry attached
    a, b = StandardModel.from_hexapod(bare), StandardModel.from_geometry(reference.geometry)
    np.testing.assert_allclose(a.base_points, b.base_points, atol=1e-12)
    np.testing.assert_allclose(a.platform_points, b.platform_points, atol=1e-12)
    np.testing.assert_allclose(a.home_lengths, b.home_lengths, atol=1e-12)
    with pytest.raises(hm.HexapodError):
        StandardModel.from_geometry(hm.Hexapod.from_preset("guideway").geometry)


def test_standard_jacobian_matches_finite_differences(reference):
    sm = StandardModel.from_geometry(reference.geometry)
    poses = box_poses(reference.home_pose, 4, seed=5)
    J = sm.jacobian(poses)
    eps = 1e-6
    for k in range(6):
        d = np.zeros((len(poses), 6))
        d[:, k] = eps
        plus, minus = poses.copy(), poses.copy()
        for T, s in ((plus, 1), (minus, -1)):
            T[:, :3, 3] += s * d[:, :3]
            T[:, :3, :3] = exp3(s * d[:, 3:]) @ T[:, :3, :3]
        fd = (sm.centre_distances(plus) - sm.centre_distances(minus)) / (2 * eps)
        np.testing.assert_allclose(J[:, :, k], fd, atol=1e-8)


def test_standard_forward_flags_bad_rows_and_shapes(reference):
    sm = StandardModel.from_geometry(reference.geometry)
    readings = np.zeros((3, 6))
    readings[1, 2] = np.nan
    res = sm.forward(readings)
    assert res.converged.tolist() == [True, False, True]
    np.testing.assert_allclose(res.poses[0], reference.home_pose, atol=1e-12)
    with pytest.raises(InputError):
        sm.forward(np.zeros(5))
    with pytest.raises(InputError):
        sm.inverse(np.eye(3))


def test_full_and_reduced_formulations_give_the_same_pose(reference):
    fc = ForwardComparison(reference)
    for T, sol in feasible(reference, 4, seed=6):
        full, red = fc.traces(sol.lengths)
        assert full.converged and red.converged
        np.testing.assert_allclose(reference.pose_of(full.q), T, atol=1e-9)
        np.testing.assert_allclose(reference.pose_of(red.q), reference.pose_of(full.q), atol=1e-9)
        for tr in (full, red):
            assert tr.iterations == tr.times.size == tr.conditions.size
            assert np.all(np.diff(tr.times) > 0) and np.all(tr.conditions >= 1)
            assert tr.step_norms[-1] < 1e-6 * tr.step_norms[0]
    assert fc.full.G.shape[0] == 72 and fc.reduced.G.shape[0] == 36


def test_pinv_step_equals_the_svd_pseudo_inverse():
    rng = np.random.default_rng(4)
    for rows, decades in ((72, 0.0), (72, 2.0), (36, 1.5), (36, 3.5)):
        J = (
            rng.normal(size=(rows, 36))
            @ np.diag(np.logspace(0, decades, 36))
            @ np.linalg.qr(rng.normal(size=(36, 36)))[0]
        )
        f = rng.normal(size=rows)
        dx, cond = pinv_step(J, f)
        np.testing.assert_allclose(dx, -np.linalg.pinv(J) @ f, rtol=1e-8, atol=1e-12)
        assert cond == pytest.approx(np.linalg.cond(J), rel=1e3 * np.finfo(float).eps * np.linalg.cond(J) ** 2)
    J[:, 0] = J[:, 1]  # rank deficient: the SVD branch, minimum-norm step
    dx, cond = pinv_step(J, f)
    np.testing.assert_allclose(dx, -np.linalg.pinv(J, rcond=1e-14) @ f, rtol=1e-6, atol=1e-12)
    assert cond > 1e12


def test_full_jacobian_matches_finite_differences(reference):
    ff = FullFormulation(reference.closed_loop, tuple(leg.prismatic for leg in reference.closed_loop.legs))
    m = reference.model
    rng = np.random.default_rng(0)
    dv = np.zeros(m.nv)
    dv[ff.free_v] = rng.normal(0, 0.05, ff.free_v.size)
    q = pin.integrate(m, feasible(reference, 1, seed=7)[0][1].q, dv)  # off the constraint manifold
    r, G = ff.evaluate(q)
    assert np.linalg.norm(r) > 1e-3
    eps, fd = 1e-6, np.zeros_like(G)
    for k, j in enumerate(ff.free_v):
        e = np.zeros(m.nv)
        e[j] = eps
        fd[:, k] = (ff.evaluate(pin.integrate(m, q, e))[0] - ff.evaluate(pin.integrate(m, q, -e))[0]) / (2 * eps)
    np.testing.assert_allclose(G, fd, atol=1e-8)


def test_full_formulation_on_ball_joint_closures():
    hexa = hm.Hexapod.from_preset("spherical")
    fc = ForwardComparison(hexa)
    T, sol = feasible(hexa, 1, seed=8)[0]
    full, red = fc.traces(sol.lengths)
    assert fc.full.G.shape[0] == 18
    np.testing.assert_allclose(hexa.pose_of(full.q), T, atol=1e-9)


def test_reference_noise_shows_in_the_cardan_errors(reference):
    sigma = 1e-3
    data = simulate(reference, 80, seed=1, encoder_noise=0.0, reference_noise=sigma)
    est = np.array([reference.forward(l).pose for l in data.readings])
    dp, dth = pose_errors(data.reference, est)
    # mean norm of a 3-D Gaussian is 1.596 sigma
    assert 1.2 < np.mean(dp) / (sigma * 1e3) < 2.0
    assert np.mean(dth) > 0


@pytest.mark.filterwarnings("ignore:Precision loss:RuntimeWarning")  # scipy on the identical samples
def test_paired_t_test_equals_scipy_stats():
    from scipy.stats import ttest_rel as scipy_ttest_rel

    rng = np.random.default_rng(3)
    cases = [(np.ones(5), np.ones(5)), (2 * np.ones(5), np.ones(5)), (np.arange(2.0), np.arange(2.0) + [0, 1])]
    for n, scale in ((2, 1.0), (3, 1e-3), (60, 10.0), (3000, 1e-6), (3000, 1.0)):
        a = np.abs(rng.normal(0, scale, n))
        cases.append((a, np.abs(a + rng.normal(0.1 * scale, scale, n))))
    for a, b in cases:
        with np.errstate(all="ignore"):
            ref = scipy_ttest_rel(a, b)
        # another implementation (and version) of the same formula: t and p to 1e-12 relative, NaN as NaN
        np.testing.assert_allclose(ttest_rel(a, b), (ref.statistic, ref.pvalue), rtol=1e-12, atol=0)


def _reproduce(tmp_path, *extra):
    out = tmp_path / "json.json"
    code = main(["reproduce", "--json", str(out), *extra])
    return code, (json.loads(out.read_text()) if out.exists() else None)


def test_reproduce_small_run_writes_json_and_figures(tmp_path, capsys):
    code, report = _reproduce(
        tmp_path, "--poses", "60", "--seed", "2", "--convergence-poses", "8", "--out", str(tmp_path / "fig")
    )
    assert code == 0
    assert set(report) == {"poses", "cardan", "spherical", "t_test"}
    assert report["poses"] == 60
    assert set(report["cardan"]) == set(report["spherical"]) == REPORT_KEYS
    assert set(report["t_test"]) == {"translation", "rotation"}
    assert all(set(v) == {"t", "p"} for v in report["t_test"].values())
    assert report["cardan"]["translation_mean_mm"] < report["spherical"]["translation_mean_mm"]
    assert report["t_test"]["translation"]["t"] < 0
    text = capsys.readouterr().out
    assert "0.6205" in text and "3.1684" in text  # the paper's column
    names = sorted(p.name for p in (tmp_path / "fig").glob("*.png"))
    assert names == [
        "reproduce_conditioning.png",
        "reproduce_convergence.png",
        "reproduce_errors_cardan.png",
        "reproduce_errors_standard.png",
        "reproduce_histograms.png",
    ]
    assert all((tmp_path / "fig" / n).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for n in names)


def test_interrupted_reproduce_leaves_no_empty_figure_folder(tmp_path, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("hexapod_model.cli.reproduce.run_study", interrupted)
    out = tmp_path / "new" / "figures"
    assert main(["reproduce", "--poses", "10", "--out", str(out)]) == 130
    assert not (tmp_path / "new").exists()
    (tmp_path / "kept").mkdir()  # a folder that was there before stays, with what it holds
    (tmp_path / "kept" / "mine.txt").write_text("x")
    assert main(["reproduce", "--poses", "10", "--out", str(tmp_path / "kept" / "fig")]) == 130
    assert sorted(p.name for p in (tmp_path / "kept").iterdir()) == ["mine.txt"]


def test_reproduce_on_the_measured_example(tmp_path):
    code, report = _reproduce(tmp_path, "--data", str(EXAMPLE), "--convergence-poses", "0")
    assert code == 0
    assert report["poses"] == len(load_measured(EXAMPLE).readings)
    assert set(report["cardan"]) == REPORT_KEYS


@pytest.mark.parametrize(
    "content, words",
    [
        ("l1,l2,l3,l4,l5,l6,x,y,z\n0,0,0,0,0,0,0,0,0.4\n", ["missing columns", "qx"]),
        (
            "l1,l2,l3,l4,l5,l6,x,y,z,qx,qy,qz,qw\n0,0,0,0,0,0,0,0,0.4,0,0,0,1\n0,0,zz,0,0,0,0,0,0.4,0,0,0,1\n",
            ["line 3"],
        ),
        (
            "l1,l2,l3,l4,l5,l6,x,y,z,qx,qy,qz,qw\n0,0,0,0,0,0,0,0,0.4,0,0,0,1\n0,0,0,0,0,0,0,0,0.4,0,0,0,2\n",
            ["unit quaternion"],
        ),
    ],
)
def test_reproduce_rejects_bad_data_files(tmp_path, capsys, content, words):
    bad = tmp_path / "bad.csv"
    bad.write_text(content)
    code, report = _reproduce(tmp_path, "--data", str(bad))
    err = capsys.readouterr().err
    assert code != 0 and report is None
    assert all(w in err for w in words), err


def test_reproduce_rejects_bad_arguments(tmp_path, capsys):
    assert main(["reproduce", "--poses", "1"]) != 0
    assert main(["reproduce", "--poses", "10", "--encoder-noise", "-1"]) != 0
    assert "noise" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "--preset", "intersecting", "--urdf", "x.urdf"])
    assert exc.value.code != 0


def test_reproduce_from_a_urdf_file(tmp_path, reference):
    urdf = tmp_path / "hexa.urdf"
    urdf.write_text(geometry_to_urdf(reference.geometry))
    code, report = _reproduce(tmp_path, "--urdf", str(urdf), "--poses", "30", "--convergence-poses", "0")
    assert code == 0 and report["poses"] == 30
    assert report["cardan"]["translation_mean_mm"] < report["spherical"]["translation_mean_mm"]


def test_standard_model_benchmark_script_runs():
    import subprocess
    import sys

    script = Path(__file__).resolve().parents[2] / "benchmarks" / "standard_model.py"
    out = subprocess.run(
        [sys.executable, str(script), "--poses", "2000", "--repeat", "1"], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    assert "batch IK" in out.stdout and "batch FK" in out.stdout and "100.0% converged" in out.stdout
