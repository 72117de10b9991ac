"""The service's errors, members of the package's one error family (:class:`HexapodError`).

* :class:`ConfigError`: a configuration or simulation file is malformed; names the file, the
  dotted field (``fixtures[0].can_ids[3]``), the value found and why it cannot be used.
* :class:`FrameError`: a CAN frame does not fit the configured payload layout (too short, a
  count that does not fit its field).
* :class:`ServiceError`: the service cannot start or run: bus, store or HTTP port unavailable.
"""

from __future__ import annotations

from typing import Any

from ..exceptions import HexapodError


class ConfigError(HexapodError, ValueError):
    """A field of ``fixture.toml`` or ``sim.toml`` is missing, unknown or out of range.

    Attributes:
        field: dotted name of the field, e.g. ``"fixtures[1].encoder.width"``.
        value: the value found there (``None`` when missing).
        reason: what is expected.
        source: the file (or ``"<dict>"``).
    """

    def __init__(self, field: str, value: Any, reason: str, source: str = "<dict>"):
        self.field, self.value, self.reason, self.source = field, value, reason, source
        super().__init__(f"{source}: field {field!r} = {value!r}: {reason}")

    def within(self, prefix: str, source: str | None = None) -> ConfigError:
        """The same error with ``prefix`` put in front of its field (and ``source`` when given)."""
        sep = "" if self.field.startswith("[") else "."
        return ConfigError(f"{prefix}{sep}{self.field}", self.value, self.reason, source or self.source)


class FrameError(HexapodError, ValueError):
    """A frame payload or a count does not fit the configured layout."""


class ServiceError(HexapodError, RuntimeError):
    """The service cannot start or keep running (bus, store or HTTP address unavailable)."""
