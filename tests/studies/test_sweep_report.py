"""What ``hexapod sweep`` shows of its results: a table on stdout, the Pareto points labelled."""

from __future__ import annotations

import pytest

from hexapod_model.cli.sweep import format_table


def _rows():
    rows = []
    for k, (r, v, f, front) in enumerate(
        [(0.12, 2.0e-4, 1.8, True), (0.15, 3.0e-4, 2.5, True), (0.18, 1.0e-4, 3.0, False)]
    ):
        rows.append(
            {"id": f"c{k:03d}", "platform_radius": r, "status": "ok", "reason": "", "volume_m3": v,
             "force_per_force_max": f, "home_kappa": 5.0 + k, "pareto": front}
        )  # fmt: skip
    rows.append({"id": "c003", "platform_radius": 0.3, "status": "invalid", "reason": "legs 1 and 2 cross",
                 "volume_m3": "", "force_per_force_max": "", "home_kappa": "", "pareto": False})  # fmt: skip
    return rows


def test_the_table_has_a_line_per_candidate_with_its_parameters_and_figures():
    lines = format_table(_rows(), ["platform_radius"]).splitlines()
    assert lines[0].split()[:2] == ["id", "platform_radius"] and "volume_cm3" in lines[0]
    assert len(lines) == 5
    c1 = lines[2].split()
    assert c1[0] == "c001" and float(c1[1]) == 0.15 and float(c1[2]) == pytest.approx(300.0) and "*" in lines[2]
    assert "*" not in lines[3] and "legs 1 and 2 cross" in lines[4]


def test_pareto_points_are_labelled_with_their_id(tmp_path):
    pytest.importorskip("matplotlib")
    from hexapod_model.plots.sweep import plot_pareto

    fig = plot_pareto(_rows(), tmp_path / "p.png")
    labels = {t.get_text() for t in fig.axes[0].texts}
    assert labels == {"c000", "c001"} and (tmp_path / "p.png").stat().st_size > 1000
