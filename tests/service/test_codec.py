"""Frame codec: payload layouts (byte order, offset/width, sign, bits), readings, no clamping."""

from __future__ import annotations

import can
import pytest

from hexapod_model.service import ConfigError, FrameError, FrameLayout, LegCodec, decode, encode


def test_default_layout_bytes_are_ours_as_documented():
    layout = FrameLayout()
    data = encode(layout, -2, error=True)
    # little-endian signed 32-bit count in bytes 0-3, error = bit 0 of byte 4, warning = bit 1
    assert data == bytes([0xFE, 0xFF, 0xFF, 0xFF, 0x01])
    assert decode(layout, data) == decode(layout, data + b"\x00\x00\x00")
    d = decode(layout, bytes([0x10, 0x27, 0, 0, 0x02, 0, 0, 0]))
    assert (d.position, d.error, d.warning) == (10000, False, True)


def test_big_endian_unsigned_field_at_an_offset():
    layout = FrameLayout(byte_order="big", offset=2, width=3, signed=False, error_bit=7, warning_bit=0)
    data = encode(layout, 0x123456, error=True)
    assert data == bytes([0x80, 0x00, 0x12, 0x34, 0x56])
    d = decode(layout, data)
    assert (d.position, d.error, d.warning) == (0x123456, True, False)  # warning bit 0 is clear


@pytest.mark.parametrize("order", ["little", "big"])
@pytest.mark.parametrize("width,signed", [(1, True), (2, False), (3, True), (4, False), (8, True)])
def test_round_trip_at_the_field_limits(order, width, signed):
    layout = FrameLayout(byte_order=order, offset=0, width=width, signed=signed, error_bit=None, warning_bit=None)
    lo, hi = layout.count_range
    for count in (lo, lo + 1, 0 if signed else 1, hi - 1, hi):
        assert decode(layout, encode(layout, count)).position == count
    with pytest.raises(FrameError, match="does not fit"):
        encode(layout, hi + 1)
    with pytest.raises(FrameError, match="does not fit"):
        encode(layout, lo - 1)


def test_short_payload_is_an_error_not_a_guess():
    with pytest.raises(FrameError, match="payload of 4 bytes; the layout needs 5"):
        decode(FrameLayout(), b"\x00\x00\x00\x00")


def test_leg_reading_home_count_and_direction():
    leg = LegCodec(0x181, FrameLayout(metres_per_count=1e-6), home_count=100_000)
    assert leg.reading(100_000) == 0.0
    assert leg.reading(112_345) == pytest.approx(0.012345, abs=1e-15)
    assert leg.count(-0.0205) == 79_500
    reversed_leg = LegCodec(0x181, FrameLayout(metres_per_count=-1e-6), home_count=0)
    assert reversed_leg.reading(reversed_leg.count(0.01)) == pytest.approx(0.01, abs=1e-12)
    msg = leg.message(0.002, warning=True)
    assert isinstance(msg, can.Message) and msg.arbitration_id == 0x181 and not msg.is_extended_id
    d = decode(leg.layout, msg.data)
    assert leg.reading(d.position) == pytest.approx(0.002, abs=1e-12) and d.warning and not d.error
    small = LegCodec(1, FrameLayout(width=1, signed=False, error_bit=None, warning_bit=None))
    with pytest.raises(FrameError, match="outside the field"):
        small.message(0.001)  # 1000 counts in an 8-bit field: refused, never clamped


@pytest.mark.parametrize(
    "kwargs,field",
    [
        ({"byte_order": "middle"}, "byte_order"),
        ({"width": 9}, "width"),
        ({"offset": 6, "width": 4}, "offset"),
        ({"metres_per_count": 0.0}, "metres_per_count"),
        ({"error_bit": 3}, "error_bit"),  # inside the count field (bits 0..31)
        ({"warning_bit": 64}, "warning_bit"),
        ({"error_bit": 40, "warning_bit": 40}, "warning_bit"),
    ],
)
def test_bad_layouts_name_the_field(kwargs, field):
    with pytest.raises(ConfigError) as info:
        FrameLayout(**kwargs)
    assert info.value.field == field
