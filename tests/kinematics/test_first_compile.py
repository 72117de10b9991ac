"""The one line logged before a compiled entry's first compilation."""

from __future__ import annotations

import logging
import subprocess
import sys
import types

from hexapod_model.kinematics.newton import first_compile


class _Entry:
    """A stand-in for a numba dispatcher: its Python function, its compiled signatures, no cache."""

    def __init__(self, name: str, signatures: list, module: str = "hexapod_model.kinematics.newton.iteration"):
        self.py_func = types.SimpleNamespace(__name__=name, __module__=module)
        self.signatures = signatures


def test_announces_a_compilation_once_per_entry(caplog, monkeypatch):
    monkeypatch.setattr(first_compile, "_announced", set())
    with caplog.at_level(logging.INFO, logger=first_compile.LOGGER):
        first_compile.announce(_Entry("solve_schur", []))
        first_compile.announce(_Entry("solve_schur", []))  # the same entry: once
        first_compile.announce(_Entry("forward_rows", ["(float64[:],)"]))  # compiled in this process: silent
    what, seconds = first_compile.ENTRIES["solve_schur"]
    assert caplog.messages == [f"compiling the solver kernels ({what}), once after installation: ~{seconds} s"]


def test_entries_of_one_name_in_two_modules_are_each_announced(caplog, monkeypatch):
    """Two kernels named alike (the pose uncertainty's and another module's ``measure``) are two entries."""
    monkeypatch.setattr(first_compile, "_announced", set())
    monkeypatch.setattr(first_compile, "_cached", lambda d: False)
    with caplog.at_level(logging.INFO, logger=first_compile.LOGGER):
        first_compile.announce(_Entry("measure", [], "hexapod_model.analysis.sensitivity"))
        first_compile.announce(_Entry("measure", [], "hexapod_model.kinematics.other"))
        first_compile.announce(_Entry("measure", [], "hexapod_model.analysis.sensitivity"))  # the first again: once
    assert len(caplog.messages) == 2


def test_the_body_check_announces_its_kernel_before_its_first_call(monkeypatch):
    """The body check's kernel compiles for about 4 s after installation, at the first forward: announced."""
    import numpy as np

    import hexapod_model as hm
    from hexapod_model.kinematics import clearance

    seen: list[str] = []
    monkeypatch.setattr(clearance, "announce", lambda d: seen.append(d.py_func.__name__))
    hexa = hm.Hexapod.from_preset("reference")
    query = clearance.ClearanceQuery(hexa.closed_loop, 0.001)
    q = hexa.closed_loop.q_home
    assert query.check(q) == (None, None) and query.check(q) == (None, None)
    assert seen == ["measure_body"]  # at the first call only: the later ones call its machine code
    assert query(q).distance > 0.001 and seen == ["measure_body"] * 2
    assert "measure_body" in first_compile.ENTRIES
    plain = clearance.ClearanceQuery(hexa.closed_loop, 0.001, compiled=False)  # the NumPy kernel compiles nothing
    plain.check(q)
    assert seen == ["measure_body"] * 2 and np.isfinite(plain(q).distance)


def test_the_proof_state_is_made_without_compiling(monkeypatch):
    """A stream's proof work arrays come from Python: no kernel of a few ``np.zeros`` compiled for it (1.5 s)."""
    import numpy as np

    import hexapod_model as hm
    from hexapod_model.kinematics.newton import krawczyk

    class Refused:
        py_func = staticmethod(krawczyk.enclosure_workspace.py_func)

        def __call__(self, *args):
            raise AssertionError("the compiled workspace called from Python")

    monkeypatch.setattr(krawczyk, "enclosure_workspace", Refused())
    prover = hm.Hexapod.from_preset("reference").engine.prover
    (work, _), _ = prover.new_state().packed
    assert work[6][1].shape == (2, 6, 6, 3, 4) and (work[6][5] == np.eye(6)).all()


def test_a_cached_entry_is_not_announced(caplog, monkeypatch):
    monkeypatch.setattr(first_compile, "_announced", set())
    monkeypatch.setattr(first_compile, "_cached", lambda d: True)
    with caplog.at_level(logging.INFO, logger=first_compile.LOGGER):
        first_compile.announce(_Entry("solve_blocks", []))
    assert caplog.messages == []


class _CountingEntry(_Entry):
    """A stand-in whose signature list counts its reads (numba builds that list anew on each read)."""

    def __init__(self, name: str, signatures: list):
        super().__init__(name, signatures)
        self.reads = 0

    @property  # type: ignore[override]
    def signatures(self) -> list:
        self.reads += 1
        return self._signatures

    @signatures.setter
    def signatures(self, value: list) -> None:
        self._signatures = value


def test_a_ready_entry_is_judged_once(monkeypatch):
    """A compiled entry is checked on its first call only: later calls (every proof, every batch) skip the check."""
    monkeypatch.setattr(first_compile, "_announced", set())
    entry = _CountingEntry("prove_configurations", ["(float64[:],)"])
    for _ in range(5):
        first_compile.announce(entry)
    assert entry.reads == 1


def test_loading_a_hexapod_imports_no_numba():
    """Numba is imported, and the kernels compiled, by the first solve: not by loading a hexapod."""
    code = (
        "import sys\nimport hexapod_model as hm\nh = hm.Hexapod.from_preset('reference')\n"
        "assert h.compiled and h.home_condition_number > 1\nprint('numba' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


_ANNOUNCE = """
import types
from hexapod_model.cli.main import _compile_notes
from hexapod_model.kinematics.newton import first_compile
first_compile._cached = lambda d: False
entry = types.SimpleNamespace(py_func=types.SimpleNamespace(__name__="forward_rows"), signatures=[])
with _compile_notes("fk"):
    first_compile.announce(entry)
"""


def test_the_command_line_shows_the_line_on_a_terminal_only():
    import os
    import pty

    main_fd, terminal = pty.openpty()
    try:
        subprocess.run([sys.executable, "-c", _ANNOUNCE], stderr=terminal, check=True, timeout=120)
        shown = os.read(main_fd, 4096).decode()
    finally:
        os.close(main_fd)
        os.close(terminal)
    what, seconds = first_compile.ENTRIES["forward_rows"]
    assert shown.strip() == f"hexapod fk: compiling the solver kernels ({what}), once after installation: ~{seconds} s"
    piped = subprocess.run([sys.executable, "-c", _ANNOUNCE], capture_output=True, text=True, check=True)
    assert piped.stderr == ""


def test_the_collector_runs_less_while_numba_compiles_and_as_before_after():
    import gc

    from numba import njit
    from numba.core import event

    first_compile.collect_less()
    seen = []

    class Probe(event.Listener):  # registered after collect_less's listener: sees the threshold it set
        def on_start(self, ev):
            seen.append(gc.get_threshold()[0])

        def on_end(self, ev):
            pass

    before = gc.get_threshold()
    with event.install_listener("numba:compile", Probe()):
        assert njit(lambda x: x + 1)(1) == 2  # not cached: compiles
        try:
            njit(lambda x: x.no_such_attribute)(1)  # a compilation that fails
        except Exception:
            pass
    assert seen == [max(before[0], first_compile.COMPILING_GC_THRESHOLD)] * 2
    assert gc.get_threshold() == before


_PLAIN_SCRIPT = """
import types
from hexapod_model.kinematics.newton import first_compile
first_compile._cached = lambda d: False
for name in ("solve_schur", "follow"):  # two entries: one warning
    first_compile.announce(types.SimpleNamespace(py_func=types.SimpleNamespace(__name__=name), signatures=[]))
"""


def test_a_plain_script_sees_one_compile_warning_on_stderr():
    """No logging configured: the first compilation of a process is said once, as a CompileWarning."""
    import hexapod_model as hm

    out = subprocess.run([sys.executable, "-c", _PLAIN_SCRIPT], capture_output=True, text=True, check=True)
    what, seconds = first_compile.ENTRIES["solve_schur"]
    lines = [line for line in out.stderr.splitlines() if "CompileWarning" in line]
    assert (
        len(lines) == 1 and f"compiling the solver kernels ({what}), once after installation: ~{seconds} s" in lines[0]
    )
    assert issubclass(hm.CompileWarning, hm.HexapodWarning) and issubclass(hm.HexapodWarning, UserWarning)


def test_the_tracker_and_the_pose_uncertainty_announce_their_kernels_before_their_first_calls(monkeypatch):
    """A tracker's construction compiles the pose uncertainty's kernels (about 5 s after installation), its
    predictor's, its stuck test's, its reading statistics' and its histories' (each about a second on a
    slower machine); its first solved sample the uncertainty of a solve (about 3 s): each is announced first."""
    import hexapod_model as hm
    from hexapod_model.analysis import sensitivity
    from hexapod_model.tracking import kernels, tracker

    seen: list[str] = []
    monkeypatch.setattr(sensitivity, "announce", lambda d: seen.append(d.py_func.__name__))
    monkeypatch.setattr(tracker, "announce", lambda d: seen.append(d.py_func.__name__))
    hexa = hm.Hexapod.from_preset("reference")
    stream = tracker.Tracker(hexa)
    made = ["measure", "predict_into", "stuck_checks", "begin_sample", "push_trusted"]
    assert seen == made
    for _ in range(3):
        stream.step(hexa.closed_loop.q_home[hexa.closed_loop.prismatic_q])
    assert seen == [*made, "measure_solved"]  # once, at its first call
    assert set(seen) <= set(first_compile.ENTRIES) and kernels.stuck_checks.py_func.__name__ == "stuck_checks"


def test_the_tracker_announces_its_branch_check_before_its_first_call(monkeypatch):
    """The branch check's kernel (about 1 s after installation) runs once the tracker has settled: announced."""

    import hexapod_model as hm
    from hexapod_model.tracking import tracker

    seen: list[str] = []
    monkeypatch.setattr(tracker, "announce", lambda d: seen.append(d.py_func.__name__))
    hexa = hm.Hexapod.from_preset("reference")
    stream = tracker.Tracker(hexa)
    home = hexa.closed_loop.q_home[hexa.closed_loop.prismatic_q]
    results = [stream.step(home + 1e-6 * k) for k in range(stream.settings.settle_samples + 3)]
    assert results[-1].status == "ok" and "settling" not in results[-1].flags
    assert seen.count("branch_residual") == 1 and "branch_residual" in first_compile.ENTRIES


def test_a_first_inverse_is_announced_before_its_pose_is_checked_and_converted(monkeypatch):
    """An inverse's first call after installation compiles the pose's check and conversion (about a second
    on a slower machine) before its solver's entry: the line comes before both."""
    import hexapod_model as hm
    from hexapod_model.kinematics import joint_space
    from hexapod_model.kinematics.newton import compiled

    seen: list[str] = []
    monkeypatch.setattr(compiled, "announce", lambda d: seen.append(d.py_func.__name__))
    set_pose = joint_space.JointSpace.set_pose

    def recorded(self, q, pose):
        seen.append("set_pose")
        set_pose(self, q, pose)

    monkeypatch.setattr(joint_space.JointSpace, "set_pose", recorded)
    hexa = hm.Hexapod.from_preset("reference")
    assert hexa.inverse(hexa.home_pose).converged
    assert seen.index("solve_blocks") < seen.index("set_pose")
