"""Scripts and benchmarks run (their figures are not asserted: timing is not a unit test)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import threading
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binomtest

import hexapod_model as hm

ROOT = Path(__file__).resolve().parent.parent


def test_benchmark_script_runs(tmp_path):
    out = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "run_benchmarks.py"),
            "spherical",
            "--samples",
            "5",
            "--json",
            str(tmp_path / "b.json"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.count("warm_fk") == 1 and "p99" in out.stdout
    (report,) = json.loads((tmp_path / "b.json").read_text())
    assert report["hexapod"] == "spherical" and report["cold_fk"]["n"] <= 5


def test_geometry_doc_example_loads():
    text = (ROOT / "docs" / "geometry.md").read_text()
    block = re.search(r"```toml\n(.*?)```", text, re.S).group(1)
    head, leg = block.split("[[legs]]")
    ref = hm.get_preset("reference").legs
    assert "[0.2445, -0.0520, 0.0]" in leg  # the example is reference leg 1
    legs = "".join(
        ("[[legs]]" + leg)
        .replace("[0.2445, -0.0520, 0.0]", str(list(lg.base_anchor)))
        .replace("[0.1004, -0.1115, 0.0]", str(list(lg.platform_anchor)))
        for lg in ref
    )
    g = hm.geometry_from_dict(tomllib.loads(head + legs))
    assert g.name == "my_hexapod" and hm.Hexapod.from_geometry(g).forward([0.0] * 6).converged


@pytest.mark.chromium
@pytest.mark.slow
def test_view_images_script_runs(tmp_path):
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "make_view_images.py"), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "reference.png").stat().st_size > 10_000 and (tmp_path / "cell.png").stat().st_size > 10_000


def test_seed002_geometry_files_match_their_generator(tmp_path):
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "make_seed002_geometries.py"), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    for made in tmp_path.glob("*.toml"):
        assert made.read_text() == (ROOT / "docs" / "geometries" / made.name).read_text(), made.name
    assert len(list(tmp_path.glob("*.toml"))) == 2


@pytest.mark.slow
def test_study_figures_script_runs_and_measured_example_matches(tmp_path):
    out = subprocess.run(
        [
            sys.executable,
            str(ROOT / "scripts" / "make_study_figures.py"),
            "--poses",
            "40",
            "--img",
            str(tmp_path / "img"),
            "--examples",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    # same rows and columns; values equal to 1e-9 (they are solver outputs printed to 12 digits,
    # whose last digit may move when the solver's iteration path changes)
    made, kept = (
        [ln.split(",") for ln in (d / "measured.csv").read_text().splitlines()]
        for d in (tmp_path, ROOT / "docs" / "examples")
    )
    assert made[0] == kept[0] and len(made) == len(kept)
    np.testing.assert_allclose(np.array(made[1:], float), np.array(kept[1:], float), rtol=0, atol=1e-9)
    assert len(list((tmp_path / "img").glob("reproduce_*.png"))) >= 4


@pytest.mark.slow
def test_eval_figures_script_runs(tmp_path):
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "make_eval_figures.py"), "--grid", "6", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert len(list(tmp_path.glob("*.png"))) == 5


def test_study_commands_benchmark_runs():
    script = str(ROOT / "benchmarks" / "study_commands.py")
    for args, words in (
        (["reproduce", "--poses", "20"], ["traces", "figure: conditioning"]),
        (["evaluate", "--runs", "1", "--grid", "5"], ["workers", "load average"]),
    ):
        out = subprocess.run([sys.executable, script, *args], capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stderr
        assert all(w in out.stdout for w in words)


def test_baseline_benchmark_runs():
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "baseline_newton.py"), "spherical"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    assert [ln.split()[0] for ln in lines] == ["baseline", "hexapod_model"]
    assert all(float(ln.rsplit("error", 1)[1]) < 1e-9 for ln in lines)  # both reach the true pose


def test_stream_memory_benchmark_runs():
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "stream_memory.py"), "--rows", "300"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    rows = [ln.split() for ln in out.stdout.strip().splitlines()[2:]]
    assert [(r[0], r[1], r[-1]) for r in rows] == [("fk", "300", "0"), ("ik", "300", "0")]  # both exit 0
    assert all(float(r[3]) > 10 for r in rows)  # max RSS in MB


def test_calibration_study_script_runs(tmp_path):
    out = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "calibration_study.py"),
            *("--poses", "40", "--folds", "2", "--hold", "*_axis.*", "--json", str(tmp_path / "c.json")),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert "after (calibrated)" in out.stdout and "within 3 sigma" in out.stdout
    assert (tmp_path / "c.json").stat().st_size > 100


def test_robustness_benchmark_classifies_every_solve(tmp_path):
    out = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "robustness.py"),
            "3-6",
            "guideway",
            "--poses",
            "400",  # the 45 deg cones leave about a third of 3-6's box within its limits: over 100 of 400
            "--json",
            str(tmp_path / "r.json"),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "returned as good but another assembly, unexplained (and any on 3-6): 0" in out.stdout
    assert "converged but not the generating pose: cold 0, warm 0" in out.stdout  # 3-6: every assembly known
    classes = ("ok", "flagged", "flagged_other", "ambiguous", "ambiguous_truth", "failed", "other_explained")
    for report in json.loads((tmp_path / "r.json").read_text()):
        for mode in ("cold", "warm"):
            counts = report[mode]
            assert counts["other_unexplained"] == 0
            assert report["preset"] != "3-6" or counts["converged_not_generating"] == 0
            assert sum(counts[k] for k in classes) + counts["no_guess"] == report["within_limits"] > 100


def test_certificate_and_tracker_false_alarm_benchmarks_run():
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "certificate.py"), "spherical", "--poses", "30"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "first attempt refused" in out.stdout and "warm:" in out.stdout
    cmd = [sys.executable, str(ROOT / "benchmarks" / "tracker_faults.py"), "reference", "--hour", "--hours", "0.0005"]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    assert out.stdout.count("expected <=") == 4  # two noise levels, at rest and moving


def _benchmark(name: str):
    """``benchmarks/NAME.py`` as a module (its functions, called in this process)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"{name}_bench", ROOT / "benchmarks" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _performance_table():
    """benchmarks/performance_table.py as a module (its row parsers and BENCHMARKS)."""
    return _benchmark("performance_table")


def test_clearance_benchmark_json_makes_the_performance_rows(tmp_path):
    report = tmp_path / "clearance.json"
    cmd = [sys.executable, str(ROOT / "benchmarks" / "clearance.py"), "--poses", "20", "--rounds", "1"]
    out = subprocess.run([*cmd, "--json", str(report)], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout + out.stderr
    data = json.loads(report.read_text())
    assert data["us"]["clearance: Hexapod.clearance"]["median"] > 0 and data["check_ratio"]["trajectory A"] > 0
    assert data["agreement"]["verdicts_equal"] == data["poses"] > 0
    table = _performance_table()
    rows = dict(table.clearance_rows(data))
    assert "µs" in rows["reference: clearance query (Hexapod.clearance), time per query"]
    assert "µs" in rows["reference: clearance query, its compiled kernel call alone"]
    assert rows["reference: warm FK along trajectory A, without / with the body check, CPU per solve"].endswith("x)")
    assert any(args[0] == "clearance.py" and parse is table.clearance_rows for args, _, parse in table.BENCHMARKS)


def test_certificate_benchmark_json_makes_the_performance_rows(tmp_path):
    report = tmp_path / "certificate.json"
    cmd = [sys.executable, str(ROOT / "benchmarks" / "certificate.py"), "reference", "3-6", "--poses", "0"]
    out = subprocess.run(
        [*cmd, "--trajectory-samples", "20", "--rest-samples", "201", "--far-guesses", "4", "--json", str(report)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    data = json.loads(report.read_text())
    assert [(t["preset"], t["trajectory"]) for t in data["trajectories"]] == [
        (p, w) for p in ("reference", "3-6") for w in ("A", "B")
    ]
    assert all(0 <= t["proven_fraction"] <= 1 and t["steps"] > 0 for t in data["trajectories"]) and not data["solves"]
    table = _performance_table()
    rows = dict(table.certificate_rows(data))
    assert len(rows) == 16
    for preset, which in (("reference", "A"), ("reference", "B"), ("3-6", "A"), ("3-6", "B")):
        where = f"{preset}: trajectory {which} at 1 kHz"
        assert rows[f"{where}, warm steps proven (Krawczyk)"].endswith(" of 19")
        step = rows[f"{where}, warm step with its proof, time per step"]
        assert "µs forward with its proof" in step and "the solve alone" in step
        assert ("floor" in step and step.endswith("x)")) == (preset == "reference")
    for rest in data["rest"]:  # at rest, 200 steps: half with regions, half each step its own test
        assert rest["steps"] == 200 and rest["proven_fraction"] == 1.0 and rest["in_region_fraction"] > 0.9
        row = rows[f"{rest['preset']}: at rest, 1 µm noise, warm step with its proof (regions), time per step"]
        assert "in a region" in row and "each step its own test" in row
        assert ("floor" in row) == (rest["preset"] == "reference")
    for rest in data["rest_streams"]:  # fixtures at rest stepped in turn: each in its own region
        assert rest["steps"] == 5 * 20 and rest["proven_fraction"] == 1.0, rest
        assert rest["in_region_fraction"] > 0.9 and rest["alone_in_region_fraction"] > 0.9, rest
        where = f"{rest['preset']}: 5 fixtures at rest, 1 µm noise, 1 µm counts, trackers stepped in turn"
        assert "one fixture alone" in rows[f"{where}, time per step"]
    for tracked in data["tracker"]:  # the tracker's short steps from its prediction build no region while moving
        assert tracked["steps"] == 10 and tracked["proven_fraction"] == 1.0 and tracked["in_region_fraction"] == 0.0
        row = rows[f"{tracked['preset']}: trajectory A at 1 kHz, the tracker (eq22), time per step"]
        assert "µs a step" in row and "with its proof" in row and row.endswith("0.00 % in a region")
    for far in data["far"]:  # a guess 0.1 m away: proven in steps, a few tests each (a failed step: 32)
        assert far["solves"] >= 3 and far["converged_fraction"] == 1.0 and far["median_steps"] > 1
        assert far["tests_per_step"] < 20, far
        assert any(k.startswith(f"{far['preset']}: warm FK from a far guess") for k in rows)
    assert any(args[0] == "certificate.py" and parse is table.certificate_rows for args, _, parse in table.BENCHMARKS)


def test_certificate_benchmark_times_each_kind_of_call_in_a_stream_of_its_own(monkeypatch):
    """The proven steps along a trajectory are timed as a caller's stream: no dense test between two of them.

    The dense reference test drops the region a step proved (and a test of another kind between
    two steps evicts the per-leg test's arrays from the caches): run between the steps, it made
    the per-step figures those of another stream.
    """
    from hexapod_model.kinematics.newton.proof import StepProver

    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))  # its imports of the floor
    bench = _benchmark("certificate")
    kinds: list[bool] = []
    prove = StepProver.prove

    def spy(self, q0, q1, structured=True, subdivide=True):
        kinds.append(structured)
        return prove(self, q0, q1, structured, subdivide)

    monkeypatch.setattr(StepProver, "prove", spy)
    report = bench.trajectory_proofs("guideway", "A", 30, rounds=2)
    assert report["steps"] == 29 and report["proven_fraction"] == 1.0
    # the warm-up (a proven forward, a dense test); two proven passes and the per-leg pass; the dense pass
    assert kinds[:2] == [True, False] and kinds[2:] == [True] * 3 * 29 + [False] * 29


def test_three_six_benchmark_runs():
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "three_six_fk.py"), "--poses", "30"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "solve_all  median" in out.stdout and "missed 0 times" in out.stdout


def test_compiled_newton_benchmark_runs():
    out = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "compiled_newton.py"),
            "spherical",
            "--rounds",
            "1",
            "--samples",
            "20",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert "Pinocchio Newton" in out.stdout and "forward_batch" in out.stdout


def test_tracker_kernels_names_each_call_of_a_kernel_called_twice_in_a_step():
    names = _benchmark("tracker_kernels").call_names(("solve_schur", "prove_packed", "solve_schur", "solve_schur"))
    assert names == ["solve_schur", "prove_packed", "solve_schur 2", "solve_schur 3"]  # no call's figure overwritten


def test_tracker_kernels_benchmark_splits_a_step_into_its_kernels_and_the_python_around_them(tmp_path):
    report = tmp_path / "kernels.json"
    script = ROOT / "benchmarks" / "tracker_kernels.py"
    out = subprocess.run(
        [sys.executable, str(script), "--steps", "200", "--fused", "--json", str(report)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    data = json.loads(report.read_text())  # what docs/performance.md's rows are made of
    assert {"solve_schur", "prove_packed", "measure_solved"} <= set(data["sequence"])  # the solve, its proof, sigma
    assert data["steps"] >= data["of"] // 2  # most steps of a moving stream call one sequence
    assert 0 < data["kernels_in_step_total_us"] < data["step_us"]
    assert len(data["kernels_in_step_us"]) == len(data["sequence"])  # each call of the sequence timed
    assert 0 < data["replayed_us"] < data["step_us"]  # the kernels without the step's Python cost less than the step
    assert data["fused_us"] > 0 and data["fused_compile_s"] > 0
    assert 0 <= data["wrapper_us"]["inside"] < 5  # the timing's own cost, taken off each kernel
    # the Python around the kernels split before each call and after the last: shares that add up to it
    before = data["python_before_us"]
    assert list(before) == [*data["kernels_in_step_us"], "after the last"] and min(before.values()) >= 0.0
    assert sum(before.values()) == pytest.approx(data["python_in_step_us"], rel=1e-9)
    assert "before each kernel and after the last" in out.stdout
    rows = dict(_performance_table().tracker_kernel_rows(data))
    assert "the Python around them" in rows["reference: tracker step, moving at 1 kHz, where its CPU goes"]
    assert (
        "as one compiled call"
        in rows["reference: tracker step's compiled kernels without the Python between them, CPU a step"]
    )
    assert "the Python around them" in out.stdout and "as one compiled call" in out.stdout


def test_floor_compare_benchmark_runs(tmp_path):
    report = tmp_path / "floor.json"
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "floor_compare.py"), "--rounds", "1", "--samples", "20"]
        + ["--json", str(report)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert "ratio package / floor" in out.stdout and "target >= 0.85x" in out.stdout
    data = json.loads(report.read_text())  # what docs/performance.md's rows are made of
    assert data["warm_fk_us"]["package"] > 0 and data["warm_fk_ratio"] > 0 and len(data["batch"]) == 3
    assert data["warm_fk_proven_us"] > data["warm_fk_us"]["package"]  # the proof costs on top of the solve
    batch = data["batch"]
    proven = batch["forward_batch, trajectory A warm, each row with its proof (the default)"]["package"]
    assert proven < batch["forward_batch, trajectory A warm"]["package"]  # solves/s: the proofs cost on top
    rows = dict(_performance_table().floor_rows(data))
    assert "µs vs the floor's" in rows["reference: warm FK with its Krawczyk proof (the default), CPU per solve"]
    parts = data["warm_fk_proof_breakdown_us"]  # the proof's compiled parts, each timed on its own
    kinds = ("prove", "compiled_call", "residual", "jacobian", "preconditioner", "blocks", "test", "apply")
    assert set(parts) == {*kinds, "whole_test_parts"}
    assert 0 < parts["compiled_call"] < parts["prove"]  # the Python around the call costs on top
    assert 0 < parts["residual"] < parts["jacobian"]  # a point's enclosure, then the box's with the Jacobian
    assert parts["residual"] + parts["jacobian"] + parts["blocks"] + 2 * parts["test"] < parts["whole_test_parts"]
    assert parts["whole_test_parts"] < parts["compiled_call"]  # the parts of one test, timed alone, within the call
    box = batch["forward_batch, box poses from home"]
    assert 0 <= data["box_rows_failing_at_the_first_step"] <= data["box_rows_following_the_path"]
    for label in {"certified at once", "following the path"} & set(box):  # each part's Newton steps per row
        assert box[label]["steps"]["package"] >= 1.0 and box[label]["steps"]["floor"] >= 1.0
    assert "two Krawczyk tests" in rows["reference: warm FK's Krawczyk proof, where its time goes, CPU (medians)"]
    assert "Krawczyk proof (median us)" in out.stdout


def test_startup_benchmark_runs(tmp_path):
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "startup.py"), "--runs", "1", "--json", str(tmp_path / "s.json")],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert "peak MB" in out.stdout and "x1.00 wall" in out.stdout  # the baseline row
    assert "hexapod_model urdf reference" in out.stdout and "(target: x3 CPU)" in out.stdout
    data = json.loads((tmp_path / "s.json").read_text())
    assert data["baseline"]["peak_mb"] > 0 and data["command"]["wall_s"] > 0 and "cold" not in data
    assert data["urdf"]["cpu_ratio"] == data["urdf"]["cpu_s"] / data["baseline"]["cpu_s"] > 0
    rows = dict(_performance_table().startup_rows(data))
    urdf = "`hexapod_model urdf reference -o FILE` (imports only, compiles nothing)"
    assert rows[f"{urdf}, CPU against `import pinocchio, numpy`"].endswith(f"({data['urdf']['cpu_ratio']:.2f}x)")
    # --cold's figures (a minute and more to measure): the first proof's compilation has a row of its own
    cold = {"first_forward_cpu_s": 15.0, "first_inverse_cpu_s": 4.0, "first_batch_cpu_s": 12.0}
    data["cold"] = {**cold, "floor_compile_cpu_s": 5.0, "first_proven_cpu_s": 76.31}
    rows = dict(_performance_table().startup_rows(data))
    assert rows["then the first warm forward, its Krawczyk proof compiling (empty numba cache), CPU"] == "76.3 s"
    first = rows["first compiled forward after installation (empty numba cache), CPU"]
    assert first.startswith("15.0 s, 3.00x the one-function floor's compile (5.0 s)")
    split = "the first compiled forward split: its solver's kernels, then its body check's (empty numba cache), CPU"
    assert split not in rows  # a page written before the split keeps its rows
    data["cold"].update(first_solver_cpu_s=10.9, first_body_check_cpu_s=4.3)
    rows = dict(_performance_table().startup_rows(data))
    assert rows[split] == (
        "10.9 s without the body check (2.18x the floor's compile), then the body check's kernels 4.3 s"
    )
    data["cold"].update(first_tracker_cpu_s=12.04, unannounced="none")
    rows = dict(_performance_table().startup_rows(data))
    tracker = "then a Tracker's first samples (empty numba cache), CPU; the compilations over 1 s the package did not"
    assert rows[f"{tracker} announce"] == "12.0 s; unannounced: none"


def test_performance_table_only_keeps_the_other_scripts_rows():
    """``--only`` with no script to rerun gives back the page's rows; rows of another command are refused."""
    table = _performance_table()
    text = (ROOT / "docs" / "performance.md").read_text()
    rows = table.page_rows(text)
    assert len(rows) > len(table.BENCHMARKS) and table.page_rows(table.page(rows, "here")) == rows
    assert table.measure(False, set(), text) == rows
    other = text.replace("`python benchmarks/startup.py --runs 3 --cold`", "`python benchmarks/startup.py --runs 9`")
    with pytest.raises(SystemExit, match="no rows of `python benchmarks/startup.py --runs 3 --cold`"):
        table.measure(False, set(), other)


def test_performance_table_only_refuses_a_page_of_another_machine(tmp_path, monkeypatch):
    """``--only`` keeps the page's other rows: never under the name of a machine that did not measure them."""
    table = _performance_table()
    text = (ROOT / "docs" / "performance.md").read_text()
    page = tmp_path / "performance.md"
    page.write_text(table.page(table.page_rows(text), "another machine, 64 cores"))
    ran = []
    monkeypatch.setattr(table, "measure", lambda *args: ran.append(args) or table.page_rows(text))
    with pytest.raises(SystemExit, match=r"measured on another machine, 64 cores, this machine is .*: run every"):
        table.main(["--only", "startup.py", "-o", str(page)])
    assert not ran and page.read_text() == table.page(table.page_rows(text), "another machine, 64 cores")
    page.write_text(table.page(table.page_rows(text), table.machine()))  # measured here: the other rows are kept
    assert table.main(["--only", "startup.py", "-o", str(page)]) == 0 and len(ran) == 1
    assert table.page_machine(page.read_text()) == table.machine()


def test_service_benchmark_runs(tmp_path):
    """Both modes, short: a fed run per fixture count and the full-queue capacity, moving and at rest (JSON, table)."""
    cmd = [sys.executable, str(ROOT / "benchmarks" / "service.py"), "--seconds", "0.5", "--one", "100"]
    out = subprocess.run(
        [
            *cmd,
            "--many",
            "20",
            "--fixtures",
            "2",
            "--more",
            "3:50",
            "--capacity",
            "--rest",
            "--json",
            str(tmp_path / "s.json"),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert "1 x    100 Hz" in out.stdout and "2 x     20 Hz" in out.stdout and "3 x     50 Hz" in out.stdout
    assert "capacity   1 x   1000 Hz" in out.stdout and "capacity   2 x    100 Hz" in out.stdout
    assert "capacity   3 x     50 Hz" in out.stdout and out.stdout.count("highest sustained set rate") <= 3
    data = json.loads((tmp_path / "s.json").read_text())
    full = [r for r in data if r.get("kind") == "capacity"]
    assert [(r["fixtures"], r["rate_hz"], r.get("motion")) for r in full] == [
        (1, 1000.0, None),
        (2, 100.0, None),
        (3, 50.0, None),
        (2, 100.0, "rest"),
    ]
    # CPU µs a set, each measured by itself (their order is a figure of the machine's load: benchmarks/, not a test)
    keys = ("solve_us", "step_us", "cycle_cpu_us_per_set", "steps_in_turn_us", "cycles_by_hand_us")
    figures = [r[k] for r in full for k in keys]
    assert all(0.0 < v < 1e6 for v in figures), figures
    rest = [r for r in data if r.get("motion") == "rest" and r.get("kind") != "capacity"]
    assert len(rest) == 1 and rest[0]["fixtures"] == 2 and rest[0]["records"] > 0, rest
    assert "a set at rest (1 um noise, 1 um counts)" in out.stdout and "at rest   2 x    100 Hz" in out.stdout
    rows = dict(_performance_table().service_rows(data))
    assert (
        len(rows) == 8 and "pose service, 2 fixture(s) × 20 Hz" in rows and "pose service, 3 fixture(s) × 50 Hz" in rows
    )
    assert "pose service, 2 fixture(s) × 100 Hz at rest (1 µm counts) from a full queue (`--capacity`)" in rows
    assert "pose service, 2 fixture(s) × 100 Hz at rest (1 µm counts)" in rows
    cell = rows["pose service, 2 fixture(s) × 100 Hz from a full queue (`--capacity`)"]
    assert cell.startswith(f"cycle thread {full[1]['cycle_cpu_us_per_set']:.0f} µs CPU a set")
    # several fixtures' tracker steps in turn, without the bus, beside the one stream's (one fixture: its own)
    assert full[0]["steps_in_turn_us"] == full[0]["step_us"] and all(r["steps_in_turn_us"] > 0.0 for r in full)
    assert f"the 2 fixtures' steps in turn, without the bus: {full[1]['steps_in_turn_us']:.0f} µs" in cell
    assert "in turn" not in rows["pose service, 1 fixture(s) × 1000 Hz from a full queue (`--capacity`)"]
    assert "the 2 fixtures' tracker steps in turn, without the bus:" in out.stdout
    # the same fixtures' cycles handed their frames on one thread: the set's Python without the bus and threads
    hand = full[1]["cycles_by_hand_us"]
    by_hand = f"the cycles handed their frames, without the bus, the threads and the store: {hand:.0f} µs"
    assert by_hand in cell and "their cycles handed the frames, without the bus" in out.stdout
    # a run of one fixture also against its solve timed after the stream's idle gap (the others: not)
    assert "the solve after the idle gap of a 1-fixture stream: 100 Hz" in out.stdout
    fed = {r["fixtures"]: r for r in data if r.get("kind") != "capacity"}
    assert fed[1]["solve_idle_us"] > 0.0 and "solve_idle_us" not in fed[2]
    assert "the solve after the same idle gap, " in rows["pose service, 1 fixture(s) × 100 Hz"]
    assert "idle gap" not in rows["pose service, 2 fixture(s) × 20 Hz"]
    # every fed run beside its cycles handed their frames at the stream's pace and the bus's wake-ups alone
    for r in [*fed.values(), *rest]:
        assert all(0.0 < r[k] < 1e6 for k in ("paced_by_hand_us", "warm_by_hand_us", "wakeups_us")), r
    paced = f"at the stream's pace, without the bus: {fed[1]['paced_by_hand_us']:.0f} µs a set"
    assert paced in rows["pose service, 1 fixture(s) × 100 Hz"] and "the bus's wake-ups alone" in out.stdout


def test_service_benchmark_reads_the_feeders_cpu_while_it_lives(tmp_path, monkeypatch):
    """The feeder (``hx-sim``) lives until its CPU was read from ``/proc``, however long the read takes.

    A read while the cycle thread holds the interpreter lock can take tens of milliseconds: the
    feeder that ended meanwhile was gone from ``/proc`` and its CPU read as 0 %.
    """
    import threading
    import time

    bench = _benchmark("service")
    read = bench.cpu_by_thread_name

    def slow_read(pid="self"):  # a read that takes long: the feeder's end, if it comes, comes first
        end = time.monotonic() + 0.5
        while time.monotonic() < end and any(t.name == "hx-sim" for t in threading.enumerate()):
            time.sleep(0.01)
        return read(pid)

    monkeypatch.setattr(bench, "cpu_by_thread_name", slow_read)
    hexa = hm.Hexapod.from_preset("reference")
    readings = bench.readings_sequence(hexa)[:200]
    report = bench.run(hexa, readings, 1, 50.0, 0.3, tmp_path)
    assert report["records"] > 0 and report["os_sim_cpu_pct"] > 0.0


def test_service_benchmark_times_the_idle_gap_solve_of_every_one_fixture_run(monkeypatch):
    """``--fixtures 1`` (and ``--more 1:RATE``) runs of one fixture: each gets its solve after its own idle gap.

    Such a run looked up an idle-gap solve that was only timed for the ``--one`` rates, and the
    script stopped on a ``KeyError``.
    """
    bench = _benchmark("service")
    runs = []

    def run(hexa, readings, n, rate, seconds, tmp, frame_gap=0.0):  # the fed run itself: its arguments, no stream
        runs.append((n, rate))
        return {"fixtures": n, "rate_hz": rate, "sustained": True}

    monkeypatch.setattr(bench, "run", run)
    monkeypatch.setattr(bench, "line", repr)
    monkeypatch.setattr(bench, "IDLE_SOLVES", 3)
    argv = ["--seconds", "0.1", "--one", "1000", "--many", "500", "--fixtures", "1", "--more", "1:250"]
    assert bench.main(argv) == 0
    assert runs == [(1, 1000.0), (1, 500.0), (1, 250.0)]


def test_service_benchmark_delivers_a_sets_frames_leg_by_leg_with_a_frame_gap(tmp_path):
    """``--frame-gap``: a set's frames leg by leg, about that far apart (the feeder sleeps between them)."""
    bench = _benchmark("service")
    hexa = hm.Hexapod.from_preset("reference")
    readings = bench.readings_sequence(hexa)[:300]
    report = bench.run(hexa, readings, 2, 100.0, 0.3, tmp_path, frame_gap=1e-3)
    assert report["records"] > 0 and report["frame_gap_us"] == pytest.approx(1000.0)
    # from the first frame to the last, the median period: a sleep ends after its time (the first frame may be late)
    assert 800.0 <= report["frame_gap_delivered_us"] < 5000.0
    assert "frame_gap_us" not in bench.run(hexa, readings, 1, 100.0, 0.2, tmp_path)
    assert bench.wakeups(readings, 1, 100.0, 0.2, tmp_path, 1e-3) > 0.0
    assert bench.gaps_of(0.0, [], 6) == {} and bench.gaps_of(1e-4, [5e-4, 7e-4, 6e-4], 6) == pytest.approx(
        {"frame_gap_us": 100.0, "frame_gap_delivered_us": 120.0}
    )


@pytest.mark.parametrize("gap", ["-1", "nan", "1e6"])
def test_service_benchmark_refuses_a_bad_frame_gap_in_one_line(gap):
    cmd = [sys.executable, str(ROOT / "benchmarks" / "service.py"), "--frame-gap", gap]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and out.stdout == ""
    assert "--frame-gap" in out.stderr and "Traceback" not in out.stderr


@pytest.mark.parametrize("more", ["5", "5:", "0:100", "x:100", "5:-1", "5:nan", "5:100,inf"])
def test_service_benchmark_refuses_a_bad_group_in_one_line(more):
    cmd = [sys.executable, str(ROOT / "benchmarks" / "service.py"), "--more", more]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and out.stdout == ""
    assert "expected FIXTURES:RATES" in out.stderr and "Traceback" not in out.stderr


def test_coverage_table_sums_every_module_per_package(tmp_path):
    import importlib.util

    spec = importlib.util.spec_from_file_location("coverage_table", ROOT / "scripts" / "coverage_table.py")
    assert spec is not None and spec.loader is not None
    table = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(table)
    package = tmp_path / "pkg"
    for name in ("__init__.py", "top.py", "sub/__init__.py", "sub/deep/kernel.py", "other/never_imported.py"):
        (package / name).parent.mkdir(parents=True, exist_ok=True)
        (package / name).write_text("x = 1\n")
    measured = {"top.py": (10, 4), "sub/__init__.py": (2, 0), "sub/deep/kernel.py": (8, 8), "__init__.py": (0, 0)}

    class Data:  # what coverage.Coverage.analysis2 gives: statements and missed lines
        def analysis2(self, path):
            n, m = measured.get(str(Path(path).relative_to(package)), (5, 5))  # not imported: all missed
            return path, list(range(n)), [], list(range(m)), ""

    rows = table.per_package(Data(), package)
    assert rows == {"(top)": (10, 4), "other": (5, 5), "sub": (10, 8)}
    text, total = table.table(rows)
    assert total == pytest.approx(100 * (25 - 17) / 25)
    assert text.splitlines()[-1].split() == ["TOTAL", "25", "17", "32.0%"]


def test_redundancy_fault_benchmark_runs(tmp_path):
    out = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "redundancy_faults.py"),
            "reference",
            "reference_tilt",
            "--samples",
            "20",
            "--clean",
            "20",
            "--json",
            str(tmp_path / "r.json"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    report = {r["preset"]: r for r in json.loads((tmp_path / "r.json").read_text())}
    assert report["reference_tilt"]["cases"]["offset 0.3"]["wrong_ok"] == 0
    assert report["reference_tilt"]["cases"]["offset 0.3"]["flagged"] == 20
    assert report["reference"]["cases"]["offset 0.3"]["wrong_ok"] == 20  # six readings cannot see it


def test_seventh_leg_placement_benchmark_runs():
    cmd = [sys.executable, str(ROOT / "benchmarks" / "seventh_leg_placement.py"), "--grid", "2"]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    worst = [float(line.split("worst")[1].split()[0]) for line in out.stdout.splitlines()]
    assert len(worst) == 5 and worst[0] == min(worst)  # reference7's placement is the best of them


def test_false_alarm_hour_benchmark_rate_is_the_stated_one_at_its_sample_size(tmp_path):
    """A short span of the hour: every case runs, and its alarm count is binomially consistent with the stated rate."""
    out_json = tmp_path / "fa.json"
    cmd = [sys.executable, str(ROOT / "benchmarks" / "false_alarm_hour.py"), "--seconds", "6", "--json", str(out_json)]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout + out.stderr
    results = json.loads(out_json.read_text())
    assert {(r["preset"], r["motion"]) for r in results} == {
        (p, m) for p in ("reference7", "reference_tilt") for m in ("moving", "rest")
    }
    for r in results:
        assert r["samples"] == 600 and r["failed"] == 0, r
        assert binomtest(r["alarms"], r["samples"], r["alpha"]).pvalue > 1e-3, r
        assert r["ci95"][0] <= r["alarms"] / r["samples"] <= r["ci95"][1]
    assert ("NOT consistent" in out.stdout) != all(r["consistent"] for r in results)


def test_service_benchmark_plays_each_fixture_from_a_point_of_its_own():
    """Fixtures of a cell stand at poses of their own: a sequence is played from evenly spread points."""
    bench = _benchmark("service")
    seq = np.arange(10.0)[:, None] * np.ones(6)
    per = bench.fixture_readings(seq, 3)
    assert per.shape == (10, 3, 6)
    np.testing.assert_array_equal(per[:, 0, 0], np.arange(10.0))
    np.testing.assert_array_equal(per[:, 1, 0], np.roll(np.arange(10.0), -3))  # fixture 1 from sample 3
    np.testing.assert_array_equal(per[:, 2, 0], np.roll(np.arange(10.0), -6))
    still = np.zeros((4, 2, 6))
    assert bench.fixture_readings(still, 2) is still  # each fixture's own readings, as given


def test_service_benchmark_measures_the_stream_it_warmed_up(tmp_path, monkeypatch):
    """A fed run's frames are out of the collector's reach, and its measured phase follows the warm-up at once.

    The frame objects stand for a kernel's buffers: made after the service froze its objects,
    each measured phase began with hundreds of thousands of them for the cycle thread's full
    collections to walk (60-90 ms each). A pause between the warm-up and the measured phase left
    the legs silent, and the measured phase began with every tracker re-anchoring (``flagged``).
    """
    import gc

    import can

    bench = _benchmark("service")
    read, tracked = bench.cpu_by_thread_name, []

    def counting_read(pid="self"):  # first called as the measured phase begins
        if not tracked:
            tracked.append(sum(1 for o in gc.get_objects() if type(o) is can.Message))
        return read(pid)

    monkeypatch.setattr(bench, "cpu_by_thread_name", counting_read)
    hexa = hm.Hexapod.from_preset("reference")
    readings = bench.readings_sequence(hexa)[:1000]  # 20 s at 50 Hz: no fixture comes to its sequence's end
    report = bench.run(hexa, readings, 2, 50.0, 0.5, tmp_path)
    assert tracked == [0]  # every frame of the run frozen with the service's objects
    assert report["records"] > 0 and set(report["statuses"]) <= {"ok", "silent_leg"}, report["statuses"]
    assert report["caught_up"] and report["warm_up_s"] < bench.WARM_UP_LIMIT


def test_an_overloaded_service_run_says_its_share_of_a_core_is_what_the_sets_sent_need():
    """A run that fell behind: its share of a core is its CPU per set times the sets sent a second (over 100 %)."""
    run = {
        "fixtures": 50,
        "rate_hz": 100.0,
        "sets_sent": 10_000,
        "warm_up_s": 5.0,
        "caught_up": False,
        "records": 10_000,
        "sets_handled": 13_000,
        "statuses": {"ok": 10_000},
        "latency_ms_median": 1766.0,
        "latency_ms_p99": 2011.0,
        "service_cpu_pct": 193.5,
        "service_cpu_us_per_set": 395.0,
        "cycle_cpu_us_per_set": 378.0,
        "process_cpu_pct": 198.7,
        "os_service_cpu_pct": 191.8,
        "os_sim_cpu_pct": 4.3,
        "os_other_cpu_pct": 0.9,
        "sustained": False,
        "solve_us": 80.0,
    }
    kept = run | {"caught_up": True, "latency_ms_p99": 4.0, "service_cpu_pct": 80.0, "sustained": True}
    said = "needed by the sets sent"
    bench, rows = _benchmark("service"), _performance_table().service_rows
    assert said in bench.line(run) and said not in bench.line(kept)
    assert said in rows([run])[0][1] and said not in rows([kept])[0][1]


def test_a_fed_run_counts_the_cpu_of_a_set_over_every_set_it_handled_the_warm_up_s_backlog_too(tmp_path, monkeypatch):
    """A run still behind after its warm-up works that backlog off in its measured time: those sets count.

    The cycle thread is held for half a second as the warm-up ends, so that the measured phase
    begins with a backlog of warm-up sets; each record published is made to cost 100 µs of the
    threads' CPU. Counted over the measured phase's sets alone, a set read as more: the backlog's
    CPU over fewer sets.
    """
    bench = _benchmark("service")
    published, held, holding = [0], threading.Event(), threading.Event()

    class Held(bench.FixtureService):
        def subscribe(self, callback):
            def counted(rec):  # on the cycle thread, after the benchmark's own subscriber
                callback(rec)
                if rec.status != "silent_leg":
                    published[0] += 1
                if held.is_set() and not holding.is_set():
                    holding.set()
                    time.sleep(0.5)  # frames queue meanwhile: a backlog as the measured phase begins

            return super().subscribe(counted)

    warmed = bench.caught_up

    def caught_up(*args):
        out = warmed(*args)
        held.set()
        assert holding.wait(10.0)
        time.sleep(0.25)  # the warm-up's last sets queue behind the held thread
        return out

    monkeypatch.setattr(bench, "FixtureService", Held)
    monkeypatch.setattr(bench, "caught_up", caught_up)
    monkeypatch.setattr(bench, "thread_cpu", lambda threads: published[0] * 100e-6)  # 100 µs a record
    hexa = hm.Hexapod.from_preset("reference")
    readings = bench.readings_sequence(hexa)[:1000]
    report = bench.run(hexa, readings, 2, 50.0, 0.5, tmp_path)
    assert report["cycle_cpu_us_per_set"] == pytest.approx(100.0, rel=1e-9)
    assert report["service_cpu_us_per_set"] == pytest.approx(100.0, rel=1e-9)
    assert report["sets_handled"] >= report["records"] + 10  # the backlog: 2 fixtures x 50 Hz x 0.25 s
