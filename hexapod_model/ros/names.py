"""Topic, frame and joint names of a fixture on ROS 2 (no DDS import: usable without the ros extra)."""

from __future__ import annotations

from dataclasses import dataclass

from ..kinematics.hexapod import Hexapod


@dataclass(frozen=True)
class FixtureNames:
    """The topic and frame names of one fixture.

    Attributes:
        fixture: the fixture's name.
        namespace: the ``[ros]`` namespace (no leading ``/``).
        joints: names of the hexapod's one-dof URDF joints (legs' prismatic and passive joints).
        joint_q: index of each of ``joints`` in the configuration ``q``.
        prismatic: names of the six prismatic joints, leg order.
        readings: names of the readings a record carries, in their order
            (:attr:`~hexapod_model.kinematics.hexapod.Hexapod.reading_names`: ``leg1`` ... ``leg6``,
            then a redundant fixture's measuring legs ``leg7`` ... and inclinometer ``tilt_x``,
            ``tilt_y``).
        encoder: the six legs' encoder model ``(zero, gain)`` (m, dimensionless; reading =
            ``zero + gain *`` prismatic joint value), None when the reading is the joint value.
    """

    fixture: str
    namespace: str
    joints: tuple[str, ...]
    joint_q: tuple[int, ...]
    prismatic: tuple[str, ...]
    readings: tuple[str, ...]
    encoder: tuple[tuple[float, ...], tuple[float, ...]] | None = None

    @classmethod
    def of(cls, fixture: str, namespace: str, hexa: Hexapod) -> FixtureNames:
        """The names of ``fixture`` modelled by ``hexa``."""
        m, enc = hexa.model, hexa.engine.encoder
        one_dof = [j for j in range(1, m.njoints) if m.joints[j].nq == 1]
        return cls(
            fixture,
            namespace,
            tuple(m.names[j] for j in one_dof),
            tuple(m.joints[j].idx_q for j in one_dof),
            tuple(hexa.prismatic_names),
            tuple(hexa.reading_names),
            None if enc is None else (tuple(map(float, enc[0])), tuple(map(float, enc[1]))),
        )

    @property
    def redundant(self) -> bool:
        """Whether the fixture has redundant sensors (more readings than its six legs)."""
        return len(self.readings) > len(self.prismatic)

    def topic(self, leaf: str) -> str:
        """``/<namespace>/<fixture>/<leaf>``."""
        return f"/{self.namespace}/{self.fixture}/{leaf}"

    @property
    def base(self) -> str:
        """The base frame, ``<fixture>/base``."""
        return f"{self.fixture}/base"

    @property
    def platform(self) -> str:
        """The platform frame, ``<fixture>/platform``."""
        return f"{self.fixture}/platform"
