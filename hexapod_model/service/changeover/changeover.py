"""The changeover of a running service: targets and recipes set, stored and turned into guidance.

>>> svc = FixtureService(load_config("fixture.toml")).start()          # doctest: +SKIP
>>> c = svc.changeover
>>> c.set_target("right", {"pose": {"x": 0.01, "y": -0.02, "z": 0.41, "roll": 5, "pitch": -3, "yaw": 10},
...                        "tolerance": {"translation_mm": 0.1, "rotation_deg": 0.05}}, by="anna")
>>> c.guidance("right")["legs"]        # per leg: reading_mm, target_mm, change_mm
>>> c.put_recipe("bracket", {"targets": {"left": {...}, "right": {...}}}, by="anna")
>>> c.activate("bracket", by="anna")   # the recipe's targets become the fixtures' targets

Every write is committed to the store before it returns (targets survive a restart or a
``kill -9``) and names who made it and when. Bad input raises
:class:`~hexapod_model.service.targets.target.TargetError` (one line naming the field); an unknown
fixture or recipe raises :class:`UnknownError`.
"""

from __future__ import annotations

import json
import logging
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from ...exceptions import HexapodError
from ...kinematics.hexapod import Hexapod
from ..config.settings import NAME_PATTERN
from ..cycle.fixture_cycle import FixtureCycle
from ..record.pose_record import PoseRecord
from ..store.fixture_store import Store
from ..targets.body_limits import clearance_of
from ..targets.guidance import guidance
from ..targets.target import Recipe, Target, TargetError, reachable, recipe_from_json, target_from_json
from .plan_monitor import PlanMonitor

log = logging.getLogger(__name__)


class UnknownError(HexapodError, KeyError):
    """No such fixture or recipe (HTTP 404)."""

    def __str__(self) -> str:
        return str(self.args[0])


class Changeover:
    """Targets, recipes and guidance of the service's fixtures.

    Args:
        store: the open store (its ``targets`` tables).
        hexapods: the fixtures' hexapods by name (inverse kinematics of the targets).
        cycles: the fixtures' cycles (their latest records; each gets its current target).
        clock: Unix time (s), for ``set_at``.
    """

    def __init__(
        self,
        store: Store,
        hexapods: dict[str, Hexapod],
        cycles: dict[str, FixtureCycle],
        clock: Callable[[], float] = time.time,
    ):
        self.store, self.hexapods, self.cycles, self.clock = store.targets, hexapods, cycles, clock
        self._write = threading.Lock()  # one write at a time: store row and cycle target change together
        self._targets: dict[str, Target] = {}
        #: ``GET /recipes``' entry of each recipe, with the stored row it was made from
        self._recipe_json: dict[str, tuple[tuple[str, str, float], dict[str, Any]]] = {}
        self.problems: dict[str, str] = {}  # stored targets that no longer solve (geometry changed)
        self._active = self.store.active()  # (name, set_by, set_at) of the active recipe, kept here
        #: the changeover plan being played and watched (its progress in :meth:`overview`), or None
        self.monitor: PlanMonitor | None = None
        #: each fixture's latest record and the clearance of its pose (measured once per record)
        self._clearance: dict[str, tuple[PoseRecord | None, dict[str, Any] | None]] = {}
        for name, row in self.store.current_targets().items():
            if name not in cycles:
                continue  # a fixture no longer configured: its rows stay in the store
            try:
                readings, clearance = reachable(hexapods[name], row.pose, "pose", name)
            except TargetError as exc:
                self.problems[name] = f"stored target {row.id} not used: {exc}"
                log.error("fixture %s: %s", name, self.problems[name])
                continue
            by, at = row.set_by, row.set_at
            self._install(Target(name, row.pose, row.tolerance, readings, by, at, row.recipe, row.id, clearance))

    def _install(self, target: Target | None, name: str | None = None) -> None:
        name = name or (target.fixture if target is not None else "")
        if target is None:
            self._targets.pop(name, None)
        else:
            self._targets[name] = target
        self.problems.pop(name, None)
        self.cycles[name].target = target

    def _fixture(self, name: str) -> Hexapod:
        if name not in self.cycles:
            raise UnknownError(f"no fixture {name!r} (fixtures: {', '.join(self.cycles)})")
        return self.hexapods[name]

    # ----- targets -----
    def target(self, name: str) -> Target | None:
        """The fixture's current target (None when none is set)."""
        self._fixture(name)
        return self._targets.get(name)

    def followed(self, name: str) -> tuple[int | None, np.ndarray | None]:
        """``(id, 4x4 pose)`` of the fixture's target, ``(None, None)`` without: what a simulated plate follows."""
        target = self._targets.get(name)
        return (None, None) if target is None else (target.id, target.pose)

    def set_target(self, name: str, body: Any, by: str) -> Target:
        """Validate ``body`` (``{"pose", "tolerance"}``), store it as the fixture's target; returns it with its id."""
        target = target_from_json(body, name, self._fixture(name), by, self.clock())
        with self._write:
            target = _with_id(target, self.store.add_target(target))
            self._install(target)
        log.info("fixture %s: target %d set by %s", name, target.id, by)
        return target

    def clear_target(self, name: str, by: str) -> bool:
        """Clear the fixture's target (False when it had none)."""
        self._fixture(name)
        with self._write:
            cleared = self.store.clear_target(name, by, self.clock())
            self._install(None, name)
        if cleared:
            log.info("fixture %s: target cleared by %s", name, by)
        return cleared

    # ----- recipes -----
    def put_recipe(self, name: str, body: Any, by: str) -> Recipe:
        """Validate and store recipe ``name`` (``{"targets": {fixture: target}}``); it is not activated."""
        if not isinstance(name, str) or not NAME_PATTERN.match(name) or name in (".", ".."):
            raise TargetError("recipe", name, "use letters, digits, '_', '-' and '.' only (it appears in URLs)")
        recipe = recipe_from_json(body, name, self.hexapods, by, self.clock())
        with self._write:
            self.store.put_recipe(recipe)
        log.info("recipe %s stored by %s (%s)", name, by, ", ".join(recipe.targets))
        return recipe

    def recipes(self) -> dict[str, Any]:
        """``{"active": {"name", "set_by", "set_at"} | None, "recipes": {name: {"targets", "set_by", "set_at"}}}``."""
        active = self._active
        recipes = {}
        for name, (body, who, at) in self.store.recipes().items():
            key = (json.dumps(body, sort_keys=True), who, at)  # a name's newest row: its text, author and time
            hit = self._recipe_json.get(name)
            if hit is None or hit[0] != key:  # solved once per stored row: the hexapods do not change
                hit = (key, self._recipe_entry(name, body, who, at))
                self._recipe_json[name] = hit
            recipes[name] = hit[1]
        return {
            "active": None if active is None else dict(zip(("name", "set_by", "set_at"), active)),
            "recipes": recipes,
        }

    def _recipe_entry(self, name: str, body: dict, who: str, at: float) -> dict[str, Any]:
        """A stored recipe's JSON as ``GET /recipes`` lists it (its targets solved), or with its ``problem``."""
        try:
            return recipe_from_json(body, name, self.hexapods, who, at).to_json()
        except TargetError as exc:  # a fixture gone from the configuration, or out of its workspace now
            return {**body, "set_by": who, "set_at": at, "problem": str(exc)}

    def activate(self, name: str, by: str) -> Recipe:
        """Make recipe ``name`` active: its targets become its fixtures' targets (one transaction)."""
        stored = self.store.recipes().get(name)
        if stored is None:
            raise UnknownError(f"no recipe {name!r} (recipes: {', '.join(self.store.recipes()) or 'none'})")
        recipe = recipe_from_json(stored[0], name, self.hexapods, by, self.clock())
        with self._write:
            ids = self.store.activate(recipe, by, recipe.set_at)
            for target, row in zip(recipe.targets.values(), ids):
                self._install(_with_id(target, row))
            self._active = (name, by, recipe.set_at)
        log.info("recipe %s activated by %s", name, by)
        return recipe

    # ----- guidance -----
    def guidance(self, name: str) -> dict[str, Any]:
        """The fixture's guidance (:func:`hexapod_model.service.targets.guidance`) and the active recipe."""
        self._fixture(name)
        active = self._active
        extra: dict[str, Any] = {"active_recipe": None if active is None else active[0]}
        if name in self.problems:
            extra["target_problem"] = self.problems[name]
        rec = self.cycles[name].last
        return guidance(rec, self._targets.get(name), extra, self._clearance_of(name, rec))

    def _clearance_of(self, name: str, rec: PoseRecord) -> dict[str, Any] | None:
        """The clearance of the record's pose (:func:`~..targets.body_limits.clearance_of`), once per record."""
        seen, value = self._clearance.get(name, (None, None))
        if seen is not rec:
            value = clearance_of(self.hexapods[name], rec.q)
            self._clearance[name] = (rec, value)
        return value

    def overview(self) -> dict[str, Any]:
        """Every fixture's guidance, the active recipe and a playing plan's progress: what the dashboard shows."""
        active, monitor = self._active, self.monitor
        return {
            "t": self.clock(),
            "active_recipe": None if active is None else active[0],
            "fixtures": [self.guidance(name) for name in self.cycles],
            "plan": None if monitor is None else monitor.progress(),
        }


def _with_id(target: Target, row: int) -> Target:
    return replace(target, id=row)
