"""The service's bus: python-can's public receive, the configured interface, frames in order."""

from __future__ import annotations

import can

from hexapod_model.service.cycle.bus import open_bus

from .helpers import service_config


def test_the_configured_bus_reads_the_frames_sent_in_order(tmp_path):
    config = service_config(tmp_path)
    sender = can.Bus(interface="virtual", channel=config.bus.channel)
    bus = open_bus(config)
    try:
        for can_id in (0x181, 0x182):
            sender.send(can.Message(arbitration_id=can_id, data=bytes([can_id & 0xFF, 1, 2])))
        got = [bus.recv(0.5) for _ in range(2)]
        assert [(m.arbitration_id, bytes(m.data)) for m in got] == [(0x181, b"\x81\x01\x02"), (0x182, b"\x82\x01\x02")]
        assert bus.recv(0.0) is None  # nothing queued: None after the timeout
    finally:
        sender.shutdown()
        bus.shutdown()
