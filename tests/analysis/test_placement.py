"""Candidate measuring legs ranked by their worst detectable fault, and ``hexapod evaluate --place-seventh-leg``."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.detectability import detectability_map
from hexapod_model.analysis.placement import candidates_from_toml, rank_placements
from hexapod_model.cli.main import main

CANDIDATES = """\
[[measuring_legs]]   # nearly a copy of leg 1: the others' faults barely show
base_anchor = {b1}
platform_anchor = {p1}
stroke = [-0.16, 0.20]

[[measuring_legs]]   # across the platform: reference7's
base_anchor = [0.25, 0.0, 0.0]
platform_anchor = [-0.15, 0.0, 0.0]
stroke = [-0.16, 0.20]
"""


def candidates_file(tmp_path):
    leg1 = hm.get_preset("reference").legs[0]
    up = np.array([0.0, 0.0, 0.02])
    b1, p1 = (list(map(float, np.array(a) + up)) for a in (leg1.base_anchor, leg1.platform_anchor))
    path = tmp_path / "candidates.toml"
    path.write_text(CANDIDATES.format(b1=b1, p1=p1))
    return path


def test_ranking_scores_each_candidate_by_its_own_detectability_map(tmp_path):
    legs = candidates_from_toml(candidates_file(tmp_path))
    ref = hm.get_preset("reference")
    scores = rank_placements(ref, legs, half_width=0.02, grid=2)
    assert [s.index for s in scores] == [1, 0]  # across the platform first, the copy of leg 1 last
    assert scores[0].worst < scores[1].worst
    for s in scores:
        geom = dataclasses.replace(ref, measuring_legs=(s.leg,))
        dmap = detectability_map(hm.Hexapod.from_geometry(geom), half_width=0.02, grid=2)
        largest = np.max(dmap.mdb.reshape(-1, 7), axis=0)
        np.testing.assert_array_equal(s.largest, largest)
        assert s.worst == largest.max() and s.inside == 4 and s.names == dmap.names


def test_place_seventh_leg_cli_ranks_the_candidates(tmp_path, capsys):
    out_json = tmp_path / "rank.json"
    cmd = ["evaluate", "reference", "--place-seventh-leg", str(candidates_file(tmp_path))]
    assert main([*cmd, "--placement-grid", "2", "--json", str(out_json)]) == 0
    text = capsys.readouterr().out
    assert "best first" in text
    report = json.loads(out_json.read_text())
    assert [r["candidate"] for r in report["ranking"]] == [2, 1]
    assert report["ranking"][0]["worst_m"] < report["ranking"][1]["worst_m"]
    assert set(report["ranking"][0]["largest"]) == {f"leg{k}" for k in range(1, 8)}


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "no \\[\\[measuring_legs\\]\\] table"),
        ("[[measuring_legs]]\nbase_anchor = [0, 0, 0]\nplatform_anchor = [0, 0, 0]\n", "stroke"),
        ("legs = 1\n", "unknown key"),
        ("[[measuring_legs]\n", "cannot read it as TOML"),
    ],
)
def test_a_bad_candidates_file_is_one_line_naming_what_is_wrong(tmp_path, text, match):
    path = tmp_path / "c.toml"
    path.write_text(text)
    with pytest.raises(hm.HexapodError, match=match):
        candidates_from_toml(path)


def test_no_candidate_is_refused():
    with pytest.raises(hm.InputError, match="at least one"):
        rank_placements(hm.get_preset("reference"), ())
