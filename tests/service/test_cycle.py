"""One fixture's cycle fed by simulated encoders, set by set: poses, injected faults, locks, recovery.

Rate 100 Hz, trajectory A, reading noise 10 um, staleness 0.05 s (5 sets). Stated latencies:
an error bit, a stuck leg, a bad reading and a spike are reported on the first affected set,
a silent leg after the staleness window (at most 6 sets); poses are clean again at most
2 sets after a fault ends (a spike: after confirm_samples + 3 sets).
"""

from __future__ import annotations

import numpy as np
import pytest

from hexapod_model.service import RECORD_KEYS, FixtureCycle, LockEvent, geometry_hash
from hexapod_model.service.cycle.fixture_cycle import _quaternion
from hexapod_model.tracking.reading_tests import TrackerSettings

from ..conftest import hexapod
from .helpers import drive, fixture_table, pose_error, service_config, sim_config

RATE = 100.0
SETTLE = TrackerSettings().settle_samples  # the tracker's first samples are flagged `settling`
SIGMAS = 5.0  # an ok pose is within 5 sigma (sigma is the RMS error length) of the truth


def run(tmp_path, faults=(), seconds=2.5, fixture=None, **sim):
    svc = service_config(tmp_path, [fixture or fixture_table()])
    spec = {"name": "left", "rate": RATE, "trajectory": "A", "faults": list(faults), **sim}
    return drive(svc, sim_config(svc, [spec]), seconds)


def check_ok_poses(out):
    """Every ok record is within SIGMAS of the truth; returns (errors / sigma) for the statistics."""
    ratios = []
    for sent, rec in out:
        if rec.status != "ok":
            continue
        dp, dr = pose_error(rec, sent.pose)
        sig = rec.sigma
        ratios.append((dp / (sig["translation_mm"] * 1e-3), dr / np.radians(sig["rotation_deg"])))
    r = np.array(ratios)
    assert len(r) and r.max() < SIGMAS, r.max(0)
    return r


def set_of(rec, t0=1.0e9):
    """The index of the set a record is about (drive() stamps set k at t0 + k / RATE + frame spacing)."""
    return round((rec.t - t0) * RATE)


def statuses(out, t0, t1):
    return [(set_of(rec), rec.status, rec.flags) for _, rec in out if t0 <= set_of(rec) / RATE < t1]


def test_clean_stream_every_set_ok_within_the_noise_propagated_sigma(tmp_path):
    _, out = run(tmp_path, seconds=3.0)
    assert all(rec.status == "flagged" and rec.flags == ["settling"] for _, rec in out[:SETTLE])
    assert len(out) == 300 and all(rec.status == "ok" and rec.flags == [] for _, rec in out[SETTLE:])
    assert all(tuple(rec.to_dict()) == RECORD_KEYS for _, rec in out)
    r = check_ok_poses(out)
    # sigma is the RMS error: the mean squared ratio is 1 when sigma is right (300 samples: +-20 %)
    assert 0.6 < np.mean(r[:, 0] ** 2) < 1.5 and 0.6 < np.mean(r[:, 1] ** 2) < 1.5
    rec = out[-1][1]
    assert rec.state == "moving" and rec.stored is False and rec.iterations >= 1
    assert 0.1 < rec.singularity_margin < 10 and len(rec.readings) == 6
    assert np.allclose(rec.readings, out[-1][0].readings, atol=6e-5)


def test_a_plate_held_far_from_home_gives_ok_poses_after_settling(tmp_path):
    """A fixture at rest 5 cm off home, tilted by about 20 degrees both ways: every set after the first ones is ok.

    (A second set predicted by extrapolating from home, where the tracker starts, to the first set
    leads Newton beyond the joint limits, and the tracker would keep that configuration: every
    later record flagged or not_converged.)
    """
    svc = service_config(tmp_path, [fixture_table()])
    spec = {"name": "left", "rate": RATE, "hold": [-0.0226, -0.0493, 0.4146, -21.2, 23.1, 2.0]}  # m, deg
    _, out = drive(svc, sim_config(svc, [spec]), 1.0)
    assert len(out) == 100 and all(rec.flags == ["settling"] for _, rec in out[:SETTLE])
    assert [(rec.status, rec.flags) for _, rec in out[SETTLE:] if rec.status != "ok" or rec.flags] == []
    check_ok_poses(out)


@pytest.mark.parametrize(
    "fault,status,flag,first,last",
    [
        (
            {"kind": "error_bit", "leg": 3, "start": 1.0, "duration": 0.2},
            "encoder_error",
            "encoder_error:leg3",
            100,
            119,
        ),
        # the tracker doubts the repeats at once (flagged); stuck_leg from the third repeat on
        ({"kind": "stuck_leg", "leg": 4, "start": 1.0, "duration": 0.3}, "stuck_leg", "stuck:leg4", 103, 129),
        # incomplete sets name the missing leg at once, silent_leg once its last frame is stale (5 sets)
        ({"kind": "silent_leg", "leg": 2, "start": 1.0, "duration": 0.3}, "incomplete", "missing:leg2", 100, 129),
        ({"kind": "spike", "leg": 5, "start": 1.0, "size": 0.002}, "flagged", "jump", 100, 100),
    ],
)
def test_each_fault_gives_its_status_in_time_and_clean_poses_after(tmp_path, fault, status, flag, first, last):
    _, out = run(tmp_path, [fault])
    bad = [(k, s, f) for k, s, f in statuses(out, SETTLE / RATE, 9) if s != "ok"]
    assert bad, "the fault went unnoticed"
    if fault["kind"] == "stuck_leg":  # the tracker doubts the first repeats at once: the frozen leg leaves the
        # predicted motion (jump); its own stuck rule, knowing 1 um counts repeat by chance, needs a longer run
        assert [(k, s) for k, s, _ in bad[:2]] == [(101, "flagged"), (102, "flagged")]
        assert {"jump", "stuck"} & set(bad[0][2]), bad[0]
        bad = bad[2:]
    assert bad[0][0] == first and bad[0][1] == status and flag in bad[0][2]
    if fault["kind"] == "spike":  # the spike, the jump back, then the doubt until the branch is confirmed
        assert bad[-1][0] <= 100 + 3 + 5 and {s for _, s, _ in bad} == {"flagged"}
    else:  # the fault's sets, then at most SETTLE sets while the tracker re-anchors after the gap
        fault_sets = [(k, s, f) for k, s, f in bad if s != "flagged"]
        assert [k for k, _, _ in fault_sets] == list(range(first, last + 1))
        if status == "incomplete":
            n = sum(s == "incomplete" for _, s, _ in fault_sets)  # until leg 2's last frame is 0.05 s old
            assert 4 <= n <= 5 and [s for _, s, _ in fault_sets] == ["incomplete"] * n + ["silent_leg"] * (30 - n)
            assert all("missing:leg2" in f if s == "incomplete" else "silent:leg2" in f for _, s, f in fault_sets)
        else:
            assert all(s == status and flag in f for _, s, f in fault_sets)
        settling = [k for k, s, f in bad if s == "flagged"]
        assert all(f == ["settling"] for _, s, f in bad if s == "flagged")
        assert len(settling) <= SETTLE and settling == list(range(settling[0], settling[0] + len(settling)))
        assert not settling or last <= settling[0] <= last + 1
    for k, s, _ in bad:
        if s != "flagged":
            rec = next(r for _, r in out if set_of(r) == k)
            assert rec.pose is None and rec.sigma is None  # never a pose with a failure
    after = statuses(out, (bad[-1][0] + 1) / RATE, 9)
    assert after and all(s == "ok" for _, s, _ in after)
    check_ok_poses(out)


def test_dropped_frames_never_mix_sampling_instants(tmp_path):
    fault = {"kind": "dropped_frames", "start": 0.5, "duration": 1.5, "probability": 0.1}
    _, out = run(tmp_path, [fault])
    during = [rec for _, rec in out if 0.5 <= set_of(rec) / RATE < 2.0]
    assert len(during) == 150  # every instant ends in a record: about 0.9^6 of them complete
    assert {rec.status for rec in during} <= {"ok", "flagged", "silent_leg", "incomplete"}
    missing = [rec for rec in during if rec.status == "incomplete"]
    assert 30 < len(missing) < 100 and all(any(f.startswith("missing:leg") for f in r.flags) for r in missing)
    complete = [rec for rec in during if rec.pose is not None]
    assert sum(rec.status == "ok" for rec in complete) > len(complete) / 2  # gaps flag a few sets, not all
    check_ok_poses(out)  # a set mixing two instants would be off by one set's motion: ~20 sigma


def test_warning_bit_is_reported_on_a_good_pose(tmp_path):
    _, out = run(tmp_path, [{"kind": "warning_bit", "leg": 1, "start": 1.0, "duration": 0.1}])
    warned = statuses(out, 1.0, 1.1)
    assert len(warned) == 10 and all(s == "ok" and f == ["encoder_warning:leg1"] for _, s, f in warned)


def test_out_of_stroke_reading_names_the_leg(tmp_path):
    _, out = run(tmp_path, [{"kind": "spike", "leg": 6, "start": 1.0, "size": 0.3}], seconds=1.5)
    k, s, f = statuses(out, 1.0, 1.01)[0]
    assert s == "out_of_stroke" and f == ["out_of_stroke:leg6"]


def test_lock_phases_lock_store_and_release(tmp_path):
    fixture = fixture_table(lock_time=0.3)
    cycle, out = run(tmp_path, seconds=5.0, fixture=fixture, move=1.5, lock=1.0, ramp=0.3)
    states = [(s.t_sim, rec.state, rec.stored) for s, rec in out]
    locked = [t for t, st, _ in states if st == "locked"]
    # still from 1.5 s to 2.5 s (and 4.0 s to 5.0 s): locked 0.3 s after the plate stopped
    assert 1.75 <= locked[0] <= 1.95 and all(st == "locked" for t, st, _ in states if 1.95 <= t < 2.5)
    assert all(st == "moving" for t, st, _ in states if 2.6 <= t < 4.0)
    # the record that locks is published before its commit; drive() commits right after it
    first_locked = {k for k in range(1, len(states)) if states[k][1] == "locked" and states[k - 1][1] != "locked"}
    assert len(first_locked) == 2
    assert all(stored == (st == "locked" and k not in first_locked) for k, (_, st, stored) in enumerate(states))
    assert all(rec.status == "ok" for _, rec in out[SETTLE:])
    check_ok_poses(out)


def test_recovery_without_motion_is_locked_and_stored_from_the_first_pose(tmp_path):
    hold = {"hold": [0.01, -0.02, 0.41, 5.0, -3.0, 10.0]}
    svc = service_config(tmp_path, [fixture_table(lock_time=0.2)])
    sim = sim_config(svc, [{"name": "left", "rate": RATE, **hold}])
    first, _ = drive(svc, sim, 0.5)
    ref = first.lock.reference  # the lock the first run took, as the store would return it
    sol = first.solver.solve_once(ref, first.hexa.q_home)
    lock = LockEvent("left", 1.0, sol.pose[:3, 3], _quaternion(sol.pose[:3, :3]), ref, "ok", first.geometry_hash, sol.q)
    cycle, out = drive(svc, sim, 0.2, recovered=lock, t0=2.0e9)
    assert cycle.recovered is lock and "initial guess" in cycle.recovery
    # locked and stored from the first pose the tracker checks (the first SETTLE are `settling`)
    assert all(rec.flags == ["settling"] and not rec.stored for _, rec in out[:SETTLE])
    assert all(rec.state == "locked" and rec.stored and rec.status == "ok" for _, rec in out[SETTLE:])
    assert all("moved_while_off" not in rec.flags for _, rec in out)
    moved = sim_config(svc, [{"name": "left", "rate": RATE, "hold": [0.015, -0.02, 0.41, 5.0, -3.0, 10.0]}])
    cycle, out = drive(svc, moved, 0.6, recovered=lock, t0=3.0e9)
    first_ok = out[SETTLE][1]
    assert "moved_while_off" in first_ok.flags and first_ok.status == "ok" and not first_ok.stored
    relocked = [rec for _, rec in out if rec.stored]
    assert relocked and all("moved_while_off" not in rec.flags for rec in relocked[1:])
    other = type(lock)(**{**lock.__dict__, "geometry_hash": "0" * 64})
    cycle, out = drive(svc, sim, 0.1, recovered=other, t0=4.0e9)
    assert cycle.recovered is None and "another geometry" in cycle.recovery
    assert all("stored_geometry_changed" in rec.flags for _, rec in out)
    assert all(rec.status == "ok" for _, rec in out[SETTLE:])


def test_one_leg_creeping_while_locked_is_an_alarm_naming_it_until_acknowledged(tmp_path, caplog):
    svc = service_config(tmp_path, [fixture_table(lock_time=0.2)])
    cfg = svc.fixtures[0]
    hexa = hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 0.0)
    held = hexa.forward([0.01, -0.01, 0.02, 0.0, 0.005, -0.004]).lengths
    rng = np.random.default_rng(2)
    out = []
    with caplog.at_level("WARNING", logger="hexapod_model.service"):
        for k in range(260):  # still 0.5 s, then leg 1 creeps 1 um per set (below the band) for 50 um
            r = held + rng.normal(0, 10e-6, 6)
            r[0] += 1e-6 * min(max(0, k - 50), 50)
            if k == 150:
                ack = cycle.acknowledge("operator", "test")
                assert ack is not None and ack.fault.legs == (0,)
            for leg, codec in enumerate(cfg.legs):
                rec = cycle.on_frame(leg, codec.message(float(r[leg])).data, 1.0 + k / RATE)
            out.append(rec)
    drifting = [k for k, rec in enumerate(out) if "drift:leg1" in rec.flags]
    assert drifting and out[drifting[0]].state == "locked" and out[drifting[0]].status != "ok"
    assert 50 + 25 <= drifting[0] <= 50 + 80  # 3 sigma = 30 um of creep, plus the average's lag
    assert all("drift:leg1" == f for rec in out[drifting[0] :] for f in rec.flags if f.startswith("drift"))
    # latched: nothing ok until the acknowledgement (set 150), then a new lock from the readings as they are
    assert all(rec.status != "ok" for rec in out[drifting[0] : 150])
    assert all("moved_while_locked:leg1" in rec.flags for rec in out[drifting[0] : 150])
    assert out[150].state == "moving" and cycle.fault is None and cycle.acknowledged is ack
    assert all(rec.status == "ok" and rec.flags == [] for rec in out[151:])
    assert out[-1].state == "locked"
    assert sum("drift" in m for m in caplog.messages) == 1
    assert any("acknowledged by operator" in m for m in caplog.messages)
