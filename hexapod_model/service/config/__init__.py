"""The service's configuration ``fixture.toml``: bus, store, HTTP, fixtures, their encoders and cells, ROS.

Read and validated once (:func:`load_config`); every error names the file and the dotted field.
"""

from .cell import Cell, Located, locate
from .codec import Decoded, FrameLayout, LegCodec, decode, encode
from .ros import RosConfig
from .settings import (
    BusConfig,
    FixtureConfig,
    HttpConfig,
    ServiceConfig,
    StoreConfig,
    config_from_dict,
    geometry_hash,
    load_config,
)
from .table import Table

__all__ = [
    "BusConfig",
    "Cell",
    "Decoded",
    "FixtureConfig",
    "FrameLayout",
    "HttpConfig",
    "LegCodec",
    "Located",
    "RosConfig",
    "ServiceConfig",
    "StoreConfig",
    "Table",
    "config_from_dict",
    "decode",
    "encode",
    "geometry_hash",
    "load_config",
    "locate",
]
