"""Shared fixtures: one loaded Hexapod per preset for the whole session."""

from __future__ import annotations

import functools

import pytest

import hexapod_model as hm

PRESET_NAMES = list(hm.PRESETS)


@functools.cache
def hexapod(name: str) -> hm.Hexapod:
    """Cached Hexapod of preset ``name`` (solver buffers are reused across tests)."""
    return hm.Hexapod.from_preset(name)


@pytest.fixture(params=PRESET_NAMES)
def preset_hexapod(request) -> hm.Hexapod:
    return hexapod(request.param)
