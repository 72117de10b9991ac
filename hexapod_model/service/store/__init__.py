"""The fixture store (SQLite): lock events, the sample log, the changeover's tables, and its writer thread."""

from .fixture_store import LockEvent, Store
from .writer import StoreWriter

__all__ = ["LockEvent", "Store", "StoreWriter"]
