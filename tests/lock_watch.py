"""A thread that counts only while it holds the interpreter lock: whether code lets another thread in.

NumPy's ``ndarray.dot`` (BLAS) and its loops over 500 elements or more release the interpreter
lock; with another thread of the process waiting for it, each release wakes that thread, and a
1 kHz step costs a fifth to a half more (docs/service.md). While a :class:`LockWatch` is open the
interpreter hands the lock over only after :data:`SWITCH` seconds, so the watcher's count moves
during the watched code only if that code released the lock (and the watcher took it first: a
test runs enough iterations for one release in each to show).
"""

from __future__ import annotations

import sys
import threading

SWITCH = 2.0  # s: the interpreter takes the lock from a thread only after this long (while watching)


class LockWatch:
    """Context manager: a spinning thread and the count of its spins since :meth:`__enter__` (:attr:`ran`)."""

    def __init__(self) -> None:
        self._spins = 0
        self._start = 0
        self._ready = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._old = sys.getswitchinterval()

    def _spin(self) -> None:
        self._ready.set()
        while not self._stop.is_set():
            self._spins += 1

    def __enter__(self) -> LockWatch:
        sys.setswitchinterval(SWITCH)
        self._thread.start()
        self._ready.wait()  # the spinner held the lock; from here this thread holds it, the spinner waits
        self._start = self._spins
        return self

    @property
    def ran(self) -> int:
        """Spins since the watch began: 0 when the watched code never let the lock go (read it inside the watch)."""
        return self._spins - self._start

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        sys.setswitchinterval(self._old)
        self._thread.join()
