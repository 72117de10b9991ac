"""The fixture store: SQLite in WAL mode, lock events committed durably, a bounded sample log.

Schema (version 2; the tables ``docs/service.md`` documents):

* ``lock_events``: one row per lock (the brakes' engaged pose): ``fixture``, ``t`` (s, Unix
  time of the reading set that completed the lock), ``x, y, z`` (m) and ``qx, qy, qz, qw`` (base
  -> platform), ``l1..l6`` (m, the mean readings of the steady run the pose was solved from),
  ``status``, ``geometry_hash`` (SHA-256 of the URDF it was solved with) and ``q`` (JSON list: the
  Pinocchio configuration, the tracker's initial guess after a restart), ``target_id`` and
  ``recipe`` (the changeover target the lock met, NULL when none; added in version 2).
* ``samples``: published records (``fixture``, ``t``, ``status``, ``flags`` as JSON, ``state``,
  ``l1..l6``, pose columns; NULL when there is none), the newest ``samples`` rows kept.
* ``meta``: ``schema_version``.
* ``targets``, ``recipes``, ``activations``: the changeover's (:mod:`~hexapod_model.service.target_store`,
  which also migrates a version-1 file when it is opened).

``synchronous=FULL``: a commit is on disk (the WAL file fsync'ed) when :meth:`Store.add_lock`
returns, so a lock published as stored survives a crash or a power loss. Writes happen on one
writer thread (:class:`StoreWriter`), off the cycle's path.
"""

from __future__ import annotations

import json
import logging
import queue
import sqlite3
import threading
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path

import numpy as np

from .errors import ServiceError
from .target_store import TargetStore, migrate

log = logging.getLogger(__name__)
LEGS = ", ".join(f"l{i}" for i in range(1, 7))
POSE = "x, y, z, qx, qy, qz, qw"
_LOCK_TAIL = "status, geometry_hash, q, target_id, recipe"
SAMPLE_COLUMNS = ("fixture", "t", "status", "flags", "state", *LEGS.split(", "), *POSE.split(", "))
_SCHEMA = f"""
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS lock_events (
    id INTEGER PRIMARY KEY AUTOINCREMENT, fixture TEXT NOT NULL, t REAL NOT NULL,
    {", ".join(c + " REAL NOT NULL" for c in POSE.split(", "))},
    {", ".join(c + " REAL NOT NULL" for c in LEGS.split(", "))},
    status TEXT NOT NULL, geometry_hash TEXT NOT NULL, q TEXT NOT NULL, target_id INTEGER, recipe TEXT);
CREATE INDEX IF NOT EXISTS lock_events_fixture ON lock_events (fixture, id);
CREATE TABLE IF NOT EXISTS samples (
    id INTEGER PRIMARY KEY AUTOINCREMENT, fixture TEXT NOT NULL, t REAL NOT NULL, status TEXT NOT NULL,
    flags TEXT NOT NULL, state TEXT NOT NULL, {", ".join(c + " REAL" for c in (*LEGS.split(", "), *POSE.split(", ")))});
CREATE INDEX IF NOT EXISTS samples_t ON samples (t);
"""


@dataclass(frozen=True)
class LockEvent:
    """A stored lock.

    Attributes:
        fixture: its name.
        t: Unix time (s) of the set that completed the lock.
        position: (3,) platform origin in the base frame (m).
        quaternion: (4,) ``qx, qy, qz, qw`` of the platform orientation in the base frame.
        readings: (6,) mean readings of the steady run (m).
        status: ``ok`` (only good poses are stored as locks).
        geometry_hash: :func:`hexapod_model.service.config.geometry_hash` of the hexapod used.
        q: the solution's Pinocchio configuration.
        id: row id once stored.
        target_id: the stored target the lock pose met (within its tolerance), or None.
        recipe: the recipe that target came from, or None.
    """

    fixture: str
    t: float
    position: np.ndarray
    quaternion: np.ndarray
    readings: np.ndarray
    status: str
    geometry_hash: str
    q: np.ndarray
    id: int | None = None
    target_id: int | None = None
    recipe: str | None = None


class Store:
    """The SQLite file: create (or open) it, write lock events and samples, read them back.

    Args:
        path: the database file.
        samples: rows of the sample log kept (older ones deleted).
        create: create the file when missing (else :class:`ServiceError`).
    """

    def __init__(self, path: str | Path, samples: int = 100_000, create: bool = True):
        self.path, self.max_samples = Path(path), samples
        if not create and not self.path.is_file():
            raise ServiceError(f"store {self.path} does not exist (the service creates it on its first start)")
        try:
            self.db = sqlite3.connect(self.path, check_same_thread=False, isolation_level=None, timeout=10.0)
            mode = self.db.execute("PRAGMA journal_mode=WAL").fetchone()[0]
            self.db.execute("PRAGMA synchronous=FULL")
            check = self.db.execute("PRAGMA quick_check").fetchone()[0]
            if check != "ok":
                raise ServiceError(f"store {self.path} is damaged: {check}")
            self.db.executescript(_SCHEMA)
            migrate(self.db, self.path)
        except sqlite3.Error as exc:
            raise ServiceError(f"store {self.path}: {exc}") from None
        if mode.lower() != "wal":
            raise ServiceError(f"store {self.path}: SQLite refused WAL mode (journal_mode={mode})")
        self._lock = threading.Lock()
        #: the changeover's targets, recipes and activations
        self.targets = TargetStore(self.db, self._lock)

    def close(self) -> None:
        """Close the connection (the WAL is checkpointed by SQLite)."""
        with self._lock:
            self.db.close()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def add_lock(self, event: LockEvent, samples: Sequence[tuple] = ()) -> LockEvent:
        """Commit ``event`` (and pending ``samples``) durably; returns it with its ``id``."""
        values = (event.t, *event.position, *event.quaternion, *event.readings)
        q = json.dumps(event.q.tolist())
        row = (event.fixture, *map(float, values), event.status, event.geometry_hash, q, event.target_id, event.recipe)
        with self._lock:
            self.db.execute("BEGIN IMMEDIATE")
            try:
                cur = self.db.execute(
                    f"INSERT INTO lock_events (fixture, t, {POSE}, {LEGS}, {_LOCK_TAIL}) "
                    f"VALUES ({', '.join('?' * len(row))})",
                    row,
                )
                self._insert_samples(samples)
                self.db.execute("COMMIT")
            except BaseException:
                self.db.execute("ROLLBACK")
                raise
        return replace(event, id=cur.lastrowid)

    def add_samples(self, samples: Sequence[tuple]) -> None:
        """Append sample rows (``SAMPLE_COLUMNS`` order) and drop the oldest beyond the bound."""
        with self._lock:
            self.db.execute("BEGIN IMMEDIATE")
            try:
                self._insert_samples(samples)
                self.db.execute("COMMIT")
            except BaseException:
                self.db.execute("ROLLBACK")
                raise

    def _insert_samples(self, samples: Sequence[tuple]) -> None:
        if not samples:
            return
        marks = ", ".join("?" * len(SAMPLE_COLUMNS))
        self.db.executemany(f"INSERT INTO samples ({', '.join(SAMPLE_COLUMNS)}) VALUES ({marks})", samples)
        last = self.db.execute("SELECT MAX(id) FROM samples").fetchone()[0]
        self.db.execute("DELETE FROM samples WHERE id <= ?", (last - self.max_samples,))

    def locks(self, fixture: str | None = None, since: float | None = None) -> list[LockEvent]:
        """Stored lock events, oldest first (of one fixture, from time ``since``)."""
        return self._locks("(? IS NULL OR fixture = ?) AND t >= ? ORDER BY id", (fixture, fixture, _since(since)))

    def last_lock(self, fixture: str) -> LockEvent | None:
        """The newest lock event of ``fixture``, or None."""
        found = self._locks("fixture = ? ORDER BY id DESC LIMIT 1", (fixture,))
        return found[0] if found else None

    def _locks(self, where: str, args: tuple) -> list[LockEvent]:
        sql = f"SELECT id, fixture, t, {POSE}, {LEGS}, {_LOCK_TAIL} FROM lock_events WHERE {where}"
        with self._lock:
            rows = self.db.execute(sql, args).fetchall()
        return [
            LockEvent(
                r[1],
                r[2],
                np.array(r[3:6]),
                np.array(r[6:10]),
                np.array(r[10:16]),
                r[16],
                r[17],
                np.array(json.loads(r[18]), dtype=float),
                r[0],
                r[19],
                r[20],
            )
            for r in rows
        ]

    def samples(self, fixture: str | None = None, since: float | None = None) -> list[tuple]:
        """Sample rows (``SAMPLE_COLUMNS`` order), oldest first."""
        sql = f"SELECT {', '.join(SAMPLE_COLUMNS)} FROM samples WHERE (? IS NULL OR fixture = ?) AND t >= ? ORDER BY id"
        with self._lock:
            return self.db.execute(sql, (fixture, fixture, _since(since))).fetchall()


def _since(since: float | None) -> float:
    return -1e300 if since is None else float(since)


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
        self.dropped = 0  # sample rows dropped because the log was full
        self._rows: deque[tuple] = deque()  # append / popleft are atomic: no lock on the cycle's path
        self._max = max_pending
        self._locks: queue.SimpleQueue = queue.SimpleQueue()
        self._wake = threading.Event()
        self._stopping = False
        self._thread = threading.Thread(target=self._run, name="hexapod-store", daemon=True)
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
            while True:
                try:
                    event, done = self._locks.get_nowait()
                except queue.Empty:
                    break
                self._write(partial(self.store.add_lock, event, pending), done)
                pending = []  # committed with the lock (or dropped with it on a store error)
            if pending:
                self._write(partial(self.store.add_samples, pending))
            if stopping:
                return

    def _write(self, commit: Callable[[], LockEvent | None], done: Callable[[LockEvent], None] | None = None) -> None:
        """Run ``commit``, then ``done`` with its result; a store error is recorded and logged instead."""
        try:
            result = commit()
        except (sqlite3.Error, OSError) as exc:
            self.error = f"store {self.store.path}: {exc}"
            log.error("%s", self.error)
            return
        if done is not None and result is not None:
            done(result)
