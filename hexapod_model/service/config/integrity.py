"""Frame integrity fields of an encoder layout: a rolling counter and a checksum byte.

Where the encoder's frame carries them, the cycle checks every frame
(:mod:`~hexapod_model.service.cycle.frame_checks`) and rejects one that fails, naming the check:

* **counter** (``counter = {offset, bits}`` in ``[fixtures.encoder]``): a rolling counter of
  ``bits`` bits (2..16) whose least significant bit is payload bit ``offset`` (bit ``b`` is
  bit ``b % 8`` of byte ``b // 8``, as for ``error_bit``). Each frame of a leg counts one up
  from that leg's previous frame, modulo ``2**bits``; any other value is ``counter_gap``: a
  lost frame, a second sender on the id (one that does not follow the sequence), a frame
  repeated or replayed.
* **checksum** (``crc = {offset, kind}``): payload byte ``offset`` holds a checksum of every
  other byte of the frame, in order; a frame whose byte differs is ``bad_crc``. ``kind``:

  - ``"crc8-sae-j1850"``: CRC-8 with polynomial ``0x1D`` (x^8 + x^4 + x^3 + x^2 + 1), initial
    value ``0xFF``, final XOR ``0xFF``, no reflection (SAE J1850, AUTOSAR's CRC8; check value
    ``0x4B`` for the ASCII bytes ``123456789``). Detects every error of up to 3 bits in a
    classic frame and every burst of up to 8.
  - ``"sum8"``: the bytes' sum modulo 256. Misses two flips of one bit position in two bytes
    that cancel.
  - ``"xor8"``: the bytes' XOR. Misses any even number of flips of one bit position.

* **SYNC counter** (CANopen, :mod:`~hexapod_model.service.cycle.canopen_link`): the link
  appends the counter of the SYNC a TPDO follows (0 for a SYNC without one) as the byte
  ``sync_byte``; a set whose legs' frames follow different SYNCs is ``sync_mismatch``.

CAN's own 15-bit CRC protects each frame on the wire; these fields catch what it cannot: a
gateway or driver that corrupts a frame after reception, a sender that is not the encoder,
frames lost or repeated between the encoder and the service.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import ConfigError
from .table import Table

MAX_PAYLOAD = 8  # classic CAN
CHECKSUMS = ("crc8-sae-j1850", "sum8", "xor8")
COUNTER_BITS = (2, 16)  # widths of a rolling counter accepted


def _crc8_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        c = byte
        for _ in range(8):
            c = ((c << 1) ^ 0x1D) & 0xFF if c & 0x80 else (c << 1) & 0xFF
        table.append(c)
    return tuple(table)


_CRC8 = _crc8_table()


def crc8_sae_j1850(data: bytes | bytearray) -> int:
    """CRC-8/SAE-J1850 of ``data``: polynomial ``0x1D``, initial ``0xFF``, final XOR ``0xFF``."""
    c = 0xFF
    for b in data:
        c = _CRC8[c ^ b]
    return c ^ 0xFF


def checksum(kind: str, data: bytes | bytearray) -> int:
    """The checksum ``kind`` (one of :data:`CHECKSUMS`) of ``data``."""
    if kind == "crc8-sae-j1850":
        return crc8_sae_j1850(data)
    if kind == "sum8":
        return sum(data) & 0xFF
    if kind == "xor8":
        x = 0
        for b in data:
            x ^= b
        return x
    raise ConfigError("crc.kind", kind, f"expected one of {', '.join(CHECKSUMS)}")


@dataclass(frozen=True)
class FrameIntegrity:
    """The integrity fields of a frame layout (none by default: nothing to check).

    Attributes:
        counter_bit: payload bit of the rolling counter's least significant bit, or ``None``.
        counter_bits: the counter's width (bits).
        crc_byte: payload byte holding the checksum of the other bytes, or ``None``.
        crc_kind: the checksum, one of :data:`CHECKSUMS`.
        sync_byte: payload byte holding the counter of the SYNC the frame follows (set by the
            CANopen link, not written in a file), or ``None``.
    """

    counter_bit: int | None = None
    counter_bits: int = 4
    crc_byte: int | None = None
    crc_kind: str = "crc8-sae-j1850"
    sync_byte: int | None = None

    def __post_init__(self) -> None:
        lo, hi = COUNTER_BITS
        if not lo <= self.counter_bits <= hi:
            raise ConfigError("counter.bits", self.counter_bits, f"expected {lo}..{hi} bits")
        if self.counter_bit is not None and not 0 <= self.counter_bit <= 8 * MAX_PAYLOAD - self.counter_bits:
            raise ConfigError(
                "counter.offset", self.counter_bit, f"the {self.counter_bits}-bit counter must end within bit 63"
            )
        if self.crc_byte is not None and not 0 <= self.crc_byte < MAX_PAYLOAD:
            raise ConfigError("crc.offset", self.crc_byte, f"expected a byte in 0..{MAX_PAYLOAD - 1}")
        if self.crc_kind not in CHECKSUMS:
            raise ConfigError("crc.kind", self.crc_kind, f"expected one of {', '.join(CHECKSUMS)}")
        if self.crc_byte is not None and self.crc_byte in self.counter_field(bytes_=True):
            raise ConfigError("crc.offset", self.crc_byte, "the checksum byte overlaps the counter")

    @classmethod
    def from_table(cls, t: Table) -> FrameIntegrity:
        """The ``counter`` and ``crc`` sub-tables of a ``[fixtures.encoder]`` table (both optional)."""
        counter_bit, counter_bits, crc_byte, crc_kind = None, 4, None, "crc8-sae-j1850"
        if "counter" in t.data:
            c = t.table("counter")
            counter_bits = c.integer("bits", 4, *COUNTER_BITS)
            counter_bit = c.integer("offset", lo=0, hi=8 * MAX_PAYLOAD - counter_bits)
            c.finish()
        if "crc" in t.data:
            c = t.table("crc")
            crc_byte = c.integer("offset", lo=0, hi=MAX_PAYLOAD - 1)
            crc_kind = c.text("kind", "crc8-sae-j1850", CHECKSUMS)
            c.finish()
        try:
            return cls(counter_bit, counter_bits, crc_byte, crc_kind)
        except ConfigError as exc:
            raise exc.within(t.where, t.source) from None

    def counter_field(self, bytes_: bool = False) -> range:
        """Payload bits of the counter (``bytes_``: the bytes they touch); empty without one."""
        if self.counter_bit is None:
            return range(0)
        if bytes_:
            return range(self.counter_bit // 8, (self.counter_bit + self.counter_bits - 1) // 8 + 1)
        return range(self.counter_bit, self.counter_bit + self.counter_bits)

    def used_bits(self) -> set[int]:
        """Every payload bit the integrity fields occupy."""
        bits = set(self.counter_field())
        for byte in (self.crc_byte, self.sync_byte):
            if byte is not None:
                bits.update(range(8 * byte, 8 * byte + 8))
        return bits

    @property
    def length(self) -> int:
        """Bytes a frame needs for these fields (0 without any)."""
        ends = [b + 1 for b in (self.crc_byte, self.sync_byte) if b is not None]
        if self.counter_bit is not None:
            ends.append(self.counter_field(bytes_=True).stop)
        return max(ends, default=0)

    @property
    def checked(self) -> bool:
        """Whether a frame carries anything to check."""
        return self.counter_bit is not None or self.crc_byte is not None or self.sync_byte is not None

    def counter(self, data: bytes | bytearray) -> int:
        """The rolling counter of a payload (the layout has one)."""
        assert self.counter_bit is not None
        return (int.from_bytes(data, "little") >> self.counter_bit) & ((1 << self.counter_bits) - 1)

    def crc_ok(self, data: bytes | bytearray) -> bool:
        """Whether the checksum byte of a payload matches its other bytes (the layout has one)."""
        k = self.crc_byte
        assert k is not None
        return len(data) > k and checksum(self.crc_kind, bytes(data[:k]) + bytes(data[k + 1 :])) == data[k]

    def seal(self, data: bytearray, counter: int) -> None:
        """Write ``counter`` (modulo the counter's range) and then the checksum into ``data``, as an encoder does."""
        if self.counter_bit is not None:
            mask = ((1 << self.counter_bits) - 1) << self.counter_bit
            value = int.from_bytes(data, "little") & ~mask | ((counter << self.counter_bit) & mask)
            data[:] = value.to_bytes(len(data), "little")
        k = self.crc_byte
        if k is not None:
            data[k] = checksum(self.crc_kind, bytes(data[:k]) + bytes(data[k + 1 :]))
