"""The hot paths' calls of compiled kernels: one machine code per call site, called directly.

numba's dispatcher resolves the numba type of every argument on every call to find the machine
code compiled for those types, the more so for a tuple of arrays (the last argument of a warm
solve's entry, :func:`.iteration.solve_schur`): a measurable part of a warm solve, a proof and a
tracker step (docs/performance.md). A call site whose arguments keep their types calls the
machine code its first call ran (:func:`direct`: what the dispatcher would pick, without the
search).

For a type it has not compiled the dispatcher compiles a new specialisation, unannounced: for a
read-only array (pandas' copy-on-write ``to_numpy()``, ``np.load(..., mmap_mode="r")``,
``setflags(write=False)``), a strided, unaligned or float32 one, the whole solver again (seconds;
the proof, a minute). Every array a hot path takes from its caller goes through :func:`plain`
first: float64, C-contiguous, aligned and writeable, copied when it is not. That keeps one
specialisation per entry, and it is what makes :func:`direct`'s machine code the right one on
every later call (its own argument checks are the array's item size only).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

_F64 = np.dtype(np.float64)


def plain(a: np.ndarray) -> np.ndarray:
    """``a`` when it is float64, C-contiguous, aligned and writeable (one compiled type), else a copy that is."""
    return a if a.dtype is _F64 and a.flags.carray else np.array(a, dtype=np.float64, order="C")


def direct(dispatcher: Callable, args: Sequence[object]) -> Callable:
    """The machine code ``dispatcher`` ran for ``args``' types, to call without its per-call type resolution.

    Call it after a call of ``dispatcher`` with ``args`` (which compiled or loaded that code); the
    caller must then pass arguments of the same types on every call (arrays through
    :func:`plain`). ``dispatcher`` itself when it is not a numba dispatcher holding that code.
    """
    get_overload = getattr(dispatcher, "get_overload", None)
    if get_overload is None:  # a plain Python function (a kernel replaced in a test, NumPy kernels)
        return dispatcher
    import numba

    try:
        return get_overload(tuple(numba.typeof(a) for a in args))
    except (KeyError, TypeError, ValueError):  # no machine code for exactly these types: keep the dispatcher
        return dispatcher
