"""Atomic file output: a temporary file in the target folder, then a rename.

A failure (an exception, Ctrl-C, a crash) leaves the target as it was: never half written.
:func:`atomic_writer` streams (constant memory: rows go to the temporary file as they are
made); :func:`atomic_write_text`, :func:`atomic_write_bytes` and :func:`atomic_save_figure`
write what is already in memory.
"""

from __future__ import annotations

import io
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from .exceptions import InputError


def check_output_path(path: str | Path, *inputs: str | Path | None) -> Path:
    """``path`` as a :class:`Path` if a file can be written there, or :class:`InputError`.

    Refuses a missing folder, a folder as the target, and a target equal to one of ``inputs``
    (an input is never overwritten); call it before any work is done.
    """
    out = Path(path)
    parent = out.parent if str(out.parent) else Path(".")
    if out.is_dir():
        raise InputError("output", str(out), "is a folder; name a file")
    if not parent.is_dir():
        raise InputError("output", str(out), f"folder {str(parent)!r} does not exist")
    for inp in inputs:
        if inp is not None and str(inp) != "-" and Path(inp).exists() and out.exists() and os.path.samefile(out, inp):
            raise InputError("output", str(out), "is also an input; choose another output file")
    return out


def _new_file_mode() -> int:
    """Permissions of a newly created file under the current umask (``mkstemp`` uses 0o600)."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


@contextmanager
def atomic_writer(path: str | Path, binary: bool = False) -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path`` for writing; rename it onto ``path`` on success.

    Text mode writes UTF-8 with no newline translation (what the ``csv`` module needs). If the
    block raises (or is interrupted), the temporary file is removed and ``path`` is untouched.

    Example::

        with atomic_writer("poses.csv") as fh:
            for row in rows:
                fh.write(row)
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        mode = path.stat().st_mode & 0o777 if path.exists() else _new_file_mode()
        os.fchmod(fd, mode)
        fh = os.fdopen(fd, "wb") if binary else os.fdopen(fd, "w", encoding="utf-8", newline="")
        with fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns the path."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_csv(path: str | Path, header: list[str], rows: list[dict[str, Any]]) -> Path:
    """Write ``rows`` (dicts) under ``header`` as CSV, atomically: floats as ``repr``, missing keys empty."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow([repr(float(v)) if isinstance(v, float) else v for v in (r.get(h, "") for h in header)])
    return atomic_write_text(path, buf.getvalue())


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder + rename)."""
    with atomic_writer(path, binary=True) as fh:
        fh.write(data)
    return Path(path)


def atomic_save_figure(fig: Any, path: str | Path, **savefig_kwargs: Any) -> Path:
    """Save a matplotlib ``Figure`` to ``path`` atomically (rendered in memory first).

    The format follows the file suffix (``.png`` when there is none).
    """
    path = Path(path)
    buf = io.BytesIO()
    fig.savefig(buf, format=path.suffix[1:].lower() or "png", **savefig_kwargs)
    return atomic_write_bytes(path, buf.getvalue())


@contextmanager
def output_folder(path: str | Path, option: str = "--out") -> Iterator[Path]:
    """Create the output folder ``path`` (and missing parents) for the block that fills it.

    If the block raises (or is interrupted), the folders created here are removed again when
    they are still empty: a stopped command leaves no empty folder behind, and never removes a
    file or a folder that was there before. A folder that cannot be created is an
    :class:`InputError` naming ``option``.
    """
    path = Path(path)
    created = [p for p in (path, *path.parents) if not p.exists()]
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(option, str(path), f"cannot create the folder: {exc.strerror}") from None
    try:
        yield path
    except BaseException:
        for folder in created:  # deepest first
            try:
                folder.rmdir()  # only an empty folder
            except OSError:
                break
        raise
