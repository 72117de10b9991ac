""":class:`Table` reads one TOML table field by field, so that each error names its field."""

from __future__ import annotations

import math
from typing import Any

from ..errors import ConfigError

REQUIRED: Any = object()


class Table:
    """One table of a TOML file being validated: every key taken once, unknown keys refused.

    Args:
        data: the table (anything else is a :class:`ConfigError`).
        where: its dotted name (``""`` for the file's top level).
        source: the file, for the messages.
    """

    def __init__(self, data: Any, where: str, source: str):
        if not isinstance(data, dict):
            raise ConfigError(where or "<top>", data, "expected a table", source)
        self.data, self.where, self.source = data, where, source
        self._taken: set[str] = set()

    def name(self, key: str) -> str:
        """Dotted name of ``key`` in this table."""
        return f"{self.where}.{key}" if self.where else key

    def error(self, key: str, value: Any, reason: str) -> ConfigError:
        """A :class:`ConfigError` naming ``key`` of this table."""
        return ConfigError(self.name(key), value, reason, self.source)

    def take(self, key: str, default: Any = REQUIRED) -> Any:
        """The raw value of ``key``, or ``default``; a missing required key is an error."""
        self._taken.add(key)
        if key in self.data:
            return self.data[key]
        if default is REQUIRED:
            raise self.error(key, None, "missing (required)")
        return default

    def number(self, key: str, default: Any = REQUIRED, lo: float = -math.inf, hi: float = math.inf) -> float:
        """A finite float in ``[lo, hi]``."""
        v = self.take(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not lo <= v <= hi:
            raise self.error(key, v, f"expected a number in [{lo:g}, {hi:g}]")
        return float(v)

    def integer(self, key: str, default: Any = REQUIRED, lo: int = 0, hi: int = 2**63) -> int:
        """An int in ``[lo, hi]``."""
        v = self.take(key, default)
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise self.error(key, v, f"expected an integer in [{lo}, {hi}]")
        return v

    def boolean(self, key: str, default: Any = REQUIRED) -> bool:
        """``true`` or ``false``."""
        v = self.take(key, default)
        if not isinstance(v, bool):
            raise self.error(key, v, "expected true or false")
        return v

    def text(self, key: str, default: Any = REQUIRED, choices: tuple[str, ...] | None = None) -> str:
        """A non-empty string, one of ``choices`` when given."""
        v = self.take(key, default)
        if not isinstance(v, str) or not v or (choices is not None and v not in choices):
            expected = f"one of {', '.join(choices)}" if choices else "a non-empty string"
            raise self.error(key, v, f"expected {expected}")
        return v

    def table(self, key: str, default: Any = REQUIRED) -> Table:
        """A sub-table (``{}`` when missing and ``default`` is ``{}``)."""
        return Table(self.take(key, default), self.name(key), self.source)

    def finish(self) -> None:
        """Refuse keys that were never taken (a misspelt field would otherwise be ignored)."""
        unknown = sorted(set(self.data) - self._taken)
        if unknown:
            known = ", ".join(sorted(self._taken))
            raise self.error(unknown[0], self.data[unknown[0]], f"unknown field (known here: {known})")
