"""The service's CAN bus: python-can, with kernel filters on SocketCAN."""

from __future__ import annotations

from typing import Any

import can

from ..config.settings import ServiceConfig
from ..errors import ServiceError


def open_bus(config: ServiceConfig, receive: bool = True) -> can.BusABC:
    """The configured python-can bus (:class:`ServiceError` if it cannot be opened).

    With ``receive`` on SocketCAN the kernel delivers only the fixtures' CAN ids (a CANopen
    fixture's SYNC, EMCY and heartbeat ids too). Other interfaces
    would filter in Python, frame by frame (30 us a frame with 120 ids on the virtual bus), so
    there the service's own id table drops the others.
    """
    b = config.bus
    filters = None
    if receive and b.interface == "socketcan":
        filters = [
            {"can_id": leg.can_id, "can_mask": 0x1FFFFFFF if leg.extended_id else 0x7FF, "extended": leg.extended_id}
            for f in config.fixtures
            for leg in f.legs
        ]
        extra = {can_id for f in config.fixtures if f.canopen is not None for can_id in f.canopen.ids()}
        filters += [{"can_id": can_id, "can_mask": 0x7FF, "extended": False} for can_id in sorted(extra)]
    kwargs: dict[str, Any] = {"bitrate": b.bitrate} if b.bitrate else {}
    try:
        return can.Bus(interface=b.interface, channel=b.channel, can_filters=filters, **kwargs)
    except (can.CanError, OSError, ImportError, ValueError) as exc:
        raise ServiceError(f"bus {b.interface}/{b.channel}: cannot open: {exc}") from None
