"""One log line before a compiled entry compiles: the first solve after installation waits for it.

numba compiles an entry of the compiled path (:mod:`.iteration`, :mod:`.batch_kernels`,
:mod:`.follow`) on its first call and keeps the machine code in its cache (``__pycache__`` or
``NUMBA_CACHE_DIR``); later processes load it in well under a second. :func:`announce` logs, at
INFO on the ``hexapod_model.compile`` logger, ``compiling the solver kernels (WHAT), once after
installation: ~N s`` before a call that will compile (no signature in this process, no cache
index on disk); the command line shows it on a terminal.
"""

from __future__ import annotations

import logging
import os
from typing import Any

LOGGER = "hexapod_model.compile"
#: each entry: what it compiles, and the CPU seconds it took from an empty cache on a 2-core machine
#: (benchmarks/startup.py --cold: the inverse's after the forward's, whose kernels it shares)
ENTRIES = {
    "solve_schur": ("direct kinematics", 12),
    "solve_blocks": ("inverse kinematics", 6),
    "forward_rows": ("the direct-kinematics batch loop", 15),
    "inverse_rows": ("the inverse-kinematics batch loop", 8),
    "follow": ("the readings path", 12),
}

log = logging.getLogger(LOGGER)
_announced: set[str] = set()


def announce(dispatcher: Any) -> None:
    """Log the compilation ``dispatcher``'s next call will start, once per entry and process, if it will."""
    name = getattr(getattr(dispatcher, "py_func", None), "__name__", "")
    if name in _announced or dispatcher.signatures or _cached(dispatcher):
        return
    _announced.add(name)
    what, seconds = ENTRIES.get(name, ("the solver", 10))
    log.info("compiling the solver kernels (%s), once after installation: ~%d s", what, seconds)


def _cached(dispatcher: Any) -> bool:
    """Whether numba's cache holds an index for ``dispatcher`` (its machine code then loads, not compiles)."""
    try:
        return os.path.exists(dispatcher._cache._cache_file._index_path)
    except AttributeError:  # no cache (cache=False) or another numba layout: assume it compiles
        return False
