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
* ``targets``, ``recipes``, ``activations``: the changeover's (:mod:`~hexapod_model.service.store.target_tables`,
  which also migrates a version-1 file when it is opened).

``synchronous=FULL``: a commit is on disk (the WAL file fsync'ed) when :meth:`Store.add_lock`
returns, so a lock published as stored survives a crash or a power loss. Writes happen on one
writer thread (:class:`~hexapod_model.service.store.writer.StoreWriter`), off the cycle's path.
"""

from __future__ import annotations

import json
import logging
import os
import sqlite3
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from operator import itemgetter
from pathlib import Path
from typing import TypeVar

import numpy as np

from ..errors import ServiceError
from ..record.pose_record import PoseRecord
from .target_tables import TargetStore, migrate

T = TypeVar("T")

log = logging.getLogger(__name__)
LEGS = ", ".join(f"l{i}" for i in range(1, 7))
POSE = "x, y, z, qx, qy, qz, qw"
_LOCK_TAIL = "status, geometry_hash, q, target_id, recipe"
SAMPLE_COLUMNS = ("fixture", "t", "status", "flags", "state", *LEGS.split(", "), *POSE.split(", "))
_pose_columns = itemgetter(*POSE.split(", "))
_NO_POSE = (None,) * 7


def sample_row(rec: PoseRecord) -> tuple:
    """A record as a row of the ``samples`` table (:data:`SAMPLE_COLUMNS` order)."""
    pose, flags = rec.pose, rec.flags
    return (
        rec.fixture,
        rec.t,
        rec.status,
        json.dumps(flags) if flags else "[]",  # json.dumps([]): most records carry no flag
        rec.state,
        *rec.readings,
        *(_NO_POSE if pose is None else _pose_columns(pose)),
    )


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
        geometry_hash: :func:`hexapod_model.service.config.settings.geometry_hash` of the hexapod used.
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

    def __init__(self, path: str | Path, samples: int = 100_000, create: bool = True, timeout: float = 10.0):
        self.path, self.max_samples, self.timeout = Path(path), samples, timeout
        if not create and not self.path.is_file():
            raise ServiceError(f"store {self.path} does not exist (the service creates it on its first start)")
        try:
            self.db = self._connect()
            check = self.db.execute("PRAGMA quick_check").fetchone()[0]
            if check != "ok":
                raise ServiceError(f"store {self.path} is damaged: {check}")
            self.db.executescript(_SCHEMA)
            migrate(self.db, self.path)
        except sqlite3.Error as exc:
            raise ServiceError(f"store {self.path}: {exc}") from None
        self._file = _identity(self.path)
        self._lock = threading.Lock()
        #: the changeover's targets, recipes and activations
        self.targets = TargetStore(self.transaction, self.read)

    def _connect(self) -> sqlite3.Connection:
        db = sqlite3.connect(self.path, check_same_thread=False, isolation_level=None, timeout=self.timeout)
        mode = db.execute("PRAGMA journal_mode=WAL").fetchone()[0]
        db.execute("PRAGMA synchronous=FULL")
        if mode.lower() != "wal":
            db.close()
            raise ServiceError(f"store {self.path}: SQLite refused WAL mode (journal_mode={mode})")
        return db

    def _same_file(self) -> None:
        """Make sure the open database is the file at :attr:`path` (the one the next start reads).

        A file deleted while the service runs is written again from the open database (SQLite's
        backup), so nothing stored is lost; a file replaced by another is an error (not written).
        """
        now = _identity(self.path)
        if now == self._file:
            return
        if now is not None:
            raise sqlite3.OperationalError(f"{self.path} was replaced by another file while the service ran")
        log.error(
            "store %s: the file was deleted while the service ran: written again from the open database", self.path
        )
        fresh = self._connect()
        try:
            self.db.backup(fresh)
        except BaseException:
            fresh.close()
            raise
        self.db.close()
        self.db, self._file = fresh, _identity(self.path)

    def transaction(self, work: Callable[[sqlite3.Connection], T]) -> T:
        """Run ``work(connection)`` in one immediate transaction, committed durably to the file at :attr:`path`.

        A failed statement's own error is raised (SQLite may have rolled back already: the
        rollback's error never hides it).
        """
        with self._lock:
            self._same_file()
            self.db.execute("BEGIN IMMEDIATE")
            try:
                result = work(self.db)
                self.db.execute("COMMIT")
            except BaseException:
                if self.db.in_transaction:
                    try:
                        self.db.execute("ROLLBACK")
                    except sqlite3.Error:
                        pass
                raise
            self._same_file()  # deleted between the check and the commit: the backup holds the commit
        return result

    def read(self, sql: str, args: tuple = ()) -> list[tuple]:
        """The rows of one query (``sql`` with ``args``), under the store's lock."""
        with self._lock:
            return self.db.execute(sql, args).fetchall()

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
        sql = f"INSERT INTO lock_events (fixture, t, {POSE}, {LEGS}, {_LOCK_TAIL}) VALUES "
        sql += f"({', '.join('?' * len(row))})"

        def work(_: sqlite3.Connection) -> int | None:
            row_id = self.db.execute(sql, row).lastrowid
            self._insert_samples(samples)
            return row_id

        return replace(event, id=self.transaction(work))

    def add_samples(self, samples: Sequence[tuple]) -> None:
        """Append sample rows (``SAMPLE_COLUMNS`` order) and drop the oldest beyond the bound."""
        self.transaction(lambda _: self._insert_samples(samples))

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


def _identity(path: Path) -> tuple[int, int] | None:
    """``(device, inode)`` of the file at ``path`` (None when there is none)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return None
    return st.st_dev, st.st_ino


def _since(since: float | None) -> float:
    return -1e300 if since is None else float(since)
