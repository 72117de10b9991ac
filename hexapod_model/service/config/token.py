"""The HTTP bearer token: read from ``[http] token_file`` (mode checked) and compared in constant time.

The file holds one line, the token (at least :data:`MIN_LENGTH` characters; a UTF-8 byte-order
mark and surrounding whitespace are stripped); it must not be
readable or writable by group or others (``chmod 600``). Make one with::

    python -c "import secrets; print(secrets.token_urlsafe(32))" > fixture.token && chmod 600 fixture.token
"""

from __future__ import annotations

import hmac
import stat
from pathlib import Path

from ..errors import ConfigError

MIN_LENGTH = 16  # characters


def read_token(path: Path, field: str = "http.token_file", source: str = "<dict>") -> str:
    """The token held by ``path``; :class:`ConfigError` when unreadable, too short or open to others."""
    try:
        mode = path.stat().st_mode
        if not stat.S_ISREG(mode):  # before reading: a FIFO would wait for a writer
            raise ConfigError(field, str(path), "not a regular file", source)
        text = path.read_text(encoding="utf-8-sig")  # a leading BOM is dropped
    except OSError as exc:
        raise ConfigError(field, str(path), f"cannot read the token file: {exc.strerror or exc}", source) from None
    except UnicodeDecodeError:
        raise ConfigError(field, str(path), "the token file is not UTF-8 text", source) from None
    if mode & 0o077:
        raise ConfigError(
            field, str(path), f"mode {stat.S_IMODE(mode):04o} lets others read or change it: chmod 600 {path}", source
        )
    lines = text.strip().splitlines()
    token = lines[0].strip() if len(lines) == 1 else ""
    if len(token) < MIN_LENGTH or any(c.isspace() for c in token):
        raise ConfigError(
            field, str(path), f"expected one line of at least {MIN_LENGTH} characters without spaces", source
        )
    return token


def bearer_matches(header: str | None, token: str) -> bool:
    """Whether an ``Authorization`` header value is ``Bearer <token>`` (constant-time comparison)."""
    if not header:
        return False
    scheme, _, value = header.partition(" ")
    if scheme.lower() != "bearer":
        return False
    return hmac.compare_digest(value.strip().encode("utf-8"), token.encode("utf-8"))
