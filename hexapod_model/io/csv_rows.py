"""Rows of a CSV file, read with the ``csv`` module in constant memory, with per-row errors.

Line rules (:class:`TableReader`):

* UTF-8 text; a leading byte-order mark (spreadsheets write one) is skipped. Any other
  encoding is an :class:`InputError` naming the line.
* Line 1 is the header; names are stripped of spaces and must be unique.
* Blank lines are skipped but counted: messages give the file's own line numbers.
* Every other line is one row (``csv`` module quoting). A row with more or fewer cells than
  the header is invalid (``line 7: 7 cells, the header has 6``); it is never re-flowed.
* Only the columns a command uses are read; each such cell must be a finite number (Python
  float syntax), and no larger in size than the limit given for its column.
"""

from __future__ import annotations

import csv
import io
import math
import sys
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from ..exceptions import InputError

MAX_LINE_BYTES = 1 << 20  # a longer line is refused (reading stays in constant memory)
CHUNK_ROWS = 1024  # rows per block of TableReader.chunks


@dataclass(frozen=True)
class Rows:
    """A block of data rows.

    Attributes:
        lines: (n,) the file line on which each row starts.
        values: (n, k) the requested columns; NaN in a cell that is not a valid number.
        errors: (n,) ``""`` for a good row, else the one-line reason (``"7 cells, the header has 6"``).
        malformed: (n,) True where the cell count differs from the header's.
    """

    lines: np.ndarray
    values: np.ndarray
    errors: list[str]
    malformed: np.ndarray

    def __len__(self) -> int:
        return len(self.lines)


class TableReader:
    """A CSV table read row by row (constant memory), with the header checked up front.

    Args:
        source: a path, or an open binary or text stream (``sys.stdin``); a stream is not closed.
        required: columns that must be in the header.
        name: how messages call the source (default: the path or the stream's ``name``).
        limits: largest ``|value|`` accepted per column name (default: any finite number).

    Raises:
        InputError: unreadable or empty file, bad header, missing columns.
    """

    def __init__(
        self,
        source: str | Path | IO[Any],
        required: Sequence[str] = (),
        name: str | None = None,
        limits: Mapping[str, float] | None = None,
    ):
        self.limits = dict(limits or {})
        self._own = isinstance(source, (str, Path))
        if isinstance(source, (str, Path)):
            self.name = name or str(source)
            try:
                self._fh: IO[Any] = _old_mac_lines(open(source, "rb"))  # noqa: SIM115 - closed by close()
            except OSError as exc:
                raise InputError("CSV file", str(source), exc.strerror or "cannot read") from None
        else:
            self.name = name or str(getattr(source, "name", "<stream>"))
            self._fh = source
        self._reader = csv.reader(self._lines())
        try:
            try:
                first = next(self._reader, None)
            except csv.Error as exc:
                raise InputError("CSV file", self.name, f"line 1: {_csv_error(exc)}") from None
            if first is None or not "".join(first).strip():
                raise InputError("CSV file", self.name, "line 1: expected a header line of column names")
            self.header = [c.strip() for c in first]
            dup = sorted({c for c in self.header if self.header.count(c) > 1})
            if dup:
                raise InputError("CSV header", self.header, f"{self.name}: column {dup[0]!r} appears twice")
            missing = [c for c in required if c not in self.header]
            if missing:
                raise InputError("CSV header", self.header, f"{self.name}: missing columns {missing}")
        except BaseException:
            self.close()
            raise

    def _lines(self) -> Iterator[str]:
        """The file's lines as text, checking UTF-8 and the length limit line by line."""
        number = 0
        while True:
            number += 1
            try:
                raw = self._fh.readline(MAX_LINE_BYTES + 1)
            except UnicodeDecodeError:  # a text stream whose decoder failed
                raise InputError("CSV file", self.name, f"line {number}: not UTF-8 text") from None
            if not raw:
                return
            if len(raw) > MAX_LINE_BYTES:
                raise InputError("CSV file", self.name, f"line {number} is longer than {MAX_LINE_BYTES} bytes")
            if isinstance(raw, bytes):
                try:
                    raw = raw.decode("utf-8")
                except UnicodeDecodeError as exc:
                    raise InputError(
                        "CSV file",
                        self.name,
                        f"line {number}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at column {exc.start + 1}); "
                        "save the file as UTF-8",
                    ) from None
            yield raw[1:] if number == 1 and raw.startswith("\ufeff") else raw

    def chunks(self, columns: Sequence[str], size: int = CHUNK_ROWS) -> Iterator[Rows]:
        """The data rows in blocks of ``size``, with the values of ``columns`` (header names)."""
        cols = [self.header.index(c) for c in columns]
        limits = [min(self.limits.get(c, math.inf), sys.float_info.max) for c in columns]  # finite: inf fails
        ncell = len(self.header)
        lines: list[int] = []
        values: list[list[float]] = []
        errors: list[str] = []
        malformed: list[bool] = []
        end = self._reader.line_num
        while True:
            try:
                cells = next(self._reader, None)
            except csv.Error as exc:
                raise InputError("CSV file", self.name, f"line {self._reader.line_num}: {_csv_error(exc)}") from None
            start, end = end + 1, self._reader.line_num
            if cells is None:
                break
            if not cells or (len(cells) == 1 and not cells[0].strip()):
                continue  # a blank line
            lines.append(start)
            malformed.append(len(cells) != ncell)
            if len(cells) != ncell:
                values.append([math.nan] * len(cols))
                errors.append(f"{len(cells)} cells, the header has {ncell}")
            else:
                row, error = _parse(cells, cols, columns, limits)
                values.append(row)
                errors.append(error)
            if len(lines) == size:
                yield _rows(lines, values, errors, malformed, len(cols))
                lines, values, errors, malformed = [], [], [], []
        if lines:
            yield _rows(lines, values, errors, malformed, len(cols))

    def read(self, columns: Sequence[str]) -> Rows:
        """All remaining rows at once (for files that fit in memory)."""
        parts = list(self.chunks(columns))
        if not parts:
            return _rows([], [], [], [], len(columns))
        return Rows(
            np.concatenate([p.lines for p in parts]),
            np.concatenate([p.values for p in parts]),
            [e for p in parts for e in p.errors],
            np.concatenate([p.malformed for p in parts]),
        )

    def close(self) -> None:
        """Close the file if this reader opened it."""
        if self._own:
            self._fh.close()

    def __enter__(self) -> TableReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _rows(lines: list, values: list, errors: list[str], malformed: list, k: int) -> Rows:
    return Rows(
        np.array(lines, dtype=np.int64),
        np.array(values, dtype=float).reshape(-1, k),
        errors,
        np.array(malformed, dtype=bool),
    )


def _parse(cells: list[str], cols: list[int], names: Sequence[str], limits: list[float]) -> tuple[list[float], str]:
    """Values of one row's used cells (NaN where invalid) and the first problem found (``""``: none)."""
    try:  # fast path: every cell a plain number within its limit (NaN and inf fail the comparison)
        row = [float(cells[c]) for c in cols]
        if all(-lim <= v <= lim for v, lim in zip(row, limits)) and not any("_" in cells[c] for c in cols):
            return row, ""
    except ValueError:
        pass
    row, error = [], ""
    for c, name, limit in zip(cols, names, limits):
        text = cells[c].strip()
        try:
            if "_" in text:  # float() reads "1_5" as 15: not how a CSV writes numbers
                raise ValueError(text)
            v = float(text)
            problem = (
                f"{name} = {text[:40]!r} is not a finite number"
                if not math.isfinite(v)
                else (f"{name} = {text[:40]!r} exceeds {limit:g} in magnitude" if abs(v) > limit else "")
            )
        except ValueError:
            problem = f"{name} is empty" if not text else f"{name} = {text[:40]!r} is not a number"
        if problem:
            v = math.nan
            error = error or problem
        row.append(v)
    return row, error


def _old_mac_lines(fh: io.BufferedReader) -> IO[Any]:
    """``fh`` itself, or a text stream of it that reads CR as a line end when its first block has CR and no LF."""
    head = fh.peek(1 << 16)
    if b"\r" in head and b"\n" not in head:  # lines ended by CR only (classic Mac OS, some loggers)
        return io.TextIOWrapper(fh, encoding="utf-8", newline=None)
    return fh


def _csv_error(exc: csv.Error) -> str:
    """The csv module's complaint in the user's words."""
    if "new-line character" in str(exc):
        return "a line ends in CR (carriage return) alone inside the text; save the file with LF or CRLF line ends"
    return str(exc)
