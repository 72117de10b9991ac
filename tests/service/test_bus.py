"""The cycle's frame reader: python-can's recv, or the interface's own receive when the wrapper adds nothing."""

from __future__ import annotations

import uuid

import can

from hexapod_model.service.cycle.bus import receiver


def test_receiver_reads_what_recv_reads_and_keeps_software_filters():
    channel = f"test-{uuid.uuid4().hex}"
    sender = can.Bus(interface="virtual", channel=channel)
    plain = can.Bus(interface="virtual", channel=channel)
    filtered = can.Bus(interface="virtual", channel=channel, can_filters=[{"can_id": 0x181, "can_mask": 0x7FF}])
    try:
        assert receiver(filtered) == filtered.recv  # software filters: python-can applies them
        read = receiver(plain)
        assert read != plain.recv
        for can_id in (0x181, 0x182):
            sender.send(can.Message(arbitration_id=can_id, data=bytes([can_id & 0xFF, 1, 2])))
        got = [read(0.5) for _ in range(2)]
        assert [(m.arbitration_id, bytes(m.data)) for m in got] == [(0x181, b"\x81\x01\x02"), (0x182, b"\x82\x01\x02")]
        assert read(0.0) is None  # nothing queued: None after the timeout, as recv
        assert filtered.recv(0.5).arbitration_id == 0x181 and filtered.recv(0.0) is None
    finally:
        for bus in (sender, plain, filtered):
            bus.shutdown()
