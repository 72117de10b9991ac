"""The changeover's tables in the fixture store, and the schema migration that added them.

Schema version 2 adds to version 1 (``lock_events``, ``samples``, ``meta``):

* ``targets``: every target set, append-only: ``fixture``, ``recipe`` (NULL: set on its own),
  the pose (``x, y, z`` m, ``qx, qy, qz, qw``; base frame), ``translation_tol`` (m),
  ``rotation_tol`` (rad), ``set_by``, ``set_at`` (s, Unix), and ``cleared_by`` / ``cleared_at``
  once cleared. A fixture's current target is its newest row, unless that row is cleared.
* ``recipes``: every recipe stored (``name``, ``targets`` as the JSON of ``PUT /recipes/NAME``,
  ``set_by``, ``set_at``); a name's newest row is current.
* ``activations``: every activation of a recipe (``recipe``, ``set_by``, ``set_at``): the newest
  is the active recipe. Activating writes the recipe's targets in the same transaction.
* ``lock_events`` gains ``target_id`` and ``recipe``: the target a lock pose met.

Every write is one ``synchronous=FULL`` transaction, committed before the call returns.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, TypeVar

import numpy as np

from ...lie import matrix_to_quaternion, quaternion_to_matrix
from ..errors import ServiceError
from ..targets.target import Recipe, Target, Tolerance

SCHEMA_VERSION = 2
_T = TypeVar("_T")


class Transaction(Protocol):
    """Runs ``work(connection)`` in one committed transaction and returns what it returns."""

    def __call__(self, work: Callable[[sqlite3.Connection], _T]) -> _T: ...  # noqa: D102


_POSE = ("x", "y", "z", "qx", "qy", "qz", "qw")
_TABLES = f"""
CREATE TABLE IF NOT EXISTS targets (
    id INTEGER PRIMARY KEY AUTOINCREMENT, fixture TEXT NOT NULL, recipe TEXT,
    {", ".join(c + " REAL NOT NULL" for c in _POSE)},
    translation_tol REAL NOT NULL, rotation_tol REAL NOT NULL,
    set_by TEXT NOT NULL, set_at REAL NOT NULL, cleared_by TEXT, cleared_at REAL);
CREATE INDEX IF NOT EXISTS targets_fixture ON targets (fixture, id);
CREATE TABLE IF NOT EXISTS recipes (
    id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL, targets TEXT NOT NULL,
    set_by TEXT NOT NULL, set_at REAL NOT NULL);
CREATE TABLE IF NOT EXISTS activations (
    id INTEGER PRIMARY KEY AUTOINCREMENT, recipe TEXT NOT NULL, set_by TEXT NOT NULL, set_at REAL NOT NULL);
"""


def migrate(db: sqlite3.Connection, path: Path) -> None:
    """Bring a store to :data:`SCHEMA_VERSION` in one transaction (version 1 -> 2); refuse a newer one."""
    db.execute("BEGIN IMMEDIATE")
    try:
        row = db.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
        version = SCHEMA_VERSION if row is None else int(row[0])
        if version > SCHEMA_VERSION:
            raise ServiceError(f"store {path}: schema version {version} is newer than this version's {SCHEMA_VERSION}")
        columns = {r[1] for r in db.execute("PRAGMA table_info(lock_events)")}
        for column, kind in (("target_id", "INTEGER"), ("recipe", "TEXT")):
            if column not in columns:  # a version-1 table
                db.execute(f"ALTER TABLE lock_events ADD COLUMN {column} {kind}")
        for statement in _TABLES.split(";"):
            if statement.strip():
                db.execute(statement)
        db.execute("INSERT OR REPLACE INTO meta VALUES ('schema_version', ?)", (str(SCHEMA_VERSION),))
        db.execute("COMMIT")
    except BaseException:
        db.execute("ROLLBACK")
        raise


@dataclass(frozen=True)
class StoredTarget:
    """A target row as stored (no inverse kinematics yet): see :class:`~hexapod_model.service.targets.target.Target`."""

    id: int
    fixture: str
    pose: np.ndarray
    tolerance: Tolerance
    set_by: str
    set_at: float
    recipe: str | None


class TargetStore:
    """Targets, recipes and activations in an open store.

    Writes go through the store's transactions (committed durably to the file at its path, see
    :class:`~hexapod_model.service.store.fixture_store.Store`); reads hold its lock.

    Args:
        transaction: runs ``work(connection)`` in one committed transaction and returns its result
            (:meth:`Store.transaction <hexapod_model.service.store.fixture_store.Store.transaction>`).
        read: the rows of a query ``(sql, args)`` under the store's lock
            (:meth:`Store.read <hexapod_model.service.store.fixture_store.Store.read>`).
    """

    def __init__(self, transaction: Transaction, read: Callable[[str, tuple], list[tuple]]):
        self._transaction, self._read_rows = transaction, read

    def _write(self, statements: Iterable[tuple[str, tuple]]) -> list[int]:
        """Run ``statements`` in one committed transaction; returns each one's ``lastrowid``."""

        def work(db: sqlite3.Connection) -> list[int]:
            return [db.execute(sql, args).lastrowid or 0 for sql, args in statements]

        return self._transaction(work)

    def _read(self, sql: str, args: tuple = ()) -> list[tuple]:
        return self._read_rows(sql, args)

    @staticmethod
    def _target_row(t: Target) -> tuple[str, tuple]:
        values = (*t.pose[:3, 3], *matrix_to_quaternion(t.pose[:3, :3]), t.tolerance.translation, t.tolerance.rotation)
        sql = (
            f"INSERT INTO targets (fixture, recipe, {', '.join(_POSE)}, translation_tol, rotation_tol, set_by, set_at) "
            f"VALUES ({', '.join('?' * 13)})"
        )
        return sql, (t.fixture, t.recipe, *map(float, values), t.set_by, float(t.set_at))

    def add_target(self, target: Target) -> int:
        """Store ``target`` as its fixture's current one; returns its row id."""
        return self._write([self._target_row(target)])[0]

    def clear_target(self, fixture: str, by: str, at: float) -> bool:
        """Clear the fixture's current target; False when it had none."""
        sql = (
            "UPDATE targets SET cleared_by = ?, cleared_at = ? WHERE id = "
            "(SELECT MAX(id) FROM targets WHERE fixture = ?) AND cleared_at IS NULL"
        )
        return self._transaction(lambda db: db.execute(sql, (by, float(at), fixture)).rowcount) > 0

    def current_targets(self) -> dict[str, StoredTarget]:
        """Each fixture's current target (its newest row, when not cleared)."""
        sql = (
            f"SELECT id, fixture, {', '.join(_POSE)}, translation_tol, rotation_tol, set_by, set_at, recipe "
            "FROM targets WHERE id IN (SELECT MAX(id) FROM targets GROUP BY fixture) AND cleared_at IS NULL"
        )
        rows = self._read(sql)
        out = {}
        for r in rows:
            T = np.eye(4)
            T[:3, 3], T[:3, :3] = r[2:5], quaternion_to_matrix(np.array(r[5:9]))
            out[r[1]] = StoredTarget(r[0], r[1], T, Tolerance(r[9], r[10]), r[11], r[12], r[13])
        return out

    def put_recipe(self, recipe: Recipe) -> None:
        """Store (or replace) a recipe."""
        body = json.dumps({"targets": {k: t.to_json(brief=True) for k, t in recipe.targets.items()}}, allow_nan=False)
        sql = "INSERT INTO recipes (name, targets, set_by, set_at) VALUES (?, ?, ?, ?)"
        self._write([(sql, (recipe.name, body, recipe.set_by, float(recipe.set_at)))])

    def recipes(self) -> dict[str, tuple[dict, str, float]]:
        """Current recipes by name: ``(body, set_by, set_at)``, ``body`` as stored (``{"targets": ...}``)."""
        newest = "SELECT MAX(id) FROM recipes GROUP BY name"
        sql = f"SELECT name, targets, set_by, set_at FROM recipes WHERE id IN ({newest}) ORDER BY name"
        rows = self._read(sql)
        return {r[0]: (json.loads(r[1]), r[2], r[3]) for r in rows}

    def activate(self, recipe: Recipe, by: str, at: float) -> list[int]:
        """Make ``recipe`` the active one and its targets current, in one transaction; returns their row ids."""
        rows = [self._target_row(t) for t in recipe.targets.values()]
        sql = "INSERT INTO activations (recipe, set_by, set_at) VALUES (?, ?, ?)"
        return self._write([*rows, (sql, (recipe.name, by, float(at)))])[:-1]

    def active(self) -> tuple[str, str, float] | None:
        """The active recipe ``(name, set_by, set_at)``, or None."""
        rows = self._read("SELECT recipe, set_by, set_at FROM activations ORDER BY id DESC LIMIT 1")
        return None if not rows else (rows[0][0], rows[0][1], rows[0][2])
