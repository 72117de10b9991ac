"""``hexapod serve`` / ``simulate-encoders`` / ``fixture`` / ``view --live``, in-process and as processes.

Everything runs on python-can's ``virtual`` bus (buses of one process) and HTTP on 127.0.0.1;
the process-level tests start ``hexapod serve ... --simulate`` on an ephemeral port, are bounded
in time and stop the process they started.
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import sqlite3
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
import uuid
from pathlib import Path

import can
import numpy as np
import pytest

from hexapod_model.cli.main import main
from hexapod_model.lie import rpy_to_matrix
from hexapod_model.service import RECORD_KEYS, FixtureService, Simulator, decode, load_config, load_simulation

from ..service.helpers import kernels_ready, stored_locks

ROOT = Path(__file__).resolve().parents[2]
HOLD = [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]


def write_config(tmp_path, port=0, extra="", fixtures=None, channel=None) -> Path:
    fixtures = fixtures or [("left", "reference", [0x181 + k for k in range(6)], "")]
    text = f'[bus]\ninterface = "virtual"\nchannel = "{channel or uuid.uuid4().hex}"\n'
    text += f'[store]\npath = "store.sqlite"\n[http]\nhost = "127.0.0.1"\nport = {port}\n{extra}'
    for name, hexa, ids, more in fixtures:
        text += f'[[fixtures]]\nname = "{name}"\nhexapod = "{hexa}"\ncan_ids = {ids}\n{more}'
    p = tmp_path / "fixture.toml"
    p.write_text(text)
    return p


def write_sim(tmp_path, body: str, name="sim.toml") -> Path:
    p = tmp_path / name
    p.write_text("seed = 5\n" + body)
    return p


HOLD_SIM = f'[[fixtures]]\nname = "left"\nrate = 100.0\nhold = {HOLD}\n'


# ----- bad input: one line, exit 2 -----
def bad_cases(tmp_path):
    ids = [0x181 + k for k in range(6)]
    (tmp_path / "broken.urdf").write_text("<robot name='x'><link name='base'/></robot>")
    return {
        "missing field": (
            write_config(tmp_path, fixtures=[("left", "reference", ids, "")])
            .read_text()
            .replace('name = "left"\n', ""),
            "fixtures[0].name",
        ),
        "duplicate CAN id": (
            write_config(tmp_path, fixtures=[("left", "reference", ids[:5] + [ids[0]], "")]).read_text(),
            "duplicate CAN id",
        ),
        "unknown interface": (write_config(tmp_path).read_text().replace('"virtual"', '"vcan"'), "bus.interface"),
        "unreadable hexapod file": (
            write_config(tmp_path, fixtures=[("left", "broken.urdf", ids, "")]).read_text(),
            "fixtures[0].hexapod",
        ),
    }


@pytest.mark.parametrize("case", ["missing field", "duplicate CAN id", "unknown interface", "unreadable hexapod file"])
def test_bad_configuration_one_line_exit_2(tmp_path, capsys, case):
    text, words = bad_cases(tmp_path)[case]
    cfg = tmp_path / "bad.toml"
    cfg.write_text(text)
    assert main(["serve", str(cfg), "--duration", "30"]) == 2
    # a hexapod file is loaded once HTTP answers "starting" (the load may compile): INFO lines first
    err = [line for line in capsys.readouterr().err.strip().splitlines() if " INFO " not in line]
    assert len(err) == 1 and err[0].startswith("hexapod serve: error:") and words in err[0], err


def test_port_in_use_one_line_exit_2(tmp_path, capsys):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        cfg = write_config(tmp_path, port=port)
        assert main(["serve", str(cfg), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"127.0.0.1:{port}: port in use" in err[0], err
    assert not (tmp_path / "store.sqlite").exists()  # nothing was started


def test_fixture_commands_without_a_store_or_with_bad_times(tmp_path, capsys):
    cfg = write_config(tmp_path)
    assert main(["fixture", "status", str(cfg)]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["fixture", "history", str(cfg), "--since", "yesterday"]) == 2
    assert "--since" in capsys.readouterr().err


# ----- in-process commands -----
def test_simulate_encoders_sends_the_fixtures_own_frames(tmp_path, capsys):
    cfg = write_config(
        tmp_path,
        fixtures=[
            (
                "left",
                "reference",
                [0x181 + k for k in range(6)],
                "home_counts = 1000\n[fixtures.encoder]\nbyte_order = 'big'\n",
            )
        ],
    )
    sim = write_sim(tmp_path, HOLD_SIM.replace("rate = 100.0", "rate = 50.0\nnoise = 0.0"))
    config = load_config(cfg)
    listener = can.Bus(interface="virtual", channel=config.bus.channel)
    try:
        assert main(["simulate-encoders", str(cfg), str(sim), "--duration", "0.3"]) == 0
        frames = []
        while (m := listener.recv(timeout=0.5)) is not None:
            frames.append(m)
    finally:
        listener.shutdown()
    assert "sent" in capsys.readouterr().err
    assert (
        12 <= len(frames) <= 6 * 16
        and len(frames) % 6 == 0
        and {m.arbitration_id for m in frames} == set(range(0x181, 0x187))
    )
    legs = config.fixtures[0].legs
    readings = {}
    for m in frames:
        leg = legs[m.arbitration_id - 0x181]
        readings[m.arbitration_id] = leg.reading(decode(leg.layout, m.data).position)
    hexa = config.fixtures[0].load_hexapod()
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(*np.radians(HOLD[3:]))
    T[:3, 3] = HOLD[:3]
    truth = hexa.inverse(T).lengths
    assert np.allclose([readings[0x181 + k] for k in range(6)], truth, atol=0.6e-6)  # 1 um counts, no noise


def test_bad_http_host_names_the_host_not_the_port(tmp_path, capsys):
    cfg = write_config(tmp_path, extra="allow_unauthenticated_reads = true\n")
    cfg.write_text(cfg.read_text().replace('host = "127.0.0.1"', 'host = "no-such-host.invalid"'))
    assert main(["serve", str(cfg), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no-such-host.invalid" in err[0] and "set [http] host" in err[0], err
    assert "port" not in err[0].split("(")[0]


# ----- process level -----
def env():
    e = dict(os.environ)
    e["PYTHONPATH"] = str(ROOT) + os.pathsep + e.get("PYTHONPATH", "")
    return e


class Served:
    """``hexapod serve`` in a subprocess: its port, its JSON lines (read in a thread), bounded waits."""

    def __init__(self, *args: str):
        kernels_ready()  # in numba's cache before the subprocess starts: its wait for ready is bounded
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "hexapod_model", "serve", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env(),
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # Ctrl-C works, as in a terminal
        )
        self.records: list[dict] = []
        self.err: list[str] = []
        self.port: int | None = None
        self._port_seen = threading.Event()
        threading.Thread(target=self._read_out, daemon=True).start()
        threading.Thread(target=self._read_err, daemon=True).start()

    def _read_out(self):
        for line in self.proc.stdout:
            self.records.append(json.loads(line))

    def _read_err(self):
        for line in self.proc.stderr:
            self.err.append(line)
            m = re.search(r"serving http://127\.0\.0\.1:(\d+)", line)
            if m:
                self.port = int(m.group(1))
                self._port_seen.set()

    def wait_port(self, timeout=90.0) -> int:
        """The port, once the service is ready (``/health`` answers ``503 starting`` before)."""
        assert self._port_seen.wait(timeout), "".join(self.err)
        assert self.port is not None
        self.wait_for(lambda: self.status("/health") != 503, timeout)
        return self.port

    def status(self, path, headers=None) -> int:
        req = urllib.request.Request(f"http://127.0.0.1:{self.port}{path}", headers=headers or {})
        try:
            with urllib.request.urlopen(req, timeout=5) as r:
                return r.status
        except urllib.error.HTTPError as e:
            return e.code

    def get(self, path):
        with urllib.request.urlopen(f"http://127.0.0.1:{self.port}{path}", timeout=5) as r:
            return json.load(r)

    def wait_for(self, predicate, timeout=60.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if predicate():
                return
            assert self.proc.poll() is None, "".join(self.err)
            time.sleep(0.05)
        raise AssertionError(f"timed out; stderr: {''.join(self.err)[-2000:]}")

    def finish(self, sig=signal.SIGINT, timeout=30.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()


def test_serve_simulated_over_http_and_json_lines_then_ctrl_c_and_fixture_status(tmp_path, capsys):
    cfg = write_config(tmp_path, fixtures=[("left", "reference", [0x181 + k for k in range(6)], "lock_time = 0.3\n")])
    sim = write_sim(tmp_path, HOLD_SIM)
    served = Served(str(cfg), "--simulate", str(sim), "--jsonl")
    try:
        served.wait_port()
        assert served.get("/fixtures") == {"fixtures": ["left"]}
        # a stored lock, and enough samples for the checks below whatever the machine's load
        served.wait_for(lambda: any(r["stored"] for r in served.records) and len(served.records) > 30)
        pose = served.get("/fixtures/left/pose")
        health = served.get("/health")
    finally:
        t0 = time.monotonic()
        code = served.finish(signal.SIGINT)
        stopped = time.monotonic() - t0
    assert code == 0, "".join(served.err)
    assert stopped < 2.0  # Ctrl-C of a running service: stopped and exited within 2 s
    assert f"hexapod serve: dashboard http://127.0.0.1:{served.port}/\n" in served.err  # no token: the page as it is
    assert tuple(pose) == RECORD_KEYS and pose["status"] == "ok" and pose["state"] == "locked" and pose["stored"]
    assert health["status"] == "ok" and health["fixtures"]["left"]["stored"]
    ok = [r for r in served.records if r["status"] == "ok"]
    assert len(ok) > 20 and all(tuple(r) == RECORD_KEYS for r in served.records)
    for r in ok:  # the held pose, within 5 sigma (sigma: RMS error length)
        p = r["pose"]
        assert np.linalg.norm(np.array([p["x"], p["y"], p["z"]]) - HOLD[:3]) < 5e-3 * r["sigma"]["translation_mm"]
        assert np.allclose([p["roll"], p["pitch"], p["yaw"]], HOLD[3:], atol=5 * 3**0.5 * r["sigma"]["rotation_deg"])
    assert main(["fixture", "status", str(cfg)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1].split()[0] == "left" and out[1].split()[-1] == "same"
    assert np.allclose([float(v) for v in out[1].split()[2:8]], HOLD, atol=2e-3)
    assert main(["fixture", "history", str(cfg), "-o", str(tmp_path / "log.csv")]) == 0
    rows = (tmp_path / "log.csv").read_text().splitlines()
    first_locked = next(r for r in served.records if r["state"] == "locked")
    assert rows[0].startswith("fixture,t,time,x,y,z") and len(rows) == 2
    assert float(rows[1].split(",")[1]) == first_locked["t"]
    assert main(["fixture", "history", str(cfg), "--samples", "--since", "0"]) == 0
    assert len(capsys.readouterr().out.splitlines()) > 20


def test_first_start_answers_503_starting_at_once_and_sigint_stops_within_2_s(tmp_path):
    cfg = write_config(tmp_path)
    t0 = time.monotonic()
    served = Served(str(cfg), "--simulate", str(write_sim(tmp_path, HOLD_SIM)))
    try:
        assert served._port_seen.wait(60), "".join(served.err)
        first = served.status("/health")
        answered = time.monotonic() - t0
        assert first in (503, 200), first
        served.proc.send_signal(signal.SIGINT)  # while starting (or just after)
        t1 = time.monotonic()
        code = served.proc.wait(10)
        assert time.monotonic() - t1 < 2.0 and code == 0, (code, "".join(served.err))
    finally:
        served.finish()
    assert answered < 10.0  # the port answers as the process starts: imports only, no compile, no hexapod
    assert not any("Traceback" in line for line in served.err), "".join(served.err)


def startup_errors(tmp_path):
    """(arguments of ``hexapod serve``, words the one line names) per start-up error."""
    cfg = write_config(tmp_path)
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen()
    (tmp_path / "busy").mkdir()
    in_use = write_config(tmp_path / "busy", port=busy.getsockname()[1])
    bad_cfg = tmp_path / "bad.toml"
    bad_cfg.write_text(cfg.read_text().replace("[store]", "[stor]"))
    misspelt = HOLD_SIM.replace("rate = 100.0", "rat = 100.0")
    return busy, {
        "misspelt sim key": ([str(cfg), "--simulate", str(write_sim(tmp_path, misspelt, "rat.toml"))], "rat"),
        "misspelt sim table key": (
            [str(cfg), "--simulate", str(write_sim(tmp_path, HOLD_SIM + 'trajectroy = "A"\n', "traj.toml"))],
            "trajectroy",
        ),
        "missing sim file": ([str(cfg), "--simulate", str(tmp_path / "nosuch.toml")], "nosuch.toml"),
        "missing fixture file": ([str(tmp_path / "nofixture.toml")], "nofixture.toml"),
        "bad fixture file": ([str(bad_cfg)], "stor"),
        "port in use": ([str(in_use), "--simulate", str(write_sim(tmp_path, HOLD_SIM))], "port in use"),
    }


@pytest.mark.parametrize(
    "case",
    [
        "misspelt sim key",
        "misspelt sim table key",
        "missing sim file",
        "missing fixture file",
        "bad fixture file",
        "port in use",
    ],
)
def test_every_start_up_error_of_serve_is_one_line_and_exit_2(tmp_path, case):
    busy, cases = startup_errors(tmp_path)
    args, words = cases[case]
    try:
        out = subprocess.run(
            [sys.executable, "-m", "hexapod_model", "serve", *args, "--duration", "60"],
            capture_output=True,
            text=True,
            env=env(),
            timeout=120,
        )
    finally:
        busy.close()
    err = [line for line in out.stderr.strip().splitlines() if " INFO " not in line]
    assert out.returncode == 2, out.stderr
    assert len(err) == 1 and err[0].startswith("hexapod serve: error:") and words in err[0], out.stderr


def test_kill_9_while_committing_locks_then_restart_recovers_the_last_lock(tmp_path):
    ids2 = [0x191 + k for k in range(6)]
    cfg = write_config(
        tmp_path,
        fixtures=[
            ("left", "reference", [0x181 + k for k in range(6)], "lock_time = 0.15\n"),
            ("right", "reference", ids2, "lock_time = 0.15\n"),
        ],
    )
    body = ""
    for name in ("left", "right"):
        body += f'[[fixtures]]\nname = "{name}"\nrate = 100.0\ntrajectory = "A"\nscale = 0.004\nperiod = 4.0\n'
        body += "move = 0.4\nlock = 0.4\nramp = 0.1\n"
    sim = write_sim(tmp_path, body)
    served = Served(str(cfg), "--simulate", str(sim), "--jsonl")

    def episodes():  # (fixture, t of the locking record, seen stored) per lock episode so far
        out, state = {}, {}
        for r in list(served.records):
            f = r["fixture"]
            if r["state"] == "locked" and state.get(f) != "locked":
                out[(f, r["t"])] = False
                key = (f, r["t"])
            if r["state"] == "locked" and r["stored"]:
                out[key] = True
            state[f] = r["state"]
        return out

    try:
        served.wait_port()
        served.wait_for(lambda: sum(episodes().values()) >= 4)
        n = len(episodes())  # kill the moment a new lock is being committed
        served.wait_for(lambda: len(episodes()) > n)
        served.proc.kill()
    finally:
        served.finish()
    stored = [k for k, v in episodes().items() if v]
    db = sqlite3.connect(tmp_path / "store.sqlite")
    assert db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"  # opens without repair
    events = db.execute("SELECT fixture, t FROM lock_events ORDER BY id").fetchall()
    db.close()
    assert set(stored) <= set(events) and len(stored) >= 4  # every lock published as stored is there
    last = {f: t for f, t in events}
    restarted = Served(str(cfg), "--simulate", str(write_sim(tmp_path, HOLD_SIM, "hold.toml")))
    try:
        restarted.wait_port()
        health = restarted.get("/health")
    finally:
        code = restarted.finish()
    assert code == 0, "".join(restarted.err)
    for f in ("left", "right"):
        assert health["fixtures"][f]["recovered_t"] == last[f]  # the guess is the last lock pose


def test_view_live_shows_a_served_pose(tmp_path, capsys):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    cfg = write_config(tmp_path, port=port)
    config = load_config(cfg)
    sim_bus = can.Bus(interface="virtual", channel=config.bus.channel, preserve_timestamps=True)
    sim = Simulator(config, load_simulation(write_sim(tmp_path, HOLD_SIM), config), sim_bus)
    try:
        with FixtureService(config) as service:
            sim.start()
            deadline = time.monotonic() + 30
            while getattr(service.record("left"), "status", None) != "ok" and time.monotonic() < deadline:
                time.sleep(0.05)
            assert main(["view", str(cfg), "--live", "--once"]) == 0
    finally:
        sim.stop()
        sim_bus.shutdown()
    captured = capsys.readouterr()
    assert "meshcat: http://127.0.0.1" in captured.out and "showed 1 poses of left" in captured.err


def test_a_step_needs_an_acknowledgement_from_the_command_line_then_ok_again(tmp_path, capsys):
    token = tmp_path / "fixture.token"
    token.write_text("cli-acknowledge-token-0123456789\n")
    token.chmod(0o600)
    cfg = write_config(tmp_path, extra='token_file = "fixture.token"\n')
    body = '[[fixtures]]\nname = "left"\nrate = 100.0\ntrajectory = "A"\n'
    body += '[[fixtures.faults]]\nkind = "step"\nleg = 2\nsize = 0.0005\nstart = 1.0\n'
    served = Served(str(cfg), "--simulate", str(write_sim(tmp_path, body)), "--jsonl")
    try:
        served.wait_port()
        assert served.status("/health") == 401  # a token is configured: reads need it too
        served.wait_for(lambda: any(r["status"] == "unacknowledged_fault" for r in served.records))
        time.sleep(0.3)
        n = len(served.records)
        url = ["--url", f"http://127.0.0.1:{served.port}"]  # port 0 in the configuration: the one it took
        assert main(["fixture", "acknowledge", str(cfg), "left", "--by", "tester", "--note", "checked", *url]) == 0
        served.wait_for(lambda: any(r["status"] == "ok" for r in served.records[n:]))
        assert main(["fixture", "acknowledge", str(cfg), "left", "--by", "tester", *url]) == 2  # nothing waits now
    finally:
        code = served.finish(signal.SIGINT)
    assert code == 0, "".join(served.err)
    err = capsys.readouterr().err
    assert "left: discontinuity (leg 2) acknowledged by tester" in err and "409" in err
    log = "".join(served.err)
    assert "acknowledged by tester (127.0.0.1:" in log and "Traceback" not in log
    page = f"dashboard http://127.0.0.1:{served.port}/#token=TOKEN, TOKEN the content of {token} "
    assert page in log  # where the dashboard is and where its token goes
    first = next(k for k, r in enumerate(served.records) if r["status"] == "unacknowledged_fault")
    later_ok = next(k for k, r in enumerate(served.records) if k > first and r["status"] == "ok")
    assert all(r["status"] != "ok" and "discontinuity:leg2" in r["flags"] for r in served.records[first:later_ok])


def test_process_late_legs_duplicate_id_store_deleted_and_http_limits(tmp_path):
    """Through `hexapod serve`: a record per instant naming late and duplicated legs, a store file
    deleted while serving keeps every lock published stored, JSON 405, 100 concurrent GETs."""
    from concurrent.futures import ThreadPoolExecutor

    ids2 = [0x191 + k for k in range(6)]
    cfg = write_config(
        tmp_path,
        fixtures=[
            ("left", "reference", [0x181 + k for k in range(6)], "lock_time = 0.15\n"),
            ("right", "reference", ids2, ""),
        ],
    )
    body = '[[fixtures]]\nname = "left"\nrate = 100.0\ntrajectory = "A"\nscale = 0.004\nperiod = 4.0\n'
    body += "move = 0.4\nlock = 0.4\nramp = 0.1\n"
    body += '[[fixtures]]\nname = "right"\nrate = 100.0\ntrajectory = "A"\n'
    for leg in (5, 6):
        body += f'[[fixtures.faults]]\nkind = "late_frame"\nleg = {leg}\nstart = 0.0\nduration = 1000.0\n'
    body += '[[fixtures.faults]]\nkind = "duplicate_id"\nleg = 3\nstart = 2.0\nduration = 1000.0\n'
    served = Served(str(cfg), "--simulate", str(write_sim(tmp_path, body)), "--jsonl")

    try:
        served.wait_port()
        served.wait_for(lambda: len(stored_locks(served.records)) >= 1)
        for suffix in ("", "-wal", "-shm"):
            (tmp_path / f"store.sqlite{suffix}").unlink(missing_ok=True)
        served.wait_for(lambda: len(stored_locks(served.records)) >= 3)
        health = served.get("/health")
        req = urllib.request.Request(f"http://127.0.0.1:{served.port}/health", method="OPTIONS")
        with pytest.raises(urllib.error.HTTPError) as info:
            urllib.request.urlopen(req, timeout=5)
        assert info.value.code == 405 and "error" in json.load(info.value)
        with ThreadPoolExecutor(max_workers=25) as pool:
            codes = list(pool.map(lambda _: served.status("/fixtures/left/pose"), range(100)))
        assert codes == [200] * 100
    finally:
        code = served.finish(signal.SIGINT)
    assert code == 0, "".join(served.err)
    right = health["fixtures"]["right"]
    assert right["status"] in ("incomplete", "duplicate_frame") and right["age_s"] < 0.5
    assert {"missing:leg5", "missing:leg6", "late_frame:leg5", "late_frame:leg6"} & set(right["flags"])
    assert any(p.startswith("right: ") for p in health["problems"]) and health["store"]["error"] is None
    late = [r for r in served.records if r["fixture"] == "right"]
    assert late and not any(r["status"] == "ok" for r in late[10:])
    assert any("duplicate:leg3" in r["flags"] for r in late)
    db = sqlite3.connect(tmp_path / "store.sqlite")
    events = {t for (t,) in db.execute("SELECT t FROM lock_events WHERE fixture = 'left'")}
    db.close()
    assert stored_locks(served.records) <= events
    assert "Traceback" not in "".join(served.err)
