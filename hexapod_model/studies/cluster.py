"""The Dask cluster that ``hexapod evaluate`` and ``hexapod sweep`` run their tasks on.

Without an address, a ``distributed.LocalCluster`` of one single-threaded worker process per core
(the solver's buffers are per thread, numba releases no GIL worth sharing), bound to 127.0.0.1;
with ``tcp://HOST:PORT``, an existing cluster started by ``dask scheduler`` / ``dask worker``
(docs/sweep.md). A scheduler that does not answer is an :class:`~hexapod_model.exceptions.InputError`,
never a silent fallback to the local machine.
"""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from ..exceptions import InputError
from ..extras import require

CONNECT_TIMEOUT_S = 5.0


def _distributed() -> Any:
    return require("distributed", "sweep")


@contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None) -> Iterator[Any]:
    """A ``distributed.Client``: on the scheduler at ``scheduler``, or on a LocalCluster of ``workers`` processes.

    Args:
        scheduler: ``tcp://HOST:PORT`` of a running ``dask scheduler``; ``None``: a LocalCluster on this
            machine (127.0.0.1, dashboard on a free local port when bokeh is installed).
        workers: processes of the LocalCluster (default: all cores); not used with ``scheduler``.

    Raises:
        InputError: dask.distributed missing, ``workers`` < 1, or no scheduler answering at ``scheduler``
            within :data:`CONNECT_TIMEOUT_S` seconds.
    """
    distributed = _distributed()
    if scheduler is not None:
        if "://" not in scheduler:
            raise InputError("--scheduler", scheduler, "expected an address like tcp://HOST:PORT")
        try:
            client = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError) as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            raise InputError("--scheduler", scheduler, f"no Dask scheduler answers there ({reason[:160]})") from None
        try:
            yield client
        finally:
            client.close()
        return
    n = workers or os.cpu_count() or 1
    if n < 1:
        raise InputError("--workers", workers, "need at least 1 worker process")
    import dask

    # fork: the workers start with the package, Pinocchio and the loaded numba kernels of this process
    # (spawn re-imports and reloads them in each: 2-3 s of CPU per worker, 3x the wall time of an evaluate)
    with dask.config.set({"distributed.worker.multiprocessing-method": "fork"}):
        cluster = distributed.LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",  # a free port: several clusters may run on one machine
            silence_logs=40,  # logging.ERROR
        )
    client = distributed.Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


def dashboard_link(client: Any) -> str | None:
    """The dashboard URL of ``client``'s scheduler, or ``None`` when it runs none.

    The dashboard's pages need bokeh (``pip install bokeh``); without it here, no link is given (the
    scheduler then serves only its health and metrics pages).
    """
    if importlib.util.find_spec("bokeh") is None:
        return None
    try:
        services = client.scheduler_info().get("services", {})
    except Exception:  # an unanswering scheduler: no link, the tasks will say more
        return None
    return client.dashboard_link if "dashboard" in services else None
