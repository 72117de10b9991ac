"""The typed record at its edges: the JSON object (HTTP, JSON lines) and the store's sample row, as documented."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from hexapod_model.service import RECORD_KEYS, PoseRecord, Store
from hexapod_model.service.store.fixture_store import SAMPLE_COLUMNS, sample_row

POSE = {"x": 0.01, "y": -0.02, "z": 0.41, "qx": 0.1, "qy": -0.2, "qz": 0.3, "qw": math.sqrt(0.86)}
LOAD = {"leg_forces_N": [10.5, -3.25, 0.0, 7.0, -1.0, 2.5], "largest_leg_force_N": 10.5}
IN_ROBOT_POSE = {"x": 0.8, "y": -0.3, "z": 0.43, "qx": 0.0, "qy": 0.0, "qz": math.sqrt(0.5), "qw": math.sqrt(0.5)}
RECORD = PoseRecord(
    "left",
    1795672991.5198855,
    [0.001, -0.002, None, 0.0, 1e-06, -0.004],
    {**POSE, "roll": 1.5, "pitch": -2.25, "yaw": 3.0},
    "ok",
    ["encoder_warning:leg2"],
    3,
    "locked",
    True,
    {"translation_mm": 0.0249, "rotation_deg": 0.006},
    0.95,
    {**LOAD, "brake_capacity_N": 400.0, "margin_N": 389.5},
    {
        "pose": {**IN_ROBOT_POSE, "roll": 0.0, "pitch": 0.0, "yaw": 90.0},
        "sigma": {"translation_mm": 0.031, "rotation_deg": 0.006},
    },
    np.eye(4),
    np.zeros(3),
)
# the text GET /fixtures/NAME/pose and `hexapod serve --jsonl` gave for this record as a dict (docs/service.md)
JSON = (
    '{"fixture": "left", "t": 1795672991.5198855, "readings": [0.001, -0.002, null, 0.0, 1e-06, -0.004], '
    '"pose": {"x": 0.01, "y": -0.02, "z": 0.41, "qx": 0.1, "qy": -0.2, "qz": 0.3, "qw": 0.9273618495495703, '
    '"roll": 1.5, "pitch": -2.25, "yaw": 3.0}, "status": "ok", "flags": ["encoder_warning:leg2"], "iterations": 3, '
    '"state": "locked", "stored": true, "sigma": {"translation_mm": 0.0249, "rotation_deg": 0.006}, '
    '"singularity_margin": 0.95, "load": {"leg_forces_N": [10.5, -3.25, 0.0, 7.0, -1.0, 2.5], '
    '"largest_leg_force_N": 10.5, "brake_capacity_N": 400.0, "margin_N": 389.5}, "pose_in_robot": {"pose": '
    '{"x": 0.8, "y": -0.3, "z": 0.43, "qx": 0.0, "qy": 0.0, "qz": 0.7071067811865476, "qw": 0.7071067811865476, '
    '"roll": 0.0, "pitch": 0.0, "yaw": 90.0}, "sigma": {"translation_mm": 0.031, "rotation_deg": 0.006}}, '
    '"extra_readings": null, "consistency": null}'
)


def test_the_json_text_is_the_documented_one_key_for_key_and_byte_for_byte():
    assert RECORD.to_json() == JSON
    assert tuple(json.loads(JSON)) == RECORD_KEYS


def test_a_record_round_trips_through_its_json_object_and_text():
    back = PoseRecord.from_dict(json.loads(RECORD.to_json()))
    assert back.to_dict() == RECORD.to_dict() and back.to_json() == JSON
    assert back.transform is None and back.q is None  # the 4x4 pose and q are not in the JSON


def test_a_redundant_fixtures_record_carries_its_extra_readings_and_its_test():
    test = {"chi2": 3.25, "bound": 13.8155, "dof": 2, "alpha": 0.001}
    rec = RECORD._replace(extra_readings={"tilt_x": 0.0125, "tilt_y": None}, consistency=test)
    body = json.loads(rec.to_json())
    assert body["extra_readings"] == {"tilt_x": 0.0125, "tilt_y": None} and body["consistency"] == test
    assert PoseRecord.from_dict(body).to_dict() == rec.to_dict()


def test_a_record_written_before_the_extra_readings_reads_back_without_them():
    old = {k: v for k, v in json.loads(JSON).items() if k not in ("extra_readings", "consistency")}
    back = PoseRecord.from_dict(old)
    assert back.extra_readings is None and back.consistency is None and back.to_json() == JSON


def test_a_nan_is_never_sent_as_json():
    with pytest.raises(ValueError):
        RECORD._replace(singularity_margin=math.nan).to_json()


def test_the_record_is_frozen():
    with pytest.raises(AttributeError):
        RECORD.status = "flagged"  # type: ignore[misc]


def test_the_store_row_round_trips_through_sqlite(tmp_path):
    row = sample_row(RECORD)
    assert row == ("left", RECORD.t, "ok", '["encoder_warning:leg2"]', "locked", *RECORD.readings, *POSE.values())
    no_pose = sample_row(RECORD._replace(pose=None, flags=[]))
    assert no_pose[3] == "[]" and no_pose[-7:] == (None,) * 7
    with Store(tmp_path / "store.sqlite") as store:
        store.add_samples([row, no_pose])
        stored = store.samples("left")
    assert stored == [row, no_pose] and len(row) == len(SAMPLE_COLUMNS)
