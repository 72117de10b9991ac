"""Frame integrity: a rolling counter, a checksum byte and CANopen's SYNC counter, checked frame by frame.

Rate 100 Hz, trajectory A, reading noise 10 um. A frame failing a check never gives a pose: its
set is ``bad_frame`` naming the check and the leg. Every ``ok`` record is compared with the
simulated truth of the instant its ``t`` names.
"""

from __future__ import annotations

import pytest

from hexapod_model.service import ConfigError, FixtureCycle, Simulator, geometry_hash
from hexapod_model.service.config.codec import FrameLayout, decode, encode
from hexapod_model.service.config.integrity import FrameIntegrity, checksum, crc8_sae_j1850
from hexapod_model.service.cycle.canopen_link import CanopenLink, SyncClock
from hexapod_model.service.cycle.frame_checks import FrameChecks

from ..conftest import hexapod
from .helpers import CollectingBus, fixture_table, pose_error, service_config, sim_config
from .test_cycle import RATE, set_of

CHECKED = {"error_bit": 32, "warning_bit": 33, "counter": {"offset": 40, "bits": 4}, "crc": {"offset": 7}}


def test_the_checksums_give_their_published_check_values():
    assert crc8_sae_j1850(b"123456789") == 0x4B  # CRC-8/SAE-J1850's catalogued check value
    assert checksum("sum8", bytes([0xFF, 0x02])) == 0x01 and checksum("xor8", bytes([0x0F, 0xFF])) == 0xF0


@pytest.mark.parametrize("kind", ["crc8-sae-j1850", "sum8", "xor8"])
def test_every_single_bit_flip_of_a_sealed_frame_fails_its_checksum(kind):
    layout = FrameLayout(integrity=FrameIntegrity(counter_bit=40, counter_bits=4, crc_byte=7, crc_kind=kind))
    data = encode(layout, -123456, warning=True, counter=13)
    assert decode(layout, data) == (-123456, False, True) and layout.integrity.counter(data) == 13
    assert layout.integrity.crc_ok(data)
    for bit in range(8 * len(data)):
        flipped = bytearray(data)
        flipped[bit >> 3] ^= 1 << (bit & 7)
        assert not layout.integrity.crc_ok(flipped), bit


def test_the_encoder_table_reads_counter_and_crc(tmp_path):
    cfg = service_config(tmp_path, [fixture_table(encoder={**CHECKED, "crc": {"offset": 7, "kind": "xor8"}})])
    integrity = cfg.fixtures[0].legs[0].layout.integrity
    assert (integrity.counter_bit, integrity.counter_bits, integrity.crc_byte, integrity.crc_kind) == (40, 4, 7, "xor8")
    assert cfg.fixtures[0].legs[0].layout.length == 8


@pytest.mark.parametrize(
    "encoder, words",
    [
        ({"crc": {"offset": 2}}, "encoder.offset"),  # inside the count field
        ({"crc": {"offset": 7, "kind": "crc16"}}, "encoder.crc.kind"),
        ({"counter": {"offset": 30, "bits": 4}}, "encoder.offset"),
        ({"counter": {"offset": 40, "bits": 1}}, "encoder.counter.bits"),
        ({"counter": {"offset": 56}, "crc": {"offset": 7}}, "encoder.crc.offset"),
    ],
)
def test_a_bad_counter_or_crc_is_one_line_naming_the_field(tmp_path, encoder, words):
    with pytest.raises(ConfigError) as exc:
        service_config(tmp_path, [fixture_table(encoder=encoder)])
    assert words in str(exc.value) and len(str(exc.value).splitlines()) == 1


def drive_checked(tmp_path, faults, encoder=CHECKED, sets=300):
    """Sets of the simulated fixture into its cycle; (cycle, records, truth poses by set index)."""
    svc = service_config(tmp_path, [fixture_table(encoder=encoder)])
    sim = sim_config(svc, [{"name": "left", "rate": RATE, "trajectory": "A", "faults": faults}])
    cfg, hexa = svc.fixtures[0], hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 1.0e9)
    bus = CollectingBus()
    simulator = Simulator(svc, sim, bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    leg_of = {leg.can_id: k for k, leg in enumerate(cfg.legs)}
    records, truth = [], []
    for k in range(sets):
        bus.sent.clear()
        truth.append(simulator.send_set(0, k / RATE, stamp=1.0e9 + k / RATE, stall_check=False).pose)
        for m in bus.sent:
            rec = cycle.on_frame(leg_of[m.arbitration_id], bytes(m.data), m.timestamp)
            if rec is not None:
                records.append(rec)
    return cycle, records, truth


def wrong_ok(records, truth):
    """``ok`` records farther than 5 sigma from the truth of the instant they name."""
    wrong = []
    for rec in records:
        if rec.status == "ok":
            dp, _ = pose_error(rec, truth[set_of(rec)])
            if dp > 5 * rec.sigma["translation_mm"] * 1e-3:
                wrong.append((set_of(rec), dp))
    return wrong


def test_one_percent_bit_flips_give_no_wrong_ok_and_name_the_check(tmp_path):
    cycle, records, truth = drive_checked(
        tmp_path, [{"kind": "bit_flip", "probability": 0.01, "start": 0.3, "duration": 60}]
    )
    assert not wrong_ok(records, truth)
    bad = [r for r in records if any(f.startswith("bad_crc:leg") for f in r.flags)]
    assert bad and all(r.status == "bad_frame" and r.pose is None for r in bad)
    assert cycle.counters["bad_crc"] == sum(f.startswith("bad_crc") for r in records for f in r.flags) > 5
    assert cycle.counters["counter_gap"] == 0  # a corrupted frame keeps its place in its leg's sequence
    assert sum(r.status == "ok" for r in records) > 200


@pytest.mark.parametrize("seconds", [0.0002, 0.005])
def test_an_intruder_copying_the_counter_on_a_legs_id_gives_no_wrong_ok(tmp_path, seconds):
    intruder = {"kind": "intruder", "leg": 3, "size": 0.0003, "seconds": seconds, "start": 1.0, "duration": 1.0}
    cycle, records, truth = drive_checked(tmp_path, [intruder])
    assert not wrong_ok(records, truth)
    during = [r for r in records if 101 <= set_of(r) < 200]
    assert during and not any(r.status == "ok" for r in during)
    assert cycle.counters["counter_gap"] > 50
    assert any("counter_gap:leg3" in r.flags for r in during)
    assert sum(r.status == "ok" for r in records if set_of(r) >= 215) > 50  # the leg's sequence resumes


def test_a_lost_frame_costs_its_legs_next_frame_not_more(tmp_path):
    cycle, records, truth = drive_checked(
        tmp_path, [{"kind": "dropped_frames", "leg": 2, "probability": 1.0, "start": 1.0, "duration": 0.005}]
    )
    assert cycle.counters["counter_gap"] == 1
    assert [r.flags for r in records if "counter_gap:leg2" in r.flags] != []
    assert not wrong_ok(records, truth)


def canopen_cycle(tmp_path):
    """A CANopen fixture's cycle behind its link and the bus's SYNC clock (reference hexapod)."""
    from .test_fieldbus import EDS

    cfg = service_config(tmp_path, [fixture_table(encoder={"protocol": "canopen", "eds": str(EDS)})]).fixtures[0]
    hexa = hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 1.0e9)
    clock = SyncClock()
    assert cfg.canopen is not None
    return cfg, cycle, clock, CanopenLink("left", cfg.canopen, cycle.on_frame, clock, cfg.staleness)


def test_canopen_frames_after_two_syncs_are_no_set(tmp_path):
    cfg, cycle, clock, link = canopen_cycle(tmp_path)
    tpdo = [encode(cfg.legs[k].layout, 0)[: cfg.canopen.pdo_length] for k in range(6)]
    records = []
    for n in range(60):
        t = 1.0e9 + n / RATE
        clock.on_sync(0, bytes([n % 240 + 1]), t)
        for k in range(6):
            link.on_heartbeat(k, bytes([0x05]), t)  # operational
            if n == 40 and k == 3:  # a second SYNC 0.5 ms after the first: legs 4-6 follow it
                clock.on_sync(0, bytes([(n + 1) % 240 + 1]), t + 0.0005)
            rec = link.on_pdo(k, tpdo[k], t + 0.0001 * k if n != 40 else t + 0.0006)
            if rec is not None:
                records.append(rec)
    bad = [r for r in records if r.status == "bad_frame"]
    assert len(bad) == 1 and bad[0].pose is None, [(r.status, r.flags) for r in records[-25:]]
    assert sorted(f for f in bad[0].flags if f.startswith("sync_mismatch")) == [
        "sync_mismatch:leg1",
        "sync_mismatch:leg2",
        "sync_mismatch:leg3",
    ] or sorted(f for f in bad[0].flags if f.startswith("sync_mismatch")) == [
        "sync_mismatch:leg4",
        "sync_mismatch:leg5",
        "sync_mismatch:leg6",
    ]
    assert cycle.counters["sync_mismatch"] == 1
    assert not any(r.status == "bad_frame" for r in records[-15:])


DBC_TEXT = """VERSION ""

BU_: ENC

BO_ 385 Encoder: 8 ENC
 SG_ Position : 0|32@1- (1,0) [0|0] "um" Vector__XXX
 SG_ Error : 32|1@1+ (1,0) [0|1] "" Vector__XXX
 SG_ Counter : 40|4@1+ (1,0) [0|15] "" Vector__XXX
 SG_ Checksum : 56|8@1+ (1,0) [0|255] "" Vector__XXX
"""


def test_a_dbc_counter_and_checksum_are_checked_and_a_missing_warning_signal_is_none(tmp_path):
    cantools = pytest.importorskip("cantools")
    dbc = tmp_path / "counted.dbc"
    dbc.write_text(DBC_TEXT)
    encoder = {"protocol": "dbc", "dbc": str(dbc), "counter": "Counter", "crc": "Checksum", "crc_kind": "xor8"}
    layout = service_config(tmp_path, [fixture_table(encoder=encoder)]).fixtures[0].legs[0].layout
    assert layout.warning_bit is None and layout.error_bit == 32
    i = layout.integrity
    assert (i.counter_bit, i.counter_bits, i.crc_byte, i.crc_kind) == (40, 4, 7, "xor8")
    message = cantools.database.load_file(str(dbc)).get_message_by_name("Encoder")
    checks = FrameChecks(i)
    for n in range(20):  # frames as the DBC describes them, the checksum computed by the sender
        data = bytearray(message.encode({"Position": 1000 + n, "Error": 0, "Counter": n % 16, "Checksum": 0}))
        data[7] = checksum("xor8", bytes(data[:7]))
        assert checks.check(0, data) is None and decode(layout, data).position == 1000 + n
    data[0] ^= 0x04
    assert checks.check(0, data) == "bad_crc"
    skipped = bytearray(message.encode({"Position": 5, "Error": 0, "Counter": 7, "Checksum": 0}))
    skipped[7] = checksum("xor8", bytes(skipped[:7]))
    assert checks.check(0, skipped) == "counter_gap"


def test_a_canopen_tpdo_long_after_its_sync_never_joins_the_next_syncs_set(tmp_path):
    cfg, cycle, clock, link = canopen_cycle(tmp_path)
    records = []
    t = 1.0e9
    for n in range(80):
        clock.on_sync(0, b"", t)  # a SYNC without a counter
        tpdo = encode(cfg.legs[0].layout, 10 * n)[: cfg.canopen.pdo_length]  # instant n: count 10 n on every leg
        for k in range(6):
            link.on_heartbeat(k, bytes([0x05]), t)
            stalled = n == 40 and k >= 3  # the sender stalled 60 ms: legs 4-6 come just before the next SYNC
            rec = link.on_pdo(k, tpdo, t + (0.06 if stalled else 0.0001 * k))
            if rec is not None:
                records.append(rec)
        t += 0.0601 if n == 40 else 0.01
    posed = [r for r in records if r.pose is not None]
    assert len(posed) > 40
    assert all(len(set(r.readings)) == 1 for r in posed), [r.readings for r in posed if len(set(r.readings)) > 1][:2]


def test_a_stalled_canopen_sender_never_mixes_two_syncs_instants_without_a_sync_counter(tmp_path):
    cfg, cycle, clock, link = canopen_cycle(tmp_path)
    records = []
    t = 1.0e9
    for n in range(80):
        clock.on_sync(0, b"", t)  # SYNCs without a counter
        tpdo = encode(cfg.legs[0].layout, 10 * n)[: cfg.canopen.pdo_length]  # instant n: count 10 n on every leg
        for k in range(6):
            link.on_heartbeat(k, bytes([0x05]), t)
            if n == 40 and k >= 3:  # legs 4-6's frames of this instant lost
                continue
            if n == 41 and k < 3:  # and legs 1-3's of the next
                continue
            rec = link.on_pdo(k, tpdo, t + 1e-6 * k)
            if rec is not None:
                records.append(rec)
        # after instant 40 the sender had stalled: instant 41 follows 20 us later (stamps cannot separate them)
        t += 2e-5 if n == 40 else 0.01
    posed = [r for r in records if r.pose is not None]
    assert len(posed) > 40
    assert all(len(set(r.readings)) == 1 for r in posed), [r.readings for r in posed if len(set(r.readings)) > 1][:2]
    assert cycle.counters["sync_mismatch"] >= 1
