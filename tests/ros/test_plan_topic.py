"""A played changeover plan on /hexapod/changeover/trajectory over DDS: a late subscriber gets the MCAP's message."""

from __future__ import annotations

import time

import can
import numpy as np
import pytest

from hexapod_model.service import FixtureService, Simulator

from ..conftest import hexapod
from ..service.helpers import fixture_table, service_config
from ..service.test_plan_play import CELLS, make_plan, simulation
from .conftest import need_extra, run_domain

pytestmark = pytest.mark.ros


def test_the_played_plan_is_on_the_trajectory_topic_for_a_late_subscriber(tmp_path):
    need_extra()
    from cyclonedds.core import Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.qos import Policy
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration
    from rosbags.typesys import Stores, get_typestore

    from hexapod_model.ros.dds import RosBridge
    from hexapod_model.ros.plan_topic import ROS_NAME, JointTrajectory, trajectory
    from hexapod_model.ros.trajectory import TOPIC, trajectory_message

    fixtures = [fixture_table("left", 0, cell=CELLS["left"]), fixture_table("right", 1, cell=CELLS["right"])]
    config = service_config(tmp_path, fixtures, ros={"domain_id": run_domain()})
    plan = make_plan(config)
    sim = simulation(tmp_path, config, plan, start=1.0)
    hexa = hexapod("reference")
    hexapods = {"left": hexa, "right": hexa}
    service = FixtureService(config, hexapods=hexapods, http=False)
    bridge = RosBridge(service, config.ros)
    bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    simulator = Simulator(config, sim, bus, hexapods=hexapods)
    got: list = []
    try:
        service.start()
        bridge.start()
        simulator.start()
        bridge.publish_plan(sim.plan.plan)
        time.sleep(0.3)
        participant = DomainParticipant(run_domain())  # joins after the write: transient local keeps it
        qos = Qos(
            Policy.Reliability.Reliable(duration(seconds=1)),
            Policy.Durability.TransientLocal,
            Policy.History.KeepLast(1),
        )
        reader = DataReader(participant, Topic(participant, "rt" + TOPIC, JointTrajectory, qos=qos), qos=qos)
        end = time.monotonic() + 5
        while not got and time.monotonic() < end:
            got.extend(m for m in reader.take(N=10) if isinstance(m, JointTrajectory))
            time.sleep(0.05)
        del reader, participant
        health = bridge.health()
    finally:
        simulator.stop()
        bridge.stop()
        service.stop()
        bus.shutdown()
    assert health["error"] is None, health
    ((msg,),) = [got]
    assert msg.joint_names == list(plan.joint_names) and len(msg.points) == len(plan.t)
    assert np.array_equal([p.positions for p in msg.points], plan.q)
    t = [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in msg.points]
    assert np.allclose(t, plan.t - plan.t[0], atol=1e-9)
    # the same bytes as the MCAP file's message of a stamp (rosbags' CDR of ROS 2's definition)
    store = get_typestore(Stores.ROS2_JAZZY)
    stamp = 1.7e9 + 0.25
    mcap = trajectory_message(plan, stamp, store)
    assert msg.header.frame_id == mcap.header.frame_id
    assert bytes(store.serialize_cdr(mcap, ROS_NAME))[4:] == trajectory(plan, stamp).serialize(use_version_2=False)[4:]
