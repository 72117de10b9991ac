"""The record a fixture's cycle publishes for each sampling instant: :class:`PoseRecord`.

Built once per reading set by the cycle and read by attribute everywhere in the package; turned
into its JSON object (:meth:`PoseRecord.to_dict`, :meth:`PoseRecord.to_json`) only at the edges
that send text: HTTP and JSON lines. The store's row, the ROS messages and the MCAP bag are made
from the attributes. The JSON object's keys, in order, are :data:`RECORD_KEYS`
(``docs/service.md`` documents each).
"""

from __future__ import annotations

import json
from typing import Any, NamedTuple

import numpy as np

RECORD_KEYS = (
    "fixture",
    "t",
    "readings",
    "pose",
    "status",
    "flags",
    "iterations",
    "state",
    "stored",
    "sigma",
    "singularity_margin",
    "load",
    "pose_in_robot",
    "extra_readings",
    "consistency",
)


class PoseRecord(NamedTuple):
    """One published record of a fixture (immutable; its lists and arrays are not to be changed either).

    A named tuple, as the solver's outcome: one is made per reading set, and a tuple costs a third
    of a frozen dataclass (0.4 against 1.6 us with these 15 fields), no more than the dict it
    replaces. Read it by attribute; compare records by :meth:`to_dict` (the arrays do not compare
    as one truth value).

    Attributes:
        fixture: the fixture's name.
        t: time of the reading set (s, the bus's clock: Unix time).
        readings: the six leg readings (m, zero at home; None for a leg without a fresh reading).
        pose: base -> platform as JSON values: ``x, y, z`` (m), ``qx, qy, qz, qw``, ``roll, pitch,
            yaw`` (deg); None without a pose.
        status: ``ok``, ``flagged``, ``drift``, ... (:mod:`~hexapod_model.service.cycle.fixture_cycle`).
        flags: what the status does not say alone (``encoder_error:leg3``, ``jump``, ...).
        iterations: Newton steps of the solve (0 without one).
        state: ``moving``, ``locked`` (the lock detector's).
        stored: whether the current lock pose is committed to the store (None: not known, a stored sample).
        sigma: 1-sigma pose uncertainty ``{"translation_mm", "rotation_deg"}``, or None.
        singularity_margin: ``cond(home) / cond(here)`` (1 at home, towards 0 at a singularity), or None.
        load: a locked fixture's process-wrench loads (:func:`~hexapod_model.service.cycle.lock_load.lock_load`).
        pose_in_robot: ``{"pose", "sigma"}`` of the coupling in the robot's frame, or None.
        extra_readings: a fixture with redundant sensors: each extra reading by name (``leg7`` in m,
            ``tilt_x``, ``tilt_y`` in rad; None without a fresh frame); None for six legs.
        consistency: the consistency test of a set solved from redundant readings: ``chi2`` (its
            statistic), ``bound`` (``chi2.ppf(1 - alpha, dof)``), ``dof`` and ``alpha`` (the
            false-alarm rate); None when no such solve ran.
        transform: the pose as a 4x4 matrix (base -> platform, m), None without a pose; not in the JSON.
        q: the Pinocchio configuration of the pose (its passive joints), None without one; not in the JSON.
    """

    fixture: str
    t: float
    readings: list[float | None]
    pose: dict[str, float] | None
    status: str
    flags: list[str]
    iterations: int
    state: str
    stored: bool | None
    sigma: dict[str, float] | None
    singularity_margin: float | None
    load: dict[str, Any] | None
    pose_in_robot: dict[str, Any] | None
    transform: np.ndarray | None = None
    q: np.ndarray | None = None
    extra_readings: dict[str, float | None] | None = None
    consistency: dict[str, float] | None = None

    def to_dict(self) -> dict[str, Any]:
        """The record's JSON object: :data:`RECORD_KEYS` in order (the lists are the record's own)."""
        return {
            "fixture": self.fixture,
            "t": self.t,
            "readings": self.readings,
            "pose": self.pose,
            "status": self.status,
            "flags": self.flags,
            "iterations": self.iterations,
            "state": self.state,
            "stored": self.stored,
            "sigma": self.sigma,
            "singularity_margin": self.singularity_margin,
            "load": self.load,
            "pose_in_robot": self.pose_in_robot,
            "extra_readings": self.extra_readings,
            "consistency": self.consistency,
        }

    def to_json(self) -> str:
        """The JSON text of :meth:`to_dict` (``allow_nan=False``: a NaN is an error, never sent)."""
        return json.dumps(self.to_dict(), allow_nan=False)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> PoseRecord:
        """The record of a JSON object made by :meth:`to_dict` (``transform`` and ``q`` None: the JSON has neither).

        ``extra_readings`` and ``consistency`` may be missing (records written before they existed).

        Raises:
            KeyError: another key of :data:`RECORD_KEYS` is missing.
        """
        values: dict[str, Any] = {k: data[k] for k in RECORD_KEYS[:-2]}
        return cls(**values, extra_readings=data.get("extra_readings"), consistency=data.get("consistency"))
