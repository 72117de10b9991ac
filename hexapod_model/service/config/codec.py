"""Encoder CAN frames <-> leg readings: the payload layout of one fixture's absolute encoders.

A frame carries the position count of one leg's encoder and status bits. The layout is
configurable per fixture (``[fixtures.encoder]`` in ``fixture.toml``) because encoders differ;
**our defaults** (no manufacturer's layout is implied) are: a little-endian signed 32-bit count
in bytes 0-3, the *error* bit at bit 32 (bit 0 of byte 4) and the *warning* bit at bit 33,
1 µm per count.

Bit positions count from bit 0 = least significant bit of payload byte 0; bit ``b`` is bit
``b % 8`` of byte ``b // 8``. The reading of a leg (metres, zero at home, as the solver takes
it) is ``(count - home_count) * metres_per_count``; nothing is clamped or wrapped: a count that
does not fit the field is a :class:`FrameError`.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import can

from ..errors import ConfigError, FrameError
from .integrity import MAX_PAYLOAD, FrameIntegrity
from .table import Table

MAX_SAMPLE_PERIOD = 10.0  # s


@dataclass(frozen=True)
class FrameLayout:
    """Payload layout of an encoder frame.

    Attributes:
        byte_order: ``"little"`` or ``"big"`` (of the count field).
        offset: first byte of the count field.
        width: bytes of the count field (1..8).
        signed: two's-complement count when true.
        metres_per_count: reading per count (m); negative for an encoder counting against the
            leg's extension.
        error_bit: payload bit meaning *error* (reading unusable), or ``None`` (``-1`` in the file).
        warning_bit: payload bit meaning *warning* (reading usable, e.g. signal margin low), or
            ``None`` (``-1`` in the file).
        integrity: the frame's rolling counter and checksum byte, if any
            (:mod:`~hexapod_model.service.config.integrity`).
        sample_period: the encoders' sampling (or SYNC) period (s; 0: not given): it splits a
            batching gateway's bursts into instants (:mod:`~hexapod_model.service.cycle.burst`).
    """

    byte_order: str = "little"
    offset: int = 0
    width: int = 4
    signed: bool = True
    metres_per_count: float = 1e-6
    error_bit: int | None = 32
    warning_bit: int | None = 33
    integrity: FrameIntegrity = FrameIntegrity()
    sample_period: float = 0.0

    def __post_init__(self) -> None:
        if not 0.0 <= self.sample_period <= MAX_SAMPLE_PERIOD:
            raise ConfigError("sample_period", self.sample_period, f"expected 0 (not given) to {MAX_SAMPLE_PERIOD:g} s")
        if self.byte_order not in ("little", "big"):
            raise ConfigError("byte_order", self.byte_order, "expected 'little' or 'big'")
        if not 1 <= self.width <= MAX_PAYLOAD:
            raise ConfigError("width", self.width, f"expected 1..{MAX_PAYLOAD} bytes")
        if not 0 <= self.offset <= MAX_PAYLOAD - self.width:
            raise ConfigError("offset", self.offset, f"the {self.width}-byte count must end within {MAX_PAYLOAD} bytes")
        if not (abs(self.metres_per_count) > 0 and abs(self.metres_per_count) < 1):
            raise ConfigError(
                "metres_per_count", self.metres_per_count, "expected a non-zero number of magnitude < 1 m"
            )
        count_bits = range(8 * self.offset, 8 * (self.offset + self.width))
        for name in ("error_bit", "warning_bit"):
            b = getattr(self, name)
            if b is None:
                continue
            if not 0 <= b < 8 * MAX_PAYLOAD:
                raise ConfigError(name, b, f"expected a bit position in 0..{8 * MAX_PAYLOAD - 1}")
            if b in count_bits:
                raise ConfigError(
                    name, b, f"lies inside the count field (bits {count_bits.start}..{count_bits.stop - 1})"
                )
        if self.error_bit is not None and self.error_bit == self.warning_bit:
            raise ConfigError("warning_bit", self.warning_bit, "same bit as error_bit")
        taken = self.integrity.used_bits()
        for name, bits in (
            ("offset", set(count_bits)),
            ("error_bit", {self.error_bit}),
            ("warning_bit", {self.warning_bit}),
        ):
            if bits & taken:
                raise ConfigError(name, getattr(self, name), "overlaps the frame's counter or checksum")

    @classmethod
    def from_table(cls, t: Table) -> FrameLayout:
        """Read a ``[fixtures.encoder]`` table (missing keys take our defaults)."""
        d = cls()

        def bit(key: str, default: int | None) -> int | None:  # -1: the encoder has no such bit
            v = t.integer(key, -1 if default is None else default, -1, 8 * MAX_PAYLOAD - 1)
            return None if v == -1 else v

        try:
            layout = cls(
                byte_order=t.text("byte_order", d.byte_order, ("little", "big")),
                offset=t.integer("offset", d.offset, 0, MAX_PAYLOAD - 1),
                width=t.integer("width", d.width, 1, MAX_PAYLOAD),
                signed=t.boolean("signed", d.signed),
                metres_per_count=t.number("metres_per_count", d.metres_per_count, -1.0, 1.0),
                error_bit=bit("error_bit", d.error_bit),
                warning_bit=bit("warning_bit", d.warning_bit),
                integrity=FrameIntegrity.from_table(t),
                sample_period=t.number("sample_period", 0.0, 0.0, MAX_SAMPLE_PERIOD),
            )
        except ConfigError as exc:
            if exc.field.startswith(t.where):
                raise
            raise exc.within(t.where, t.source) from None
        t.finish()
        return layout

    @cached_property
    def length(self) -> int:
        """Bytes a frame needs: the count field, every status bit and the integrity fields."""
        bits = [b for b in (self.error_bit, self.warning_bit) if b is not None]
        return max([self.offset + self.width, self.integrity.length] + [b // 8 + 1 for b in bits])

    @cached_property
    def count_range(self) -> tuple[int, int]:
        """Smallest and largest count the field holds."""
        n = 8 * self.width
        return (-(1 << (n - 1)), (1 << (n - 1)) - 1) if self.signed else (0, (1 << n) - 1)

    @cached_property
    def unpack(self) -> Callable[[bytes | bytearray], tuple[int, bool, bool]]:
        """``data -> (count, error, warning)`` for this layout, its format compiled once.

        The cycle's per-frame decoder (:func:`decode` checks the length first, then calls it):
        a precompiled :class:`struct.Struct` for 1, 2, 4 and 8-byte fields, ``int.from_bytes``
        otherwise; status bits as a byte index and mask.
        """
        start, stop = self.offset, self.offset + self.width
        order, signed = self.byte_order, self.signed
        code = {1: "b", 2: "h", 4: "i", 8: "q"}.get(self.width)
        e, w = self.error_bit, self.warning_bit
        eb, em = (0, 0) if e is None else (e >> 3, 1 << (e & 7))
        wb, wm = (0, 0) if w is None else (w >> 3, 1 << (w & 7))
        if code is not None:  # one Python call a frame: the count is read inside it, not by a function of its own
            fmt = struct.Struct(("<" if order == "little" else ">") + (code if signed else code.upper()))
            unpack_from, offset = fmt.unpack_from, self.offset

            def unpack(data: bytes | bytearray) -> tuple[int, bool, bool]:
                return unpack_from(data, offset)[0], bool(data[eb] & em), bool(data[wb] & wm)
        else:

            def unpack(data: bytes | bytearray) -> tuple[int, bool, bool]:
                count = int.from_bytes(data[start:stop], order, signed=signed)  # type: ignore[arg-type]
                return count, bool(data[eb] & em), bool(data[wb] & wm)

        return unpack


class Decoded(NamedTuple):
    """One decoded frame: the raw position count and the status bits."""

    position: int
    error: bool
    warning: bool


def decode(layout: FrameLayout, data: bytes | bytearray) -> Decoded:
    """Count and status bits of a payload; :class:`FrameError` when it is too short."""
    if len(data) < layout.length:
        raise FrameError(f"payload of {len(data)} bytes; the layout needs {layout.length}")
    return Decoded(*layout.unpack(data))


def encode(layout: FrameLayout, count: int, error: bool = False, warning: bool = False, counter: int = 0) -> bytes:
    """Payload of ``layout.length`` bytes; :class:`FrameError` when ``count`` does not fit the field.

    A layout with a rolling counter carries ``counter`` (modulo its range), one with a checksum
    byte the checksum of the other bytes (:mod:`~hexapod_model.service.config.integrity`).
    """
    lo, hi = layout.count_range
    if not lo <= count <= hi:
        raise FrameError(f"count {count} does not fit the {8 * layout.width}-bit field [{lo}, {hi}]")
    data = bytearray(layout.length)
    data[layout.offset : layout.offset + layout.width] = count.to_bytes(
        layout.width,
        layout.byte_order,  # type: ignore[arg-type]
        signed=layout.signed,
    )
    for bit, on in ((layout.error_bit, error), (layout.warning_bit, warning)):
        if on and bit is not None:
            data[bit >> 3] |= 1 << (bit & 7)
    layout.integrity.seal(data, counter)
    return bytes(data)


@dataclass(frozen=True)
class LegCodec:
    """One leg's encoder: its CAN id, the fixture's layout and its count at home.

    Attributes:
        can_id: arbitration id of the leg's frames.
        layout: the payload layout.
        home_count: the count at the home reading (reading 0 m).
        extended_id: 29-bit identifier.
    """

    can_id: int
    layout: FrameLayout
    home_count: int = 0
    extended_id: bool = False

    def reading(self, count: int) -> float:
        """Leg reading (m, zero at home) of a count."""
        return (count - self.home_count) * self.layout.metres_per_count

    def count(self, reading: float) -> int:
        """Nearest count of a leg reading (m); :class:`FrameError` when outside the field."""
        c = self.home_count + round(reading / self.layout.metres_per_count)
        lo, hi = self.layout.count_range
        if not lo <= c <= hi:
            raise FrameError(f"reading {reading!r} m is count {c}, outside the field [{lo}, {hi}]")
        return c

    def message(self, reading: float, error: bool = False, warning: bool = False, counter: int = 0) -> can.Message:
        """The ``can.Message`` an encoder at ``reading`` (m) sends (``counter``: its rolling counter, if any)."""
        return can.Message(
            arbitration_id=self.can_id,
            is_extended_id=self.extended_id,
            data=encode(self.layout, self.count(reading), error, warning, counter),
        )
