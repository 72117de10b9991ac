"""The bus as the field has it, through ``hexapod serve --simulate`` as a user runs it: no false latch, no wrong name.

Trajectory A with lock phases (3 s of motion, 2 s still, ramps of 0.3 s) at 100 sets/s, as the
example ``sim.toml`` plays it, with the package's simulated faults: 30 % of whole sets lost, two
consecutive one-frame glitches on one leg, every frame repeated ten times, one leg stamped
50 ms ahead. None is a step or a swap the data show: no record may wait for an acknowledgement,
and no record may be dated before the one published ahead of it.
"""

from __future__ import annotations

import json

import pytest

from .helpers import kernels_ready

MOTION = 'trajectory = "A"\nscale = 0.01\nperiod = 8.0\nmove = 3.0\nlock = 2.0\nramp = 0.3\n'
FAULTS = {
    "lost_sets": 'kind = "lost_sets"\nprobability = 0.3\nstart = 0.5\nduration = 60\n',
    "glitches": 'kind = "spike"\nleg = 4\nstart = 1.0\nsize = 0.002\n[[fixtures.faults]]\n'
    'kind = "spike"\nleg = 4\nstart = 1.01\nsize = -0.0015\n',
    "repeated_frames": 'kind = "repeated_frames"\nsets = 10\nstart = 0.5\nduration = 60\n',
    "ahead_stamp": 'kind = "ahead_stamp"\nleg = 4\nseconds = 0.05\nstart = 1.0\nduration = 60\n',
}


@pytest.mark.parametrize("fault", sorted(FAULTS))
def test_hexapod_serve_simulated_faults_of_the_bus_latch_nothing_and_name_no_healthy_leg(tmp_path, capsys, fault):
    from hexapod_model.cli.main import main

    from ..cli.test_service_cli import write_config, write_sim

    cfg = write_config(tmp_path, fixtures=[("left", "reference", [0x181 + k for k in range(6)], "staleness = 0.05\n")])
    body = f'[[fixtures]]\nname = "left"\nrate = 100.0\n{MOTION}[[fixtures.faults]]\n{FAULTS[fault]}'
    sim = write_sim(tmp_path, body)
    kernels_ready()  # the run's seconds serve: none go to compiling
    assert main(["serve", str(cfg), "--simulate", str(sim), "--jsonl", "--duration", "6"]) == 0
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines() if line.startswith("{")]
    assert len(records) > 150
    assert not [r for r in records if r["status"] == "unacknowledged_fault"], next(
        r["flags"] for r in records if r["status"] == "unacknowledged_fault"
    )
    times = [r["t"] for r in records]
    assert all(b >= a for a, b in zip(times, times[1:])), "record times ran backwards"
    if fault == "ahead_stamp":
        later = [r for r in records if r["t"] >= records[0]["t"] + 1.2 and r["status"] != "silent_leg"]
        assert later and not any(r["status"] == "ok" for r in later)
        for r in later:  # (silent_leg: the simulator's own thread lost sets on a busy machine)
            assert {f.split(":")[1] for f in r["flags"] if ":leg" in f} == {"leg4"}, r["flags"]
    else:
        assert sum(r["status"] == "ok" for r in records) > 100
