"""The store's one writer thread: samples in batches, lock events at once, store errors held until they clear."""

from __future__ import annotations

import logging
import queue
import sqlite3
import threading
from collections import deque
from collections.abc import Callable
from functools import partial

from ..threads import NamedThread
from .fixture_store import LockEvent, Store

log = logging.getLogger(__name__)


MAX_PENDING = 100_000  # sample rows held for the writer at most (a stalled disk drops the oldest)


class StoreWriter:
    """The one thread that writes to the store: samples in batches, lock events at once.

    :meth:`sample` only appends to a bounded in-memory log (no wake-up of this thread per
    record: the cycle thread keeps the GIL and the CPU); the thread takes the log every
    ``flush_interval`` and writes it in one transaction. :meth:`lock` wakes it at once: the
    event is committed durably together with the samples queued before it.

    Args:
        store: the open :class:`Store`.
        flush_interval: seconds between sample batches.
        max_pending: sample rows kept while the store lags (the oldest are dropped beyond).
    """

    def __init__(self, store: Store, flush_interval: float = 0.5, max_pending: int = MAX_PENDING):
        self.store, self.flush_interval = store, flush_interval
        self.error: str | None = None
        #: sample rows lost, since the start: the log was full, or a store error failed their batch
        self.dropped = 0
        self._rows: deque[tuple] = deque()  # append / popleft are atomic: no lock on the cycle's path
        self._max = max_pending
        self._locks: queue.SimpleQueue = queue.SimpleQueue()
        self._retry: list[tuple[LockEvent, Callable[[LockEvent], None]]] = []  # locks a store error held back
        self._wake = threading.Event()
        self._stopping = False
        self._thread = NamedThread(target=self._run, name="hx-store")
        self._thread.start()

    def sample(self, row: tuple) -> None:
        """Queue a sample row (``SAMPLE_COLUMNS`` order); written within ``flush_interval``."""
        rows = self._rows
        rows.append(row)
        if len(rows) > self._max:
            rows.popleft()
            self.dropped += 1

    def lock(self, event: LockEvent, done: Callable[[LockEvent], None]) -> None:
        """Queue a lock event; ``done(stored_event)`` is called once it is committed durably."""
        self._locks.put((event, done))
        self._wake.set()

    def stop(self) -> None:
        """Write what is queued and end the thread."""
        self._stopping = True
        self._wake.set()
        self._thread.join()

    def _take(self) -> list[tuple]:
        rows, out = self._rows, []
        for _ in range(len(rows)):  # what is there now; later rows wait for the next batch
            out.append(rows.popleft())
        return out

    def _run(self) -> None:
        while True:
            self._wake.wait(self.flush_interval)
            self._wake.clear()  # a lock queued from here on sets it again
            stopping = self._stopping
            pending = self._take()
            locks, self._retry = self._retry, []
            while True:
                try:
                    locks.append(self._locks.get_nowait())
                except queue.Empty:
                    break
            for event, done in locks:
                if not self._write(partial(self.store.add_lock, event, pending), done):
                    self._retry.append((event, done))  # tried again at the next batch: stored once it can be
                    self.dropped += len(pending)  # the rows go with the failed transaction
                pending = []  # committed with the lock (or dropped with it on a store error)
            if pending and not self._write(partial(self.store.add_samples, pending)):
                self.dropped += len(pending)
            if stopping:
                return

    def _write(self, commit: Callable[[], LockEvent | None], done: Callable[[LockEvent], None] | None = None) -> bool:
        """Run ``commit``, then ``done`` with its result; a store error is recorded (until a write succeeds)."""
        try:
            result = commit()
        except (sqlite3.Error, OSError) as exc:
            error = f"store {self.store.path}: {exc}"
            if error != self.error:
                log.error("%s", error)
            self.error = error
            return False
        if self.error is not None:
            log.warning(
                "store %s: writing again (%d locks waited; %d sample rows lost since the start)",
                self.store.path,
                len(self._retry),
                self.dropped,
            )
            self.error = None
        if done is not None and result is not None:
            done(result)
        return True
