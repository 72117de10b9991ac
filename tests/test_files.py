"""Atomic output helpers: all or nothing, the permissions open() would give, figures in memory first."""

from __future__ import annotations

import os
import stat

import pytest
from matplotlib.figure import Figure

from hexapod_model.files import atomic_save_figure, atomic_write_text, atomic_writer


def mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_streamed_file_appears_only_when_complete(tmp_path):
    path = tmp_path / "out.csv"
    with atomic_writer(path) as fh:
        fh.write("a,b\r\n")  # no newline translation: csv writes its own line ends
        assert not path.exists() and len(list(tmp_path.iterdir())) == 1
    assert path.read_bytes() == b"a,b\r\n"
    with open(tmp_path / "plain", "w"):
        pass
    assert mode(path) == mode(tmp_path / "plain")  # not mkstemp's 0o600


def test_failure_or_interrupt_leaves_the_target_as_it_was(tmp_path):
    path = tmp_path / "out.csv"
    path.write_text("old")
    os.chmod(path, 0o640)
    for exc in (RuntimeError("half-way"), KeyboardInterrupt()):
        with pytest.raises(type(exc)), atomic_writer(path) as fh:
            fh.write("new, half")
            raise exc
        assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["out.csv"]
    atomic_write_text(path, "new")
    assert path.read_text() == "new" and mode(path) == 0o640  # an existing file keeps its permissions


def test_figure_is_rendered_before_the_file_is_touched(tmp_path):
    fig = Figure(figsize=(2, 2))
    fig.add_subplot().plot([0, 1], [0, 1])
    path = tmp_path / "f.png"
    atomic_save_figure(fig, path, dpi=50)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(TypeError):
        atomic_save_figure(fig, tmp_path / "g.png", dpi=50, no_such_option=True)  # savefig fails: no file at all
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.png"]
