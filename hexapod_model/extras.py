"""The optional parts of the package and the extra that installs each (``pip install 'hexapod_model[EXTRA]'``).

The core (URDF and MJCF generation, forward and inverse kinematics, the studies' tables) needs
Pinocchio, NumPy, numba, SciPy and a few small packages. Heavier parts are extras, named for
what needs them:

* ``cell``: example-robot-data, the UR10 of ``hexapod view/snapshot --cell`` (~400 MB);
* ``view``: meshcat and Pillow, ``hexapod view`` / ``snapshot`` and :mod:`hexapod_model.viz`;
* ``plots``: matplotlib, the figures of ``reproduce``, ``evaluate``, ``calibrate`` and ``track``;
* ``service``: python-can (and the web server's packages), ``hexapod serve``, ``fixture``, ``live``;
* ``fieldbus``: canopen and cantools, the CANopen (EDS/DCF) and DBC encoder protocols of ``hexapod serve``;
* ``sweep``: Dask ``distributed``, ``hexapod sweep`` and ``hexapod evaluate``'s tasks;
* ``plan``: example-robot-data and coal, ``hexapod changeover plan`` and :mod:`hexapod_model.planning`;
* ``all``: every one of them.

A command whose extra is missing stops with one line naming the ``pip install`` that brings it
(:func:`require`).
"""

from __future__ import annotations

import importlib
import importlib.metadata
from types import ModuleType

from .exceptions import HexapodError

#: extra -> what needs it (the error's wording)
EXTRAS = {
    "cell": "the robot cell (--cell)",
    "view": "the 3-D view and snapshots",
    "plots": "the figures",
    "service": "the fixture pose service",
    "fieldbus": "the CANopen and DBC encoder protocols",
    "sweep": "design sweeps and evaluate on Dask",
    "plan": "changeover planning",
}

#: extra -> the modules of it the package imports (``cell`` is a data-only distribution)
MODULES = {
    "cell": (),
    "view": ("meshcat", "PIL"),
    "plots": ("matplotlib",),
    "service": ("can", "starlette", "uvicorn"),
    "fieldbus": ("canopen", "cantools"),
    "sweep": ("distributed",),
    "plan": ("coal",),
}


class MissingExtraError(HexapodError, ImportError):
    """An optional dependency is not installed; the message names the ``pip install`` that brings it."""


def install_hint(extra: str) -> str:
    """``pip install 'hexapod_model[extra]'``."""
    return f"pip install 'hexapod_model[{extra}]'"


def require(module: str, extra: str, what: str | None = None) -> ModuleType:
    """Import ``module`` or raise :class:`MissingExtraError` naming ``extra``'s install command.

    Args:
        module: the import name (``"meshcat"``, ``"matplotlib"``, ``"can"``...).
        extra: the extra that installs it (a key of :data:`EXTRAS`).
        what: what needs it, for the message (default: the extra's entry in :data:`EXTRAS`).
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        needs = what or EXTRAS[extra]
        raise MissingExtraError(f"{exc.name or module} is not installed ({needs}): {install_hint(extra)}") from None


def require_distribution(name: str, extra: str, what: str | None = None) -> importlib.metadata.Distribution:
    """The installed distribution ``name`` (a data-only wheel) or :class:`MissingExtraError` as :func:`require`."""
    try:
        return importlib.metadata.distribution(name)
    except importlib.metadata.PackageNotFoundError:
        raise MissingExtraError(f"{name} is not installed ({what or EXTRAS[extra]}): {install_hint(extra)}") from None


def require_extra(extra: str) -> None:
    """:func:`require` each module of ``extra`` (:data:`MODULES`): a command calls it before its imports."""
    for module in MODULES[extra]:
        require(module, extra)
