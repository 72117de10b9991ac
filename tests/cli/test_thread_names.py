"""The service's threads carry their names at the OS level: a ``serve --simulate`` process's CPU splits by thread."""

from __future__ import annotations

import os
import signal
import sys
import threading
from pathlib import Path

import pytest

from hexapod_model.service.threads import NamedThread, set_os_thread_name

from .test_service_cli import HOLD_SIM, Served, write_config, write_sim

linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and prctl are Linux's")


def comm(pid: int, tid: int) -> str:
    return Path(f"/proc/{pid}/task/{tid}/comm").read_text().strip()


@linux
def test_a_named_thread_names_itself_for_the_os_and_long_names_are_cut():
    seen: dict[str, str] = {}

    def read(key: str) -> None:
        seen[key] = comm(os.getpid(), threading.get_native_id())

    t = NamedThread(target=read, name="hx-test", args=("short",))
    t.start()
    t.join()
    t = NamedThread(target=read, name="hx-a-name-longer-than-fifteen", args=("long",))
    t.start()
    t.join()
    assert seen == {"short": "hx-test", "long": "hx-a-name-longe"}
    plain = threading.Thread(target=read, name="hx-plain", args=("plain",))  # Python's name only
    plain.start()
    plain.join()
    assert seen["plain"] != "hx-plain"


@linux
def test_set_os_thread_name_renames_the_calling_thread_only():
    out: dict[str, object] = {}

    def rename() -> None:
        out["set"] = set_os_thread_name("hx-renamed")
        out["comm"] = comm(os.getpid(), threading.get_native_id())

    before = comm(os.getpid(), threading.get_native_id())
    t = threading.Thread(target=rename)
    t.start()
    t.join()
    assert out == {"set": True, "comm": "hx-renamed"}
    assert comm(os.getpid(), threading.get_native_id()) == before


@linux
def test_serve_simulate_threads_read_hx_names_in_proc(tmp_path):
    cfg = write_config(tmp_path)
    sim = write_sim(tmp_path, HOLD_SIM)
    served = Served(str(cfg), "--simulate", str(sim), "--jsonl")
    try:
        served.wait_port()
        served.wait_for(lambda: len(served.records) > 5)  # the cycle runs and the simulator sends
        pid = served.proc.pid
        names = {comm(pid, int(p.name)) for p in Path(f"/proc/{pid}/task").iterdir()}
    finally:
        code = served.finish(signal.SIGINT)
    assert code == 0, "".join(served.err)
    assert {"hx-cycle", "hx-store", "hx-http", "hx-sim"} <= names, names
