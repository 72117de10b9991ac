"""Shared fixtures: one loaded Hexapod per preset for the whole session; the chromium marker."""

from __future__ import annotations

import functools
import shutil

import pytest

import hexapod_model as hm
from hexapod_model.viz.render import CHROMIUM_NAMES

PRESET_NAMES = list(hm.PRESETS)
HAVE_CHROMIUM = any(shutil.which(name) for name in CHROMIUM_NAMES)


@functools.cache
def hexapod(name: str) -> hm.Hexapod:
    """Cached Hexapod of preset ``name`` (solver buffers are reused across tests)."""
    return hm.Hexapod.from_preset(name)


@pytest.fixture(params=PRESET_NAMES)
def preset_hexapod(request) -> hm.Hexapod:
    return hexapod(request.param)


def pytest_collection_modifyitems(config, items):
    """Tests marked ``chromium`` are skipped, with the reason, on a machine without the browser."""
    if HAVE_CHROMIUM:
        return
    skip = pytest.mark.skip(reason="needs headless Chromium: apt-get install chromium (.ci/run installs it)")
    for item in items:
        if "chromium" in item.keywords:
            item.add_marker(skip)
