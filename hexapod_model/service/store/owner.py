"""One service per store: an exclusive lock on the store, held while a service runs.

Two services writing one SQLite file would interleave their lock rows and sample logs, and
both would read the bus. :class:`StoreOwner` takes an exclusive, non-blocking ``flock`` on a
file beside the store (``<store>.owner``, e.g. ``fixture.sqlite.owner``) and writes there who
holds it (process id, host, start time, later the HTTP address). A second service on the same
store is refused with one line naming that process. The operating system releases the lock when
the process ends, however it ends (``kill -9`` too): a stale ``.owner`` file never blocks a
restart. Readers of the store (``hexapod fixture status``) take no lock.

POSIX only (``fcntl``); where it is missing, no lock is taken and nothing is refused.
"""

from __future__ import annotations

import os
import socket
import time
from pathlib import Path

from ..errors import ServiceError

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]


def owner_path(store: Path) -> Path:
    """The lock file of the store ``store``: the same name with ``.owner`` appended."""
    return store.with_name(store.name + ".owner")


class StoreOwner:
    """The exclusive lock on a store, for as long as a service runs.

    Args:
        store: the store's SQLite file (its folder must exist or be creatable).

    Raises:
        ServiceError: another process holds the lock (named, with what it wrote), or the lock
            file cannot be opened.
    """

    def __init__(self, store: Path):
        self.store, self.path = Path(store), owner_path(Path(store))
        self._fd: int | None = None
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise ServiceError(f"store {self.store}: cannot open its lock file {self.path}: {exc.strerror}") from None
        if fcntl is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                holder = _read(fd) or "another process"
                os.close(fd)
                raise ServiceError(
                    f"store {self.store} is in use by {holder}: one service per store "
                    f"(stop it, or give this one another [store] path)"
                ) from None
        self._fd = fd
        self._started = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        self.describe()

    def describe(self, address: str | None = None) -> None:
        """Write who holds the lock (and ``address``, the HTTP URL, once known) into the lock file."""
        if self._fd is None:
            return
        text = f"the fixture service pid {os.getpid()} on {socket.gethostname()} since {self._started}"
        if address:
            text += f" at {address}"
        data = (text + "\n").encode("utf-8")
        os.ftruncate(self._fd, 0)
        os.pwrite(self._fd, data, 0)

    @property
    def held(self) -> bool:
        """Whether this object still holds the lock."""
        return self._fd is not None

    def release(self) -> None:
        """Release the lock (the file stays; its text is cleared). Safe to call twice."""
        fd, self._fd = self._fd, None
        if fd is None:
            return
        try:
            os.ftruncate(fd, 0)
        except OSError:
            pass
        os.close(fd)  # closing the descriptor releases the flock


def _read(fd: int) -> str:
    """The holder's line of the lock file (empty when it wrote none yet)."""
    try:
        return os.pread(fd, 512, 0).decode("utf-8", "replace").strip().splitlines()[0]
    except (OSError, IndexError):
        return ""
