"""One log line before a compiled entry compiles: the first solve after installation waits for it.

numba compiles an entry of the compiled path (:mod:`.iteration`, :mod:`.batch_kernels`,
:mod:`.follow`) on its first call and keeps the machine code in its cache (``__pycache__`` or
``NUMBA_CACHE_DIR``); later processes load it in well under a second. :func:`announce` logs, at
INFO on the ``hexapod_model.compile`` logger, ``compiling the solver kernels (WHAT), once after
installation: ~N s`` before a call that will compile (no signature in this process, no cache
index on disk); the command line shows it on a terminal. The first of a process is also a
:class:`~hexapod_model.exceptions.CompileWarning`, which Python shows on stderr in a plain
script where no logging is configured (the command line shows its own line instead).

While numba compiles, :func:`collect_less` has Python's cyclic garbage collector run less often:
the compiler allocates millions of short-lived objects, and the collections they trigger took
about 15 % of the first solve's compilation (``benchmarks/startup.py --cold``).
"""

from __future__ import annotations

import gc
import inspect
import logging
import os
import warnings
from types import FrameType
from typing import Any

from ...exceptions import CompileWarning

LOGGER = "hexapod_model.compile"
#: each entry: what it compiles, and the CPU seconds it took from an empty cache on a 2-core machine
#: (benchmarks/startup.py --cold: the inverse's after the forward's, whose kernels it shares)
ENTRIES = {
    "solve_schur": ("direct kinematics", 12),
    "solve_blocks": ("inverse kinematics", 6),
    "forward_rows": ("the direct-kinematics batch loop", 13),
    "inverse_rows": ("the inverse-kinematics batch loop", 8),
    "follow": ("the readings path", 12),
    "prove_packed": ("the Krawczyk proof of a warm step", 60),
    "measure": ("the pose uncertainty", 5),
    "measure_solved": ("the pose uncertainty of a solve", 3),
    "stuck_checks": ("the tracker's stuck test", 1),
    "begin_sample": ("the tracker's reading statistics", 1),
    "branch_residual": ("the tracker's branch check", 2),
    "predict_into": ("the tracker's predictor", 1),
    "push_trusted": ("the tracker's histories", 1),
    "measure_body": ("the body check: joint cones and collisions", 4),
}

#: first-generation threshold of the cyclic garbage collector while numba compiles (CPython's
#: default is 700); the process's own thresholds are restored when the compilation ends
COMPILING_GC_THRESHOLD = 10_000

log = logging.getLogger(LOGGER)
_announced: set[tuple[str, str]] = set()  # (module, name) of each entry announced or found ready
_warned: list[bool] = []  # the CompileWarning, once per process
_PACKAGE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
_collecting_less: list[Any] = []  # the numba event listener, once registered


def announce(dispatcher: Any) -> None:
    """Log the compilation ``dispatcher``'s next call will start, once per entry and process, if it will.

    Entries are told apart by module and name (two modules may each have a ``measure``); the
    message is :data:`ENTRIES`' for the name.
    """
    py_func = getattr(dispatcher, "py_func", None)
    name = getattr(py_func, "__name__", "")
    key = (getattr(py_func, "__module__", ""), name)
    if key in _announced:  # announced, compiled or loaded already: a set lookup on every later call
        return
    if dispatcher.signatures or _cached(dispatcher):  # numba builds the signature list anew: ~15 us
        _announced.add(key)
        return
    _announced.add(key)
    collect_less()
    what, seconds = ENTRIES.get(name, ("the solver", 10))
    message = f"compiling the solver kernels ({what}), once after installation: ~{seconds} s"
    log.info("%s", message)
    if not _warned:
        _warned.append(True)
        warnings.warn(message, CompileWarning, stacklevel=_caller_level())


def _caller_level() -> int:
    """The ``stacklevel`` of the first frame outside the package: the warning names the user's line."""
    here = inspect.currentframe()
    frame: FrameType | None = None if here is None else here.f_back
    level = 1
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE):
        frame, level = frame.f_back, level + 1
    return level


def _cached(dispatcher: Any) -> bool:
    """Whether numba's cache holds an index for ``dispatcher`` (its machine code then loads, not compiles)."""
    try:
        return os.path.exists(dispatcher._cache._cache_file._index_path)
    except AttributeError:  # no cache (cache=False) or another numba layout: assume it compiles
        return False


def collect_less() -> None:
    """From now on, raise the collector's first threshold to :data:`COMPILING_GC_THRESHOLD` while numba compiles.

    A listener of numba's ``numba:compile`` event (a compilation, not a load from the cache): the
    outermost compilation saves the thresholds and the last one to end restores them, also when
    it fails. Imports numba; registered once per process.
    """
    if _collecting_less:
        return
    from numba.core import event

    class CollectLess(event.Listener):
        def __init__(self) -> None:
            self.depth, self.saved = 0, gc.get_threshold()

        def on_start(self, event: Any) -> None:
            if self.depth == 0:  # numba compiles under its global lock: one thread at a time
                self.saved = gc.get_threshold()
                gc.set_threshold(max(self.saved[0], COMPILING_GC_THRESHOLD), *self.saved[1:])
            self.depth += 1

        def on_end(self, event: Any) -> None:
            self.depth -= 1
            if self.depth == 0:
                gc.set_threshold(*self.saved)

    listener = CollectLess()
    event.register("numba:compile", listener)
    _collecting_less.append(listener)
