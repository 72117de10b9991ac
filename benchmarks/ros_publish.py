"""Cost of publishing the service's records as ROS 2 topics (not a test: figures are printed).

python benchmarks/ros_publish.py [--records 3000]

A :class:`~hexapod_model.ros.dds.RosBridge` on a localhost-only Cyclone DDS participant (domain 0,
no reader) is given ``ok`` records of the reference hexapod. Per record, in microseconds of the
thread's CPU time (steadier than wall time on a loaded machine): the publisher thread's work
(PoseStamped, JointState of 36 joints, /tf, and /diagnostics once a second: conversion, CDR and
DDS writes), with the records per second one core sustains, and the cycle thread's (the
subscriber's call: queue the record and a copy of its configuration, while the publisher runs).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from hexapod_model import Hexapod
from hexapod_model.ros.dds import QUEUE_LENGTH, RosBridge
from hexapod_model.service import FixtureService, config_from_dict
from hexapod_model.service.record.pose import pose_record
from hexapod_model.service.record.pose_record import PoseRecord


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=3000)
    args = parser.parse_args(argv)
    hexa = Hexapod.from_preset("reference", compiled=False)
    with tempfile.TemporaryDirectory() as tmp:
        data = {
            "bus": {"interface": "virtual", "channel": "ros-bench"},
            "store": {"path": str(Path(tmp) / "s.sqlite")},
            "fixtures": [{"name": "right", "hexapod": "reference", "can_ids": list(range(0x191, 0x197))}],
            "ros": {"namespace": "bench"},
        }
        config = config_from_dict(data, "bench.toml", Path(tmp))
        service = FixtureService(config, http=False, hexapods={"right": hexa})
        assert config.ros is not None
        bridge = RosBridge(service, config.ros).start()
        if bridge.error:
            print(f"cannot publish: {bridge.error}")
            return 1
        T = hexa.home_pose.copy()
        T[2, 3] += 0.01
        sol = hexa.inverse(T)
        t0 = time.time()
        records = [
            PoseRecord(
                "right",
                t0 + 0.01 * k,
                sol.lengths.tolist(),
                pose_record(T),
                "ok",
                [],
                0,
                "moving",
                False,
                {"translation_mm": 0.025, "rotation_deg": 0.006},
                0.95,
                None,
                None,
                T,
                sol.q,
            )
            for k in range(args.records)
        ]
        start = time.thread_time()
        for rec in records:
            bridge._publish(rec, sol.q)
        publish_us = (time.thread_time() - start) / len(records) * 1e6
        # the cycle thread's part: the subscriber call, a burst shorter than the queue
        burst = records[: QUEUE_LENGTH - 100]
        start = time.thread_time()
        for rec in burst:
            bridge._on_record(rec)
        queue_us = (time.thread_time() - start) / len(burst) * 1e6
        time.sleep(1.0)  # the publisher thread drains the queue
        bridge.stop()
    print(f"records: {len(records)} + {len(burst)} ok records of one fixture, messages written: {bridge.published}")
    print(f"publisher thread: {publish_us:.0f} us per record -> {1e6 / publish_us:.0f} records/s on one core")
    print(f"cycle thread (subscriber call: queue the record, copy its configuration): {queue_us:.1f} us per record")
    print(f"records dropped (queue full): {bridge.dropped}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
