"""``hexapod sweep`` on a real Dask cluster (a scheduler and two workers started here, on 127.0.0.1)."""

from __future__ import annotations

import csv
import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.cli.main import main
from hexapod_model.studies.sweep import evaluate_candidate, pareto_front
from hexapod_model.studies.sweep_spec import apply_parameters, load_spec

distributed = pytest.importorskip("distributed", reason="pip install -e '.[sweep]'")

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "docs" / "examples" / "sweep.toml"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def scheduler():
    """``dask scheduler`` and two ``dask worker --nthreads 1`` on 127.0.0.1; stopped at the end."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    dask = [sys.executable, "-m", "dask"]
    procs = [
        subprocess.Popen(
            [*dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    ]
    try:
        for _ in range(2):
            procs.append(
                subprocess.Popen(
                    [*dask, "worker", address, "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"],
                    env=env,
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                )
            )
        deadline = time.monotonic() + 60
        while True:
            try:
                with distributed.Client(address, timeout=5) as client:
                    client.wait_for_workers(2, timeout=60)
                break
            except (OSError, TimeoutError):
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.5)
        yield address
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def _sweep(tmp_path: Path, scheduler: str, parameters: str, grid: int = 4) -> list[dict[str, str]]:
    """Run a sweep of the reference preset over ``parameters`` (TOML lines) on ``scheduler``; its rows."""
    spec = tmp_path / "spec.toml"
    spec.write_text(
        f'base = "reference"\n[evaluate]\ngrid = {grid}\ncone_deg = 10.0\ncone_samples = 3\n[parameters]\n{parameters}'
    )
    assert main(["sweep", str(spec), "--scheduler", scheduler, "--out", str(tmp_path / "out")]) == 0
    return _rows(tmp_path / "out" / "sweep.csv")


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_example_sweep_on_two_workers_matches_evaluate_and_resumes(scheduler, tmp_path, capsys):
    out = tmp_path / "sweep"
    assert main(["sweep", str(EXAMPLE), "--scheduler", scheduler, "--out", str(out)]) == 0
    assert "6 computed, 0 from earlier runs" in capsys.readouterr().out
    rows = _rows(out / "sweep.csv")
    spec = load_spec(EXAMPLE)
    assert len(rows) == len(spec.candidates()) == 6
    assert (out / "pareto.png").stat().st_size > 1000
    assert any(r["pareto"] == "True" for r in rows)
    s = spec.settings
    for r in rows:
        assert r["status"] == "ok", r["reason"]
        assert float(r["volume_limits_m3"]) > 0
        if float(r["platform_radius"]) < 0.13:  # neighbouring 25 mm platform housings overlap at home
            assert float(r["volume_m3"]) == 0.0 and int(r["points_inside"]) == 0
        else:
            assert 0 < float(r["volume_m3"]) <= float(r["volume_limits_m3"])
            assert float(r["force_per_force_max"]) > 0
            assert float(r["sigma_min_min"]) <= float(r["sigma_max_max"])
            assert float(r["stiffness_translational_min"]) > 0
        js = tmp_path / f"{r['id']}.json"
        argv = ["evaluate", r["geometry"], "--grid", str(s.grid), "--cone-deg", str(s.cone_deg)]
        argv += ["--cone-samples", str(s.cone_samples), "--scheduler", scheduler, "--json", str(js)]
        assert main(argv) == 0
        ev = json.loads(js.read_text())
        assert float(r["volume_m3"]) == pytest.approx(ev["volume_m3"], rel=1e-9)
        assert int(r["points_inside"]) == ev["points_inside"]
        assert float(r["home_kappa"]) == pytest.approx(ev["home"]["kappa"], rel=1e-9)
    stamps = {p: p.stat().st_mtime_ns for p in (out / "results").iterdir()}
    capsys.readouterr()
    assert main(["sweep", str(EXAMPLE), "--scheduler", scheduler, "--out", str(out)]) == 0
    assert "0 computed, 6 from earlier runs" in capsys.readouterr().out
    assert {p: p.stat().st_mtime_ns for p in (out / "results").iterdir()} == stamps
    assert _rows(out / "sweep.csv") == rows


def test_invalid_candidates_get_their_reason(scheduler, tmp_path, capsys):
    found = _sweep(tmp_path, scheduler, "platform_spread_deg = [24.0, 150.0]\nstroke_min = [-0.16, 0.0]\n")
    rows = {(float(r["platform_spread_deg"]), float(r["stroke_min"])): r for r in found}
    assert rows[(24.0, -0.16)]["status"] == "ok"
    assert rows[(150.0, -0.16)]["status"] == "invalid" and "cross at home" in rows[(150.0, -0.16)]["reason"]
    for key in ((24.0, 0.0), (150.0, 0.0)):
        assert rows[key]["status"] == "invalid" and "stroke" in rows[key]["reason"] and rows[key]["geometry"] == ""
    assert "invalid" in capsys.readouterr().out


def test_singular_home_is_a_reason_not_a_crash():
    from hexapod_model.description.geometry_toml import geometry_to_toml
    from hexapod_model.studies.evaluate import Settings

    g = apply_parameters(hm.get_preset("reference"), {"platform_radius": 0.0}, "flat")
    r = evaluate_candidate(geometry_to_toml(g), Settings(grid=3), None, 0.0)
    assert r["status"] == "invalid" and "home condition number" in r["reason"]


def test_wrong_scheduler_address_is_one_clear_error(tmp_path, capsys):
    address = f"tcp://127.0.0.1:{_free_port()}"
    assert main(["sweep", str(EXAMPLE), "--scheduler", address, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and address in err[0] and "no Dask scheduler answers" in err[0]
    assert not (tmp_path / "o" / "results").exists() or not any((tmp_path / "o" / "results").iterdir())


@pytest.mark.parametrize(
    "text, named",
    [
        ("[parameters]\nbase_radius = [0.2]\nwheel_count = [3]\n", "wheel_count"),
        ("[evaluate]\ncone_samples = 0\n[parameters]\nbase_radius = [0.2]\n", "evaluate.cone_samples"),
        ("[evaluate]\ncone_deg = 95\n[parameters]\nbase_radius = [0.2]\n", "evaluate.cone_deg"),
        ("[parameters]\nbase_radius = { min = 0.3, max = 0.2 }\n", "parameters.base_radius"),
        ('[sample]\nmode = "sobol"\n[parameters]\nbase_radius = [0.2]\n', "sample.mode"),
    ],
)
def test_spec_errors_name_the_value(tmp_path, capsys, text, named):
    spec = tmp_path / "bad.toml"
    spec.write_text('base = "reference"\n' + text)
    assert main(["sweep", str(spec), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and named in err[0]


def test_random_sample_is_seeded_and_within_ranges(tmp_path):
    spec = tmp_path / "r.toml"
    spec.write_text(
        'base = "reference"\n[sample]\nmode = "random"\ncount = 5\nseed = 3\n'
        "[parameters]\nhome_height = { min = 0.35, max = 0.45 }\nbase_offset = [0.0, 0.012]\n"
    )
    a, b = load_spec(spec).candidates(), load_spec(spec).candidates()
    assert a == b and len(a) == 5
    assert all(0.35 <= c["home_height"] <= 0.45 and c["base_offset"] in (0.0, 0.012) for c in a)


def test_pareto_front():
    v = np.array([1.0, 2.0, 3.0, 2.0, np.nan])
    f = np.array([1.0, 1.5, 3.0, 2.0, 0.1])
    assert pareto_front(v, f).tolist() == [True, True, True, False, False]


def test_benchmark_script_reports_candidates_per_second():
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "sweep.py"), "--candidates", "2", "--grid", "4", "--workers", "1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert "cand/s" in out.stdout and "load average" in out.stdout


def test_layout_parameters_rebuild_the_base_and_a_base_file_is_relative_to_the_spec(tmp_path):
    from hexapod_model.description.geometry_toml import save_geometry

    base = hm.get_preset("reference")
    same = apply_parameters(base, {"base_radius": 0.25, "platform_spread_deg": 24.0}, "same")
    np.testing.assert_allclose(same.base_points(), base.base_points(), atol=1e-12)
    np.testing.assert_allclose(same.platform_points(), base.platform_points(), atol=1e-12)
    wider = apply_parameters(base, {"platform_radius": 0.18, "stroke_max": 0.25}, "wider")
    np.testing.assert_allclose(np.linalg.norm(wider.platform_points()[:, :2], axis=1), 0.18)
    assert all(leg.stroke == (-0.16, 0.25) for leg in wider.legs)
    (tmp_path / "g").mkdir()
    save_geometry(base, tmp_path / "g" / "mine.toml")
    spec = tmp_path / "g" / "s.toml"
    spec.write_text('base = "mine.toml"\n[parameters]\nhome_height = [0.4]\n')
    loaded = load_spec(spec)
    assert loaded.base == base and loaded.base_source == str((tmp_path / "g" / "mine.toml").resolve())


def test_a_value_listed_twice_is_one_task_and_two_rows(scheduler, tmp_path, capsys):
    a, b = _sweep(tmp_path, scheduler, "home_height = [0.4, 0.4]\n", grid=3)
    assert "1 computed" in capsys.readouterr().out
    assert a == b and a["status"] == "ok"
