"""The optional [ros] table of fixture.toml (no ROS package needed)."""

from __future__ import annotations

import pytest

from hexapod_model.service import ConfigError
from hexapod_model.service.config.ros import RosConfig

from ..service.helpers import service_config


def test_without_a_ros_table_nothing_is_published(tmp_path):
    assert service_config(tmp_path).ros is None


def test_defaults_stay_on_this_machine(tmp_path):
    cfg = service_config(tmp_path, ros={}).ros
    assert cfg == RosConfig()
    assert (cfg.enabled, cfg.namespace, cfg.domain_id, cfg.interface, cfg.peers) == (
        True,
        "hexapod",
        0,
        "127.0.0.1",
        ("127.0.0.1",),
    )


def test_a_cell_network(tmp_path):
    table = {"namespace": "/cell1/fixtures/", "domain_id": 7, "interface": "192.168.10.2", "peers": ["192.168.10.5"]}
    cfg = service_config(tmp_path, ros=table).ros
    assert (cfg.namespace, cfg.domain_id, cfg.interface, cfg.peers) == (
        "cell1/fixtures",
        7,
        "192.168.10.2",
        ("192.168.10.5",),
    )


@pytest.mark.parametrize(
    ("table", "field", "says"),
    [
        ({"domain_id": 233}, "ros.domain_id", "[0, 232]"),
        ({"namespace": "9lives"}, "ros.namespace", "ROS 2 name"),
        ({"namespace": "a b"}, "ros.namespace", "ROS 2 name"),
        ({"peers": []}, "ros.peers", "one or more"),
        ({"peers": ["localhost"]}, "ros.peers[0]", "IPv4"),
        ({"interface": "eth0"}, "ros.interface", "IPv4"),
        ({"diagnostics_period": 0}, "ros.diagnostics_period", "[0.01, 3600]"),
        ({"enabled": "yes"}, "ros.enabled", "true or false"),
        ({"namspace": "x"}, "ros.namspace", "unknown field"),
    ],
)
def test_bad_fields_are_named(tmp_path, table, field, says):
    with pytest.raises(ConfigError, match=r"field '" + field.replace("[", r"\[").replace("]", r"\]")) as err:
        service_config(tmp_path, ros=table)
    assert says in str(err.value)
