"""One service per store: a second service on the same store file is refused, naming the first."""

from __future__ import annotations

import os

import pytest

from hexapod_model.cli.main import main
from hexapod_model.service import FixtureService, ServiceError, load_config

from ..cli.test_service_cli import write_config
from ..conftest import hexapod


def test_a_second_service_on_the_store_is_refused_naming_the_first_and_may_start_once_it_stops(tmp_path):
    config = load_config(write_config(tmp_path))
    hexapods = {"left": hexapod("reference")}
    with FixtureService(config, hexapods=hexapods):
        second = FixtureService(config, hexapods=hexapods)
        with pytest.raises(ServiceError) as exc:
            second.start()
        text = str(exc.value)
        assert len(text.splitlines()) == 1 and f"pid {os.getpid()}" in text and "store.sqlite" in text, text
        assert not second.running and second.endpoint is None
    with FixtureService(config, hexapods=hexapods) as again:  # the lock went with the first service
        assert again.running


def test_hexapod_serve_on_a_store_in_use_is_one_line_exit_2(tmp_path, capsys):
    cfg = write_config(tmp_path)
    with FixtureService(load_config(cfg), hexapods={"left": hexapod("reference")}):
        rows = _rows(tmp_path / "store.sqlite")
        assert main(["serve", str(cfg), "--duration", "0.1"]) == 2
        assert _rows(tmp_path / "store.sqlite") == rows  # the second wrote nothing
    err = [line for line in capsys.readouterr().err.strip().splitlines() if " INFO " not in line]
    assert len(err) == 1 and "in use by" in err[0] and f"pid {os.getpid()}" in err[0], err


def _rows(path) -> int:
    import sqlite3

    with sqlite3.connect(path) as db:
        return sum(db.execute(f"SELECT COUNT(*) FROM {t}").fetchone()[0] for t in ("lock_events", "samples"))
