"""The service's threads, named for the operating system: ``/proc/PID/task/*/comm`` reads ``hx-cycle``, ...

Python's thread names live in the interpreter only; ``top -H``, ``ps -L`` and the per-thread
CPU clocks under ``/proc`` show the process's name for every thread. A :class:`NamedThread`
sets its Linux name (``prctl(PR_SET_NAME)``, at most 15 bytes) as it starts, so that the CPU
of a ``hexapod serve --simulate`` process splits, from outside, into the service's threads
(``hx-cycle``, ``hx-store``, ``hx-http``, ``hx-start``) and the simulator's (``hx-sim``).
Elsewhere than Linux the name stays Python's only.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import sys
import threading
from collections.abc import Callable
from functools import cache

#: ``prctl`` option that names the calling thread (linux/prctl.h)
PR_SET_NAME = 15
#: the longest name the kernel keeps (bytes, without the terminating zero)
OS_NAME_BYTES = 15


@cache
def _prctl() -> Callable[..., int] | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
    except OSError:
        return None
    return libc.prctl


def set_os_thread_name(name: str) -> bool:
    """Name the calling thread for the operating system (Linux; elsewhere nothing happens).

    Args:
        name: the name, ASCII; cut to its first 15 bytes (the kernel's limit).

    Returns:
        Whether the name was set.
    """
    prctl = _prctl()
    if prctl is None:
        return False
    return prctl(PR_SET_NAME, ctypes.c_char_p(name.encode("ascii", "replace")[:OS_NAME_BYTES]), 0, 0, 0) == 0


class NamedThread(threading.Thread):
    """A :class:`threading.Thread` that gives itself its Python name at the OS level as it starts.

    Args:
        target: what the thread runs.
        name: its name (``hx-...``; at most 15 bytes reach the OS).
        args: positional arguments of ``target``.
        daemon: whether the interpreter may exit while it runs.
    """

    def __init__(self, target: Callable[..., object], name: str, args: tuple = (), daemon: bool = True):
        super().__init__(target=target, name=name, args=args, daemon=daemon)

    def run(self) -> None:
        """Set the OS name, then run the target."""
        set_os_thread_name(self.name)
        super().run()
