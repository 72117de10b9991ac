"""Atomic file output: a temporary file in the target folder, then a rename.

A failure (an exception, Ctrl-C, a crash) leaves the target as it was: never half written.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

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


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns the path."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder + rename)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent if str(path.parent) else ".")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
