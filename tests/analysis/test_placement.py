"""Candidate measuring legs and inclinometers ranked by their worst detectable fault, and ``hexapod evaluate``'s
``--place-seventh-leg`` and ``--place-inclinometer``."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.analysis.detectability import detectability_map
from hexapod_model.analysis.placement import TIE_RTOL, candidates_from_toml, rank_placements, tied
from hexapod_model.cli.main import main
from hexapod_model.description.sensors import Inclinometer

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
        geom = dataclasses.replace(ref, measuring_legs=(s.sensor,))
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
        ("", "no \\[\\[measuring_legs\\]\\] or \\[\\[inclinometers\\]\\] table"),
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


def _deg(*rpy_deg: float, sigma: float = 2e-5) -> Inclinometer:
    return Inclinometer(tuple(math.radians(v) for v in rpy_deg), sigma)


def test_an_inclinometer_mounting_counts_only_through_the_skew_of_its_axes_and_its_noise():
    tilt = hm.get_preset("reference_tilt")
    candidates = (
        _deg(0, 0, 0),  # reference_tilt's
        _deg(0, 0, 45),  # turned about the vertical
        _deg(30, 0, 0),  # rolled: the projected axes stay perpendicular
        _deg(0, -20, 0),  # pitched: likewise
        _deg(30, 30, 0),  # rolled and pitched: the projected axes skew
        _deg(0, 0, 0, sigma=1e-5),  # a quieter sensor
    )
    scores = {s.index: s for s in rank_placements(tilt, candidates, half_width=0.02, grid=2)}
    level = scores[0]
    assert level.names[-2:] == ("tilt_x", "tilt_y") and level.inside == 4
    for k in (1, 2, 3):  # the criterion cannot tell these from the level mounting (docs/redundancy.md)
        np.testing.assert_allclose(scores[k].largest[:6], level.largest[:6], rtol=0, atol=1e-12)  # 1 pm
        assert tied(scores[k].worst, level.worst)
    assert scores[4].worst > 1.05 * level.worst and not tied(scores[4].worst, level.worst)
    assert scores[5].worst < 0.8 * level.worst
    assert TIE_RTOL < 0.01  # a tie is far tighter than the skewed candidate's difference


INCLINOMETERS = """\
[[inclinometers]]
rpy_deg = [0.0, 0.0, 0.0]

[[inclinometers]]
rpy_deg = [0.0, 0.0, 45.0]

[[inclinometers]]
rpy = [0.5, 0.5, 0.0]   # rad
sigma = 2.0e-5
"""


def test_place_inclinometer_cli_ranks_the_candidates_and_marks_ties(tmp_path, capsys):
    path = tmp_path / "incl.toml"
    path.write_text(INCLINOMETERS)
    out_json = tmp_path / "rank.json"
    cmd = ["evaluate", "reference_tilt", "--place-inclinometer", str(path), "--placement-grid", "2"]
    assert main([*cmd, "--json", str(out_json)]) == 0
    text = capsys.readouterr().out
    assert "3 candidate inclinometers" in text and "ties the rank above" in text
    ranking = json.loads(out_json.read_text())["ranking"]
    assert {r["candidate"] for r in ranking[:2]} == {1, 2} and ranking[2]["candidate"] == 3
    assert ranking[2]["rpy"] == [0.5, 0.5, 0.0] and ranking[2]["sigma"] == 2e-5
    assert set(ranking[0]["largest"]) == {*(f"leg{k}" for k in range(1, 7)), "tilt_x", "tilt_y"}


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("[[inclinometers]]\nsigma = 1e-5\n", r"inclinometers\[0\]\.rpy_deg.*required"),
        ("[[inclinometers]]\nrpy = [0.0, 2.0, 0.0]\n", r"pitch 2 rad is beyond \+-1\.5708 rad"),
        ("[[inclinometers]]\nrpy = [0.0, 0.0, 90.0]\n", r"yaw 90 rad .*rpy_deg"),
        ("[[inclinometers]]\nrpy_deg = [90.0, 0.0, 0.0]\n", r"its y axis rises 90 deg .*at most 85 deg"),
        ("[[inclinometers]]\nrpy_deg = [0.0, 0.0]\n", r"inclinometers\[0\]\.rpy_deg"),
        ("[[inclinometers]]\nrpy_deg = [0, 0, 0]\nsigma = 0.0\n", r"inclinometers\[0\]\.sigma"),
        ("[[inclinometers]]\nrpy_deg = [0, 0, 0]\nxyz = [0, 0, 0]\n", r"inclinometers\[0\]\.xyz.*unknown field"),
        ("[[inclinometers]]\nrpy_deg = [0, 0, 0]\nrpy = [0, 0, 0]\n", "not both"),
        ("inclinometers = 3\n", "expected \\[\\[inclinometers\\]\\] tables"),
    ],
)
def test_a_bad_inclinometer_candidate_is_one_line_naming_it(tmp_path, text, match):
    path = tmp_path / "c.toml"
    path.write_text(text)
    with pytest.raises(hm.GeometryError, match=match) as err:
        candidates_from_toml(path)
    assert "\n" not in str(err.value)


def test_each_flag_reads_only_its_own_kind_and_a_bad_file_is_one_line_at_the_cli(tmp_path, capsys):
    path = tmp_path / "incl.toml"
    path.write_text(INCLINOMETERS)
    assert main(["evaluate", "reference", "--place-seventh-leg", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "unknown key" in err and "[[measuring_legs]]" in err and len(err.splitlines()) == 1
    path.write_text("[[inclinometers]]\nrpy_deg = [0.0, 95.0, 0.0]\n")
    assert main(["evaluate", "reference_tilt", "--place-inclinometer", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "pitch" in err and "1.5708" in err and len(err.splitlines()) == 1 and "Traceback" not in err


def test_a_candidate_inclinometer_replaces_the_geometrys_and_measuring_legs_stay(tmp_path):
    both = dataclasses.replace(hm.get_preset("reference7"), inclinometer=Inclinometer())
    (s,) = rank_placements(both, (_deg(0, 0, 10),), half_width=0.02, grid=2)
    assert s.names == (*(f"leg{k}" for k in range(1, 8)), "tilt_x", "tilt_y")
