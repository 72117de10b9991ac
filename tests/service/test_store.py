"""The SQLite store: WAL, durable lock events before the callback, bounded sample log, damage refused."""

from __future__ import annotations

import sqlite3
import threading

import numpy as np
import pytest

from hexapod_model.service import LockEvent, ServiceError, Store
from hexapod_model.service.store.fixture_store import SAMPLE_COLUMNS
from hexapod_model.service.store.writer import StoreWriter


def event(fixture="left", t=1.5, k=0.0):
    return LockEvent(
        fixture,
        t,
        np.array([0.01, -0.02, 0.4 + k]),
        np.array([0.0, 0.0, 0.0, 1.0]),
        np.arange(6) * 1e-3,
        "ok",
        "ab" * 32,
        np.linspace(0, 1, 43),
    )


def sample(t, fixture="left"):
    return (fixture, t, "ok", "[]", "moving", *([0.001] * 6), 0.0, 0.0, 0.4, 0.0, 0.0, 0.0, 1.0)


def test_wal_mode_and_lock_events_round_trip(tmp_path):
    store = Store(tmp_path / "s.sqlite")
    assert store.db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert store.db.execute("PRAGMA synchronous").fetchone()[0] == 2  # FULL
    a = store.add_lock(event(t=1.0))
    store.add_lock(event("right", t=2.0))
    c = store.add_lock(event(t=3.0, k=0.01))
    assert a.id is not None and c.id is not None and c.id > a.id
    last = store.last_lock("left")
    assert last is not None and last.id == c.id and last.t == 3.0 and last.position[2] == 0.4 + 0.01
    assert np.array_equal(last.q, np.linspace(0, 1, 43)) and np.array_equal(last.readings, np.arange(6) * 1e-3)
    assert [e.t for e in store.locks()] == [1.0, 2.0, 3.0] and [e.t for e in store.locks("left", 2.0)] == [3.0]
    assert store.last_lock("nobody") is None
    store.close()
    again = Store(tmp_path / "s.sqlite", create=False)
    assert [e.fixture for e in again.locks()] == ["left", "right", "left"]
    again.close()


def test_sample_log_is_bounded(tmp_path):
    store = Store(tmp_path / "s.sqlite", samples=50)
    store.add_samples([sample(float(t)) for t in range(80)])
    store.add_samples([sample(float(t)) for t in range(80, 120)])
    rows = store.samples()
    assert len(rows) == 50 and [r[1] for r in rows] == [float(t) for t in range(70, 120)]
    assert len(rows[0]) == len(SAMPLE_COLUMNS)
    assert [r[1] for r in store.samples("left", 115.0)] == [115.0 + k for k in range(5)]


def test_writer_calls_back_only_after_the_commit_is_visible_to_another_connection(tmp_path):
    store = Store(tmp_path / "s.sqlite")
    writer = StoreWriter(store, flush_interval=0.05)
    seen, done = [], threading.Event()

    def committed(stored: LockEvent) -> None:
        other = sqlite3.connect(tmp_path / "s.sqlite")  # a reader that is not the writer
        seen.append(other.execute("SELECT t FROM lock_events WHERE id = ?", (stored.id,)).fetchone())
        other.close()
        done.set()

    for t in range(10):
        writer.sample(sample(float(t)))
    writer.lock(event(t=9.5), committed)
    assert done.wait(10)
    writer.stop()
    assert seen == [(9.5,)] and len(store.samples()) == 10  # the pending samples went in with it
    store.close()


def test_a_damaged_or_missing_store_is_refused(tmp_path):
    (tmp_path / "bad.sqlite").write_bytes(b"this is not an SQLite database" * 100)
    with pytest.raises(ServiceError, match="bad.sqlite"):
        Store(tmp_path / "bad.sqlite")
    with pytest.raises(ServiceError, match="does not exist"):
        Store(tmp_path / "none.sqlite", create=False)


def _writer_lock(writer, ev, timeout=10.0):
    stored, done = [], threading.Event()
    writer.lock(ev, lambda e: (stored.append(e), done.set()))
    return stored, done


def test_a_deleted_file_is_written_again_before_a_lock_is_reported_stored(tmp_path):
    path = tmp_path / "s.sqlite"
    store = Store(path)
    writer = StoreWriter(store, flush_interval=0.05)
    stored, done = _writer_lock(writer, event(t=1.0))
    assert done.wait(10)
    for suffix in ("", "-wal", "-shm"):
        (tmp_path / f"s.sqlite{suffix}").unlink(missing_ok=True)
    stored, done = _writer_lock(writer, event(t=2.0))
    assert done.wait(10) and writer.error is None
    again = Store(path, create=False)  # what the next start reads: both locks
    assert [e.t for e in again.locks()] == [1.0, 2.0]
    again.close()
    writer.stop()
    store.close()


def test_disk_full_reports_the_real_error_and_the_lock_is_stored_once_it_clears(tmp_path):
    store = Store(tmp_path / "s.sqlite")
    writer = StoreWriter(store, flush_interval=0.05)
    pages = store.db.execute("PRAGMA page_count").fetchone()[0]
    store.db.execute(f"PRAGMA max_page_count = {pages + 1}")  # a full disk, as SQLite sees it
    from dataclasses import replace

    stored, done = _writer_lock(writer, replace(event(t=5.0), q=np.linspace(0, 1, 20_000)))  # needs new pages
    assert not done.wait(1.0)
    assert writer.error is not None and "full" in writer.error and "rollback" not in writer.error, writer.error
    store.db.execute("PRAGMA max_page_count = 1073741823")  # space again
    assert done.wait(10) and stored[0].t == 5.0
    assert writer.error is None  # the fault cleared: so does the error
    writer.stop()
    store.close()


def test_another_process_holding_the_database_is_an_error_until_it_lets_go(tmp_path):
    store = Store(tmp_path / "s.sqlite", timeout=0.2)
    writer = StoreWriter(store, flush_interval=0.05)
    other = sqlite3.connect(tmp_path / "s.sqlite", isolation_level=None)
    other.execute("BEGIN EXCLUSIVE")
    stored, done = _writer_lock(writer, event(t=7.0))
    assert not done.wait(1.0) and writer.error is not None and "locked" in writer.error
    other.execute("ROLLBACK")
    other.close()
    assert done.wait(10) and writer.error is None
    writer.stop()
    assert [e.t for e in store.locks()] == [7.0]
    store.close()


def test_every_sample_row_a_full_disk_lost_is_counted(tmp_path):
    store = Store(tmp_path / "s.sqlite")
    writer = StoreWriter(store, flush_interval=0.05)
    pages = store.db.execute("PRAGMA page_count").fetchone()[0]
    store.db.execute(f"PRAGMA max_page_count = {pages + 1}")  # a full disk, as SQLite sees it
    from dataclasses import replace

    sent = 0
    stored, done = _writer_lock(writer, replace(event(t=5.0), q=np.linspace(0, 1, 20_000)))  # held back: no room
    for _batch in range(40):  # rows queued while the lock waits: each batch tries the lock with them
        for _ in range(50):
            writer.sample(sample(10.0 + sent * 0.01))
            sent += 1
        threading.Event().wait(0.02)
    assert not done.is_set() and writer.error is not None
    store.db.execute("PRAGMA max_page_count = 1073741823")  # space again
    assert done.wait(10)
    writer.stop()
    assert len(store.samples()) + writer.dropped == sent, (len(store.samples()), writer.dropped, sent)
    store.close()


def test_health_shows_the_sample_rows_lost(tmp_path):
    from types import SimpleNamespace

    from hexapod_model.service.http.health import health

    store = Store(tmp_path / "s.sqlite")
    writer = StoreWriter(store, flush_interval=60.0, max_pending=10)  # no batch before stop()
    for k in range(25):  # the log holds 10: the 15 oldest go
        writer.sample(sample(float(k)))
    view = SimpleNamespace(
        cycles={},
        writer=writer,
        config=SimpleNamespace(store=SimpleNamespace(path=store.path)),
        running=True,
        started=0.0,
        frames=0,
        unknown_frames=0,
        lag=0.0,
        health_sections={},
    )
    lost = health(view)["store"]["lost_samples"]  # type: ignore[arg-type]
    writer.stop()
    store.close()
    assert lost == 15
