"""fixture.toml and sim.toml: validated, every error naming its field, relative paths, examples load."""

from __future__ import annotations

from pathlib import Path

import pytest

from hexapod_model.service import ConfigError, load_config, load_simulation

from .helpers import IDS, fixture_table, service_config, sim_config

ROOT = Path(__file__).resolve().parents[2]


def test_the_examples_load_with_our_defaults():
    cfg = load_config(ROOT / "docs/examples/fixture.toml")
    assert cfg.http.host == "127.0.0.1" and cfg.bus.interface == "virtual"
    assert cfg.store.path == ROOT / "docs/examples/fixture.sqlite"  # relative to the file
    left, right = cfg.fixtures
    assert [leg.can_id for leg in left.legs] == IDS[0] and right.legs[3].home_count == 100_000
    assert (
        left.noise == 10e-6 and left.steady_band == pytest.approx(100e-6) and left.drift_limit == pytest.approx(30e-6)
    )
    sim = load_simulation(ROOT / "docs/examples/sim.toml", cfg)
    assert [s.name for s in sim.fixtures] == ["left", "right"] and sim.fixtures[0].faults[0].legs == (2,)
    assert len(sim.fixtures[0].poses) == 800  # 8 s there and back at 100 Hz


def write(tmp_path, text: str) -> Path:
    p = tmp_path / "fixture.toml"
    p.write_text(text)
    return p


BASE = """
[bus]
interface = "virtual"
channel = "x"
[[fixtures]]
name = "a"
hexapod = "reference"
can_ids = [1, 2, 3, 4, 5, 6]
"""


@pytest.mark.parametrize(
    "text,field,words",
    [
        (BASE.replace('name = "a"\n', ""), "fixtures[0].name", "missing"),
        (BASE.replace("[1, 2, 3, 4, 5, 6]", "[1, 2, 3, 4, 5, 2]"), "fixtures[0].can_ids[5]", "duplicate CAN id"),
        (BASE.replace('"virtual"', '"vcan"'), "bus.interface", "socketcan"),
        (BASE.replace('"reference"', '"nothere.urdf"'), "fixtures[0].hexapod", "does not exist"),
        (BASE.replace("[1, 2, 3, 4, 5, 6]", "[1, 2, 3, 4, 5, 0x800]"), "fixtures[0].can_ids[5]", "[0, 2047]"),
        (BASE + "noize = 1e-5\n", "fixtures[0].noize", "unknown field"),
        (BASE + "[fixtures.encoder]\nwidth = 4\nerror_bit = 2\n", "fixtures[0].encoder.error_bit", "count field"),
        (BASE + "[fixtures.encoder]\nwidth = 9\n", "fixtures[0].encoder.width", "[1, 8]"),
        (BASE + "home_counts = [1, 2]\n", "fixtures[0].home_counts", "six"),
        (BASE + "drift_limit = 1e-3\n", "fixtures[0].drift_limit", "steady_band"),
        (BASE + "predictor = 'eq99'\n", "fixtures[0].predictor", "eq22"),
        (BASE.replace("[bus]", "[http]\nport = 70000\n[bus]"), "http.port", "65535"),
        ("fixtures = []", "fixtures", "one or more"),
        (BASE.replace('"reference"', '"."'), "fixtures[0].hexapod", "is a folder"),
        (BASE.replace('name = "a"', 'name = ".."'), "fixtures[0].name", "not dots alone"),
        (BASE.replace('name = "a"', 'name = "."'), "fixtures[0].name", "not dots alone"),
        (BASE.replace("[bus]", '[http]\nhost = "10.1.2.3"\n[bus]'), "http.host", "token_file"),
        (BASE.replace("[bus]", '[http]\ntoken_file = "none.token"\n[bus]'), "http.token_file", "cannot read"),
        (BASE.replace("[bus]", '[http]\ncertfile = "c.pem"\n[bus]'), "http.keyfile", "both"),
        ("[bus\n", "<file>", "not valid TOML"),
    ],
)
def test_bad_configuration_names_the_field(tmp_path, text, field, words):
    with pytest.raises(ConfigError) as info:
        load_config(write(tmp_path, text))
    err = info.value
    assert err.field == field and words in str(err) and str(tmp_path / "fixture.toml") in str(err)
    assert "\n" not in str(err)


def test_duplicate_ids_across_fixtures_sharing_the_bus(tmp_path):
    with pytest.raises(ConfigError) as info:
        service_config(
            tmp_path, [fixture_table("a"), fixture_table("b", can_ids=[0x1A0, 0x1A1, 0x1A2, 0x1A3, 0x1A4, 0x181])]
        )
    assert info.value.field == "fixtures[1].can_ids[5]" and "fixtures[0].can_ids[0]" in str(info.value)


def test_unreadable_hexapod_file_is_named_when_loaded(tmp_path):
    (tmp_path / "broken.urdf").write_text("this is not a URDF")
    cfg = service_config(tmp_path, [fixture_table(hexapod="broken.urdf")])
    assert cfg.fixtures[0].hexapod == str(tmp_path / "broken.urdf")
    with pytest.raises(ConfigError) as info:
        cfg.fixtures[0].load_hexapod()
    assert info.value.field == "fixtures[0].hexapod" and "cannot load the hexapod" in str(info.value)


def test_home_count_must_fit_the_layout(tmp_path):
    with pytest.raises(ConfigError) as info:
        service_config(tmp_path, [fixture_table(home_counts=300, encoder={"width": 1, "signed": False})])
    assert info.value.field == "fixtures[0].home_counts[0]"


@pytest.mark.parametrize(
    "sim,field",
    [
        ({"name": "nope", "hold": [0, 0, 0.4, 0, 0, 0]}, "fixtures[0].name"),
        ({"name": "left"}, "fixtures[0].trajectory"),
        ({"name": "left", "trajectory": "C"}, "fixtures[0].trajectory"),
        ({"name": "left", "hold": [0, 0, 0.9, 0, 0, 0]}, "fixtures[0].hold"),  # outside the workspace
        ({"name": "left", "hold": [0, 0, 0.4, 0, 0, 0], "faults": [{"kind": "gremlin"}]}, "fixtures[0].faults[0].kind"),
        (
            {"name": "left", "hold": [0, 0, 0.4, 0, 0, 0], "faults": [{"kind": "stuck_leg", "leg": 7}]},
            "fixtures[0].faults[0].leg",
        ),
        ({"name": "left", "trajectory": "A", "lock": 1.0, "move": 0.3, "ramp": 0.2}, "fixtures[0].ramp"),
    ],
)
def test_bad_simulation_names_the_field(tmp_path, sim, field):
    service = service_config(tmp_path)
    with pytest.raises(ConfigError) as info:
        sim_config(service, [sim])
    assert info.value.field == field


def test_a_fifo_as_the_token_file_is_refused_in_one_line_without_waiting_for_a_writer(tmp_path):
    import os
    import threading

    from hexapod_model.service.config.token import read_token

    fifo = tmp_path / "token"
    os.mkfifo(fifo, 0o600)
    result: list = []

    def read():
        try:
            read_token(fifo)
        except ConfigError as exc:
            result.append(str(exc))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(5.0)
    if reader.is_alive():  # blocked opening the FIFO: let it go before failing
        with open(fifo, "w") as f:
            f.write("x")
        reader.join(5.0)
        raise AssertionError("reading the token hung on a FIFO")
    assert len(result) == 1 and "not a regular file" in result[0] and "\n" not in result[0], result
