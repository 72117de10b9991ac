"""The bus as the field has it, through one fixture's cycle: lost sets, glitches, repeated frames, skewed stamps.

Rate 100 Hz, trajectory A, reading noise 10 um. None of these is a step or a swap the data show,
so none may latch a fault that waits for a person's acknowledgement, and no record may be
stamped ahead of the frames it is made of.
"""

from __future__ import annotations

import numpy as np
import pytest

from hexapod_model.service import FixtureCycle, Simulator, geometry_hash

from ..conftest import hexapod
from .helpers import CollectingBus, fixture_table, pose_error, service_config, sim_config
from .test_cell import HOLD
from .test_cycle import RATE, check_ok_poses, set_of


def deliver(tmp_path, sets, transform, faults=(), seed=3, truth=None, **fixture):
    """Drive a cycle set by set; ``transform(k, frames) -> frames`` edits each set's ``(leg, data, t)`` list.

    ``truth``: a list that receives every sent set, in order; ``fixture``: more fields of the fixture's table.
    """
    svc = service_config(tmp_path, [fixture_table(**fixture)])
    sim = sim_config(svc, [{"name": "left", "rate": RATE, "trajectory": "A", "faults": list(faults)}], seed=seed)
    cfg, hexa = svc.fixtures[0], hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 1.0e9)
    bus = CollectingBus()
    simulator = Simulator(svc, sim, bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    leg_of = {leg.can_id: k for k, leg in enumerate(cfg.legs)}
    out = []
    for k in range(sets):
        bus.sent.clear()
        sent = simulator.send_set(0, k / RATE, stamp=1.0e9 + k / RATE, stall_check=False)
        if truth is not None:
            truth.append(sent)
        frames = [(leg_of[m.arbitration_id], bytes(m.data), m.timestamp) for m in bus.sent]
        for leg, data, t in transform(k, frames):
            rec = cycle.on_frame(leg, data, t)
            if rec is not None:
                out.append((sent, rec))
    return cycle, out


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
def test_thirty_percent_of_sets_lost_at_random_latch_nothing(tmp_path, seed):
    rng = np.random.default_rng(seed)
    lost = rng.random(400) < 0.3
    cycle, out = deliver(tmp_path, 400, lambda k, frames: [] if lost[k] and k > 20 else frames, seed=seed)
    assert cycle.fault is None, cycle.fault
    check_ok_poses(out)


def test_most_sets_lost_keep_the_frame_period_and_latch_nothing(tmp_path):
    # a sender that loses most sets (85 %: a busy machine): the intervals between a leg's frames are mostly
    # two or more periods, which must not become the period (it merged two instants into one set, a duplicate
    # frame on every leg, and numbered the instants wrong, a step on the moving legs)
    lost = np.random.default_rng(3).random(1500) < 0.85
    cycle, out = deliver(tmp_path, 1500, lambda k, frames: [] if lost[k] and k > 20 else frames, seed=3)
    assert cycle.fault is None, cycle.fault
    assert not any(rec.status == "duplicate_frame" for _, rec in out)
    assert cycle.counters["duplicate_frames"] == 0
    check_ok_poses(out)


def test_two_consecutive_one_frame_glitches_on_one_leg_latch_nothing(tmp_path):
    faults = [
        {"kind": "spike", "leg": 4, "start": 1.0, "size": 0.002},
        {"kind": "spike", "leg": 4, "start": 1.01, "size": -0.0015},
    ]
    cycle, out = deliver(tmp_path, 250, lambda k, frames: frames, faults)
    assert cycle.fault is None, cycle.fault
    assert all(rec.status == "ok" for _, rec in out if set_of(rec) >= 130)
    check_ok_poses(out)


def test_every_frame_repeated_ten_times_latches_nothing(tmp_path):
    cycle, out = deliver(tmp_path, 250, lambda k, frames: [f for f in frames for _ in range(10)])
    assert cycle.fault is None, cycle.fault
    assert cycle.counters["repeated_frames"] == 9 * 6 * 250 and cycle.counters["duplicate_frames"] == 0
    check_ok_poses(out)


def test_a_leg_stamped_50_ms_ahead_is_named_and_no_record_runs_ahead(tmp_path):
    def ahead(k, frames):
        return [(leg, data, t + (0.05 if leg == 3 and k >= 100 else 0.0)) for leg, data, t in frames]

    cycle, out = deliver(tmp_path, 250, ahead)
    assert cycle.fault is None, cycle.fault
    times = [rec.t for _, rec in out]
    assert all(b >= a for a, b in zip(times, times[1:])), "record times ran backwards"
    assert all(rec.t <= sent.t_last + 1e-9 for sent, rec in out), "a record stamped ahead of its frames"
    later = [rec for _, rec in out if set_of(rec) >= 101]
    assert later and all(rec.status != "ok" for rec in later)
    for rec in later:
        named = {f.split(":")[1] for f in rec.flags if ":leg" in f}
        assert named == {"leg4"}, rec.flags
    check_ok_poses(out)


def gateway(order=None):
    """A ``deliver`` transform: five sets held, then delivered with the stamp of the burst's last frame.

    ``order(frames) -> frames``: how the gateway orders a burst (default: as received).
    """
    burst: list = []

    def batch(k, frames):
        burst.extend(frames)
        if k % 5 != 4:
            return []
        stamp = frames[-1][2]
        out = [(leg, data, stamp) for leg, data, _ in burst]
        burst.clear()
        return out if order is None else order(out)

    return batch


def wrong_ok(out, truth):
    """``ok`` records farther than 5 sigma from the truth of the instant their ``t`` names."""
    wrong = []
    for _, rec in out:
        if rec.status == "ok":
            dp, _ = pose_error(rec, truth[set_of(rec)].pose)
            if dp > 5 * rec.sigma["translation_mm"] * 1e-3:
                wrong.append((set_of(rec), dp))
    return wrong


PERIOD = {"encoder": {"sample_period": 1.0 / RATE}}  # the encoders' sampling period, given


def test_a_gateway_stamping_five_instants_with_one_time_in_order_gives_their_poses(tmp_path):
    truth: list = []
    cycle, out = deliver(tmp_path, 300, gateway(), truth=truth, **PERIOD)
    assert not wrong_ok(out, truth)
    ok = [set_of(rec) for _, rec in out if rec.status == "ok"]
    assert len(ok) > 250 and len(set(ok)) == len(ok), "one record per instant, dated at its instant"
    times = [rec.t for _, rec in out]
    assert all(b >= a for a, b in zip(times, times[1:])), "record times ran backwards"
    assert cycle.fault is None, cycle.fault
    check_ok_poses([(truth[set_of(rec)], rec) for _, rec in out])


def test_without_the_sampling_period_a_gateways_bursts_give_flagged_poses_of_their_instants(tmp_path):
    truth: list = []
    cycle, out = deliver(tmp_path, 300, gateway(), truth=truth)
    assert not any(rec.status == "ok" for _, rec in out)
    posed = [(truth[set_of(rec)], rec) for _, rec in out if rec.pose is not None and "batched_stamps" in rec.flags]
    assert len(posed) > 200
    for sent, rec in posed:  # right for the instant its t names
        dp, _ = pose_error(rec, sent.pose)
        assert dp < 5 * rec.sigma["translation_mm"] * 1e-3 or "jump" in rec.flags or "settling" in rec.flags


def test_a_gateway_that_stops_batching_leaves_burst_mode(tmp_path):
    batch = gateway()
    truth: list = []
    cycle, out = deliver(tmp_path, 300, lambda k, frames: batch(k, frames) if k < 150 else frames, truth=truth)
    assert not wrong_ok(out, truth)
    later = [rec for _, rec in out if set_of(rec) >= 175]
    assert len(later) > 120 and all(rec.status == "ok" and rec.flags == [] for rec in later), later[:3]


@pytest.mark.parametrize("fault", ["reordered", "frame_lost", "instant_lost"])
def test_a_gateway_burst_that_cannot_be_split_into_instants_gives_no_pose(tmp_path, fault):
    rng = np.random.default_rng(7)

    def order(frames):
        if fault == "reordered":
            return [frames[i] for i in rng.permutation(len(frames))]
        if fault == "frame_lost":
            return frames[:9] + frames[10:]
        return frames[:12] + frames[18:]  # the third instant of every burst lost

    truth: list = []
    cycle, out = deliver(tmp_path, 300, gateway(order), truth=truth, **PERIOD)
    assert not any(rec.status == "ok" for _, rec in out), [rec.flags for _, rec in out if rec.status == "ok"][:3]
    assert not any(rec.pose is not None for _, rec in out[10:])
    assert sum("batched_stamps" in rec.flags for _, rec in out) > 50


def test_a_frame_of_the_instant_arriving_after_the_next_instant_began_names_no_healthy_leg(tmp_path):
    pending: list = []

    def leg6_after_next_leg1(k, frames):  # leg 6's frame (its own stamp) arrives after the next set's first
        if k < 100:
            return frames
        before = pending[:]
        pending[:] = [f for f in frames if f[0] == 5]
        return [frames[0], *before, *[f for f in frames[1:] if f[0] != 5]]

    truth: list = []
    cycle, out = deliver(tmp_path, 250, leg6_after_next_leg1, truth=truth)
    named = {f for _, rec in out if set_of(rec) >= 101 for f in rec.flags if ":leg" in f}
    assert not any(f.startswith("ahead:") for f in named), named
    assert cycle.counters["ahead_frames"] == 0
    check_ok_poses([(truth[set_of(rec)], rec) for _, rec in out])


def test_a_leg_at_rest_sending_equal_frames_each_period_is_no_repeat_with_a_skew_of_one_period(tmp_path):
    svc = service_config(tmp_path, [fixture_table(max_skew=0.01)])  # free-running encoders: one period
    sim = sim_config(svc, [{"name": "left", "rate": RATE, "hold": HOLD, "noise": 0.0}])
    cfg, hexa = svc.fixtures[0], hexapod("reference")
    cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), None, 1.0e9)
    bus = CollectingBus()
    simulator = Simulator(svc, sim, bus, hexapods={"left": hexa})  # type: ignore[arg-type]
    leg_of = {leg.can_id: k for k, leg in enumerate(cfg.legs)}
    records = []
    for k in range(100):
        bus.sent.clear()
        simulator.send_set(0, k / RATE, stamp=1.0e9 + k / RATE, stall_check=False)
        for m in bus.sent:
            rec = cycle.on_frame(leg_of[m.arbitration_id], bytes(m.data), m.timestamp)
            if rec is not None:
                records.append(rec)
    assert cycle.counters["repeated_frames"] == 0
    assert len(records) >= 99 and all(r.status != "incomplete" for r in records)
