"""The service compiles every kernel a reading set may run before it reads the bus.

After installation (an empty numba cache) each kernel a reading set runs is compiled at its
first call, for seconds to minutes. The test watches the kernels' first calls instead: each
compiled entry point gets its machine code (``Dispatcher.add_overload``) at its first call with
a signature, compiled or loaded from numba's cache alike. One that gets it after the service
started reading is a kernel the preparation missed: with an empty cache, a compile while
frames queue. So the test runs with the cache as it is, and takes seconds instead of the
minutes an empty cache's compile takes.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent(
    """
    import json, sys, time
    from pathlib import Path

    import can
    import numpy as np
    from numba.core.dispatcher import Dispatcher

    from hexapod_model.kinematics.hexapod import Hexapod
    from hexapod_model.lie import matrix_to_rpy, quaternion_of_matrix, xyz_rpy_to_pose
    from hexapod_model.service import FixtureService, Simulator, config_from_dict, geometry_hash, simulation_from_dict
    from hexapod_model.service.store.fixture_store import LockEvent, Store

    folder = Path(sys.argv[1])
    config = config_from_dict(
        {
            "bus": {"interface": "virtual", "channel": "compile-first"},
            "store": {"path": str(folder / "store.sqlite")},
            "http": {"host": "127.0.0.1", "port": 0},
            "fixtures": [{"name": "left", "hexapod": "reference", "can_ids": [0x181 + k for k in range(6)]}],
        },
        "test.toml",
        folder,
    )
    hexa = Hexapod.load("reference")
    home = hexa.home_pose
    store = Store(config.store.path)  # the lock pose stored before a restart: home
    store.add_lock(
        LockEvent("left", 1.0, home[:3, 3].copy(), np.array(quaternion_of_matrix(home[:3, :3])), np.zeros(6), "ok",
                  geometry_hash(hexa), hexa.q_home.copy())
    )
    store.close()
    moved = home @ xyz_rpy_to_pose([0.0, 0.0, 0.05, 0.0, 0.0, 45.0])  # the plate moved while the service was off
    hold = [*moved[:3, 3], *np.degrees(matrix_to_rpy(moved[:3, :3]))]
    sim = simulation_from_dict({"fixtures": [{"name": "left", "rate": 100.0, "noise": 2e-6, "hold": hold}]}, config)
    records = []
    service = FixtureService(config, hexapods={"left": hexa}, http=False)
    service.subscribe(records.append)
    service.start()  # returns once prepared: every kernel compiled (or loaded from the cache)
    compiled = []  # the entry points that get their machine code from here on (compiled or loaded)
    add_overload = Dispatcher.add_overload

    def watched(self, cres):
        compiled.append(f"{self.py_func.__module__}.{self.py_func.__qualname__}")
        return add_overload(self, cres)

    Dispatcher.add_overload = watched
    bus = can.Bus(interface="virtual", channel="compile-first", preserve_timestamps=True)
    try:
        Simulator(config, sim, bus, hexapods={"left": hexa}).run(1.5)
        time.sleep(0.3)
    finally:
        service.stop()
        bus.shutdown()
    print(json.dumps({"compiled": compiled, "poses": sum(r.pose is not None for r in records)}))
    """
)


def test_a_restart_with_the_plate_moved_compiles_nothing_while_reading(tmp_path):
    script = tmp_path / "serve.py"
    script.write_text(SCRIPT)
    run = subprocess.run([sys.executable, str(script), str(tmp_path)], capture_output=True, text=True, timeout=1800)
    assert run.returncode == 0, run.stderr[-3000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out["compiled"] == [], out["compiled"]  # every kernel was compiled before the first frame was read
    assert out["poses"] > 50
