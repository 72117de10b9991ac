"""The plan as a ROS 2 JointTrajectory in MCAP: read back, the same joints, times and values as the plan."""

from __future__ import annotations

import numpy as np
import pytest

from hexapod_model.planning.writers import read_plan

from .test_plan import planned  # noqa: F401  (the module's plan)

pytest.importorskip("mcap", reason="mcap is not installed: pip install 'hexapod_model[ros]'")
pytest.importorskip("rosbags", reason="rosbags is not installed: pip install 'hexapod_model[ros]'")


def test_the_mcap_holds_the_plans_trajectory(planned, tmp_path):  # noqa: F811
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_typestore

    from hexapod_model.ros.trajectory import TOPIC, TYPE, write_trajectory_mcap

    tmp, plan, _ = planned
    plan = read_plan(tmp / "plan.json")
    write_trajectory_mcap(plan, tmp_path / "plan.mcap", stamp=1000.0)
    with (tmp_path / "plan.mcap").open("rb") as f:
        messages = list(make_reader(f).iter_messages())
    assert len(messages) == 1
    schema, channel, message = messages[0]
    assert channel.topic == TOPIC and schema.name == TYPE
    msg = get_typestore(Stores.ROS2_JAZZY).deserialize_cdr(message.data, TYPE)
    assert list(msg.joint_names) == list(plan.joint_names) and len(msg.points) == len(plan.t)
    for k in (0, len(plan.t) // 3, len(plan.t) - 1):
        p = msg.points[k]
        np.testing.assert_array_equal(p.positions, plan.q[k])
        np.testing.assert_array_equal(p.velocities, plan.qd[k])
        t = p.time_from_start.sec + p.time_from_start.nanosec * 1e-9
        assert t == pytest.approx(plan.t[k], abs=1e-9)
