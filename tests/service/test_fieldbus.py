"""Encoder protocols: a DBC-described and a CANopen (EDS) encoder set give the hand-written layout's records.

The CANopen encoders are ``canopen`` library nodes played from the example EDS on python-can's
``virtual`` bus, answering the service in the same process; nothing leaves this process.
"""

from __future__ import annotations

import time
import uuid
from pathlib import Path

import pytest

from hexapod_model.service import ConfigError, FixtureCycle, FixtureService, Simulator, decode, geometry_hash

from ..conftest import hexapod
from .helpers import CollectingBus, fixture_table, kernels_ready, service_config, sim_config

canopen = pytest.importorskip("canopen")
cantools = pytest.importorskip("cantools")

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
DBC, EDS = EXAMPLES / "encoders.dbc", EXAMPLES / "encoder.eds"
RAW = {"error_bit": 40, "warning_bit": 41}  # the example DBC's layout, written out by hand
MOVING = {"name": "left", "rate": 100.0, "noise": 0.0, "trajectory": "A", "period": 60.0}  # slow: a busy
# machine's uneven pacing of the test's own sends must not read as a step


def test_the_example_dbc_and_eds_give_the_layouts_written_by_hand(tmp_path):
    dbc = service_config(tmp_path, [fixture_table(encoder={"protocol": "dbc", "dbc": str(DBC)})])
    raw = service_config(tmp_path, [fixture_table(encoder=RAW)])
    assert dbc.fixtures[0].legs == raw.fixtures[0].legs and dbc.fixtures[0].protocol == "dbc"
    co = service_config(tmp_path, [fixture_table(encoder={"protocol": "canopen", "eds": str(EDS)})])
    f = co.fixtures[0]
    assert f.canopen is not None and f.canopen.node_ids == (1, 2, 3, 4, 5, 6) and f.canopen.heartbeat == 0.1
    assert (f.legs[0].layout.width, f.legs[0].layout.error_bit, f.legs[0].layout.metres_per_count) == (4, 32, 1e-6)


@pytest.mark.parametrize(
    "encoder, words",
    [
        ({"protocol": "dbc", "dbc": "missing.dbc"}, "encoder.dbc"),
        ({"protocol": "dbc", "dbc": str(DBC), "position": "Speed"}, "encoder.position"),
        ({"protocol": "canopen", "eds": str(EDS), "position_object": 0x6010}, "encoder.position_object"),
        ({"protocol": "canbus"}, "encoder.protocol"),
    ],
)
def test_a_bad_protocol_table_is_one_line_naming_the_field(tmp_path, encoder, words):
    with pytest.raises(ConfigError) as exc:
        service_config(tmp_path, [fixture_table(encoder=encoder)])
    assert words in str(exc.value) and len(str(exc.value).splitlines()) == 1


def test_dbc_encoded_frames_give_the_records_of_the_hand_written_layout(tmp_path):
    dbc = service_config(tmp_path, [fixture_table(encoder={"protocol": "dbc", "dbc": str(DBC)})])
    raw = service_config(tmp_path, [fixture_table(encoder=RAW)])
    message = cantools.database.load_file(str(DBC)).get_message_by_name("EncoderPosition")
    hexa = hexapod("reference")
    cycles = [FixtureCycle(c.fixtures[0], hexa, geometry_hash(hexa), None, 1e9) for c in (raw, dbc)]
    bus = CollectingBus()
    simulator = Simulator(raw, sim_config(raw, [MOVING]), bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    legs = raw.fixtures[0].legs
    out: list[list] = [[], []]
    for k in range(200):
        bus.sent.clear()
        simulator.send_set(0, k / 100.0, stamp=1e9 + k / 100.0, stall_check=False)
        for msg in bus.sent:
            leg = msg.arbitration_id - 0x181
            d = decode(legs[leg].layout, msg.data)
            vendor = message.encode({"Position": d.position * 1e-3, "Error": d.error, "Warning": d.warning})
            for cycle, data, records in zip(cycles, (msg.data, vendor), out):
                rec = cycle.on_frame(leg, data, msg.timestamp)
                if rec is not None:
                    records.append(rec)
    assert len(out[0]) == len(out[1]) >= 190 and sum(r.status == "ok" for r in out[1]) >= 150
    for a, b in zip(*out):
        assert (a.status, a.flags, a.pose, a.readings) == (b.status, b.flags, b.pose, b.readings)


# ----- CANopen nodes on the virtual bus -----
class Encoders:
    """Six CiA 406 encoders played by ``canopen`` from the example EDS: positions sent in TPDO1 on each SYNC."""

    def __init__(self, channel: str):
        self.network = canopen.Network()
        self.network.connect(interface="virtual", channel=channel, receive_own_messages=False)
        self.nodes = []
        for node_id in range(1, 7):
            node = canopen.LocalNode(node_id, str(EDS))
            self.network.add_node(node)
            node.tpdo.read(from_od=True)
            node.nmt.state = "OPERATIONAL"
            self.nodes.append(node)

    def heartbeat(self, legs=range(6)):
        for k in legs:
            self.network.send_message(0x700 + k + 1, bytes([0x05]))

    def send(self, counts):
        self.network.sync.transmit()
        for node, count in zip(self.nodes, counts):
            node.tpdo[1]["Position value"].raw = int(count)
            node.tpdo[1].transmit()

    def close(self):
        self.network.disconnect()


def _counts(config, hexa, n):
    """The counts of the raw simulation's sets (noise-free trajectory A), and the raw layout's records."""
    raw = service_config(Path(config), [fixture_table(encoder=RAW)])
    bus = CollectingBus()
    simulator = Simulator(raw, sim_config(raw, [MOVING]), bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    cycle = FixtureCycle(raw.fixtures[0], hexa, geometry_hash(hexa), None, 1e9)
    sets, records = [], {}
    for k in range(n):
        bus.sent.clear()
        simulator.send_set(0, k / 100.0, stamp=1e9 + k / 100.0, stall_check=False)
        sets.append([decode(raw.fixtures[0].legs[0].layout, m.data).position for m in bus.sent])
        for m in bus.sent:
            rec = cycle.on_frame(m.arbitration_id - 0x181, m.data, m.timestamp)
            if rec is not None:
                records[tuple(rec.readings)] = rec
    return sets, records


def test_a_canopen_encoder_set_drives_the_service_to_the_raw_layouts_records_emcy_and_heartbeat(tmp_path):
    channel = f"co-{uuid.uuid4().hex}"
    hexa = hexapod("reference")
    sets, raw_records = _counts(tmp_path, hexa, 150)
    config = service_config(
        tmp_path, [fixture_table(encoder={"protocol": "canopen", "eds": str(EDS)})], channel=channel
    )
    encoders = Encoders(channel)
    got = []
    service = FixtureService(config, http=False, hexapods={"left": hexa})
    service.subscribe(got.append)
    try:
        service.start()
        _play(encoders, sets)
        _settle(got)
        ok = [r for r in got if r.status == "ok"]
        assert len(ok) >= 100, [(r.status, r.flags) for r in got if r.status != "ok"][:40]
        for r in ok:  # the same readings give the same pose as the hand-written layout's cycle
            ref = raw_records.get(tuple(r.readings))
            assert ref is not None and ref.status == "ok"
            assert max(abs(r.pose[c] - ref.pose[c]) for c in "xyz") < 1e-9
        # EMCY: leg 3's encoder reports an error -> encoder_error until its reset
        got.clear()
        encoders.nodes[2].emcy.send(0x7300)
        _play(encoders, sets[-10:])
        playing = list(got)  # then the bus is quiet: silent_leg
        assert len(playing) >= 5 and all(r.status == "encoder_error" for r in playing[1:]), playing
        assert all(r.flags == ["encoder_error:leg3"] for r in playing[1:])
        encoders.nodes[2].emcy.reset()
        _settle(got)
        # heartbeat lost on leg 5 (its TPDOs still come): silent_leg naming it alone
        got.clear()
        _play(encoders, sets[-20:], beating=[0, 1, 2, 3, 5])
        playing = list(got)
        assert len(playing) >= 10 and all(r.status == "silent_leg" for r in playing[1:]), playing
        silent = [[f for f in r.flags if f.startswith("silent:")] for r in playing[1:]]
        assert all(s == ["silent:leg5"] for s in silent), silent
    finally:
        service.stop()
        encoders.close()


def _play(encoders, sets, beating=range(6), period=0.01):
    """Heartbeats, a SYNC and the six TPDOs of each set, one set per ``period`` s."""
    t0 = time.monotonic()
    for k, counts in enumerate(sets):
        encoders.heartbeat(beating)
        encoders.send(counts)
        time.sleep(max(0.0, t0 + (k + 1) * period - time.monotonic()))


def _settle(got, quiet=0.3, limit=5.0):
    """Wait until no record arrived for ``quiet`` s (at most ``limit`` s)."""
    t0, n = time.monotonic(), -1
    while time.monotonic() - t0 < limit and n != len(got):
        n = len(got)
        time.sleep(quiet)


@pytest.mark.parametrize("encoder", [f'protocol = "canopen"\neds = "{EDS}"\n', f'protocol = "dbc"\ndbc = "{DBC}"\n'])
def test_hexapod_serve_simulated_canopen_and_dbc_fixtures_publish_ok_records(tmp_path, capsys, encoder):
    import json

    from hexapod_model.cli.main import main

    from ..cli.test_service_cli import HOLD_SIM, write_config, write_sim

    more = f"[fixtures.encoder]\n{encoder}"
    cfg = write_config(tmp_path, fixtures=[("left", "reference", [0x181 + k for k in range(6)], more)])
    kernels_ready()  # the run's seconds serve: none go to compiling
    assert (
        main(["serve", str(cfg), "--simulate", str(write_sim(tmp_path, HOLD_SIM)), "--jsonl", "--duration", "3"]) == 0
    )
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines() if line.startswith("{")]
    ok = [r for r in records if r["status"] == "ok"]
    assert len(ok) >= 100 and len(ok) >= 0.8 * len(records), {r["status"] for r in records}
