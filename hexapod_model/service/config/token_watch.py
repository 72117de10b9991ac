"""The token file, watched: a rotated token is in force at the next request, a lost one refuses.

:class:`TokenWatch` holds the token read at start-up and looks at the file again (``stat``:
inode, size, modification and change times) each time a request needs the token. When it
changed (rewritten in place, replaced by a rename, its mode changed) the file is read again with
:func:`~hexapod_model.service.config.token.read_token`'s checks:

* a good token is in force at once (the old one refused), and a log line says the file changed;
* a file deleted, unreadable, open to others or holding no valid token leaves **no** token in
  force: requests that need one are refused (``503``, the reason in one line) until the file
  is fixed, and an error line is logged once. The old token is never kept silently.

A file changed within the last second is read again at each look (file times are coarse: two
writes within one tick of the clock look alike). The token itself never appears in a log line.
"""

from __future__ import annotations

import logging
import os
import threading
import time
from pathlib import Path

from ..errors import ConfigError
from .token import read_token

log = logging.getLogger(__name__)
RECENT = 1.0  # s: a file modified this recently is read again at every look


class TokenWatch:
    """The token in force, from ``path``, re-read when the file changes.

    Args:
        path: the token file (``[http] token_file``), or None: no token is configured.
        token: the token read at start-up (None with no ``path``).
    """

    def __init__(self, path: Path | None, token: str | None):
        self.path, self._token = path, token
        self._problem: str | None = None
        self._lock = threading.Lock()
        self._seen = self._identity() if path is not None else None

    @property
    def configured(self) -> bool:
        """Whether a token file is configured (without one, writes are refused with ``403``)."""
        return self.path is not None

    def current(self) -> tuple[str | None, str | None]:
        """``(token, problem)``: the token in force, or None with why none is (a one-line reason)."""
        if self.path is None:
            return None, None
        with self._lock:
            now = self._identity()
            if now != self._seen or (now is not None and time.time() - now[3] / 1e9 < RECENT):
                self._reload(now)
            return self._token, self._problem

    def _identity(self) -> tuple[int, int, int, int, int, int] | None:
        assert self.path is not None
        try:
            s = os.stat(self.path)
        except OSError:
            return None
        return (s.st_dev, s.st_ino, s.st_size, s.st_mtime_ns, s.st_ctime_ns, s.st_mode)

    def _reload(self, now: tuple | None) -> None:
        assert self.path is not None
        self._seen = now
        old, had_problem = self._token, self._problem
        try:
            token = read_token(self.path)
        except ConfigError as exc:
            self._token, self._problem = (
                None,
                f"token file {self.path}: {exc.reason}; requests needing the token are refused",
            )
            if self._problem != had_problem:
                log.error("%s", self._problem)
            return
        self._token, self._problem = token, None
        if token != old or had_problem is not None:
            log.warning("token file %s changed: the token it holds now is in force", self.path)
