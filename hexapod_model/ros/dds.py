"""Publish the service's records as ROS 2 topics over DDS (Eclipse Cyclone DDS's Python binding).

:class:`RosBridge` subscribes to a :class:`~hexapod_model.service.FixtureService`: on the cycle
thread it only queues the record (and the configuration of its pose); its own thread turns
queued records into messages (:mod:`hexapod_model.ros.convert`) and writes them. A DDS failure
(no ``cyclonedds``, a participant that cannot be created, a failed write) is logged once, kept
in :meth:`RosBridge.health` (``/health``) and never stops the service.

ROS 2 conventions: the DDS topic of ``/a/b`` is ``rt/a/b``; the types are ROS 2's DDS types
(:mod:`hexapod_model.ros.messages`), written as plain CDR (XCDR1); each writer's USER_DATA holds
``typehash=RIHS01_...;``, the type's hash as ``rosidl`` computes it (here by ``rosbags``). QoS:
reliable, volatile, keep last 10; ``/tf_static``: reliable, transient local, keep last 1.
Discovery: :func:`cyclone_xml` (this machine only by default). A stock ROS 2 node of this machine
finds the service with no setting: the service announces itself by unicast to the loopback
discovery ports every :data:`SPDP_INTERVAL` s, and answers the node's announcement at its
addresses (a node's default discovery multicasts, which the service never hears).
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from typing import Any

from ..extras import install_hint
from ..planning.model import Plan
from ..service.config.ros import RosConfig
from ..service.record.pose_record import PoseRecord
from ..service.service import FixtureService
from ..service.threads import NamedThread
from .names import FixtureNames

log = logging.getLogger(__name__)
INSTALL_HINT = install_hint("ros")
QUEUE_LENGTH = 1000  # records waiting for the publisher thread; more are dropped (counted on /health)
MAX_PARTICIPANTS = 32  # participant indices probed on each peer: ROS 2 nodes of one machine and domain
SPDP_INTERVAL = 1.0  # s between the participant announcements sent to the peers (Cyclone DDS's default: 30 s)


def cyclone_xml(cfg: RosConfig) -> str:
    """The Cyclone DDS configuration of ``cfg``: its interface, no multicast, unicast discovery at its peers.

    The participant announces itself to every peer's discovery ports each :data:`SPDP_INTERVAL`
    s, so that a node started after the service (whose own multicast announcements the service
    does not hear) learns of it within that time rather than at Cyclone DDS's default 30 s.
    """
    peers = "".join(f'<Peer address="{p}"/>' for p in cfg.peers)
    return (
        '<CycloneDDS><Domain id="any"><General><Interfaces>'
        f'<NetworkInterface address="{cfg.interface}"/></Interfaces>'
        "<AllowMulticast>false</AllowMulticast></General>"
        f"<Discovery><SPDPInterval>{SPDP_INTERVAL:g}s</SPDPInterval><ParticipantIndex>auto</ParticipantIndex>"
        f"<MaxAutoParticipantIndex>{MAX_PARTICIPANTS}</MaxAutoParticipantIndex>"
        f"<Peers>{peers}</Peers></Discovery></Domain></CycloneDDS>"
    )


def type_hashes() -> dict[type, str]:
    """``RIHS01_...`` of each published message type (ROS 2 Jazzy's definitions, hashed by ``rosbags``)."""
    from rosbags.typesys import Stores, get_typestore

    from .messages import ROS_NAMES

    store = get_typestore(Stores.ROS2_JAZZY)
    return {cls: store.hash_rihs01(name) for cls, name in ROS_NAMES.items()}


class _Writers:
    """The DDS entities: one participant, a writer per topic (built in :meth:`RosBridge.start`)."""

    def __init__(self, cfg: RosConfig, names: dict[str, FixtureNames], service: FixtureService):
        from cyclonedds.domain import Domain, DomainParticipant
        from cyclonedds.pub import DataWriter
        from cyclonedds.qos import Policy, Qos
        from cyclonedds.topic import Topic
        from cyclonedds.util import duration

        from .changeover_topics import ChangeoverTopics
        from .messages import DiagnosticArray, JointState, PoseStamped, String, TFMessage

        hashes = type_hashes()
        self._entities: list[Any] = []
        self.domain = Domain(cfg.domain_id, cyclone_xml(cfg))
        self.participant = DomainParticipant(cfg.domain_id, qos=Qos(Policy.Userdata(b"enclave=/;")))
        self._entities = [self.domain, self.participant]

        def writer(name: str, cls: type, depth: int = 10, transient: bool = False, typehash: str | None = None):
            qos = Qos(
                Policy.Reliability.Reliable(duration(milliseconds=100)),
                Policy.Durability.TransientLocal if transient else Policy.Durability.Volatile,
                Policy.History.KeepLast(depth),
                Policy.DataRepresentation(use_cdrv0_representation=True),
                Policy.Userdata(f"typehash={typehash or hashes[cls]};".encode()),
            )
            topic: Any = Topic(self.participant, "rt" + name, cls, qos=qos)
            w = DataWriter(self.participant, topic, qos=qos)
            self._entities += [topic, w]
            return w

        self.pose = {n: writer(v.topic("pose"), PoseStamped) for n, v in names.items()}
        self.joints = {n: writer(v.topic("joint_states"), JointState) for n, v in names.items()}
        self.tf = writer("/tf", TFMessage, 100)
        self.tf_static = writer("/tf_static", TFMessage, 1, transient=True)
        self.diagnostics = writer("/diagnostics", DiagnosticArray)
        reliable = (
            Policy.Reliability.Reliable(duration(milliseconds=100)),
            Policy.Durability.Volatile,
            Policy.History.KeepLast(10),
            Policy.DataRepresentation(use_cdrv0_representation=True),
        )
        self.changeover = ChangeoverTopics(service, self.participant, cfg.namespace, names, reliable, hashes[String])
        self._entities += self.changeover.entities
        self.writer = writer  # more topics later (a played plan's trajectory)

    def close(self) -> None:
        """Delete every entity, newest first (the participant and domain last)."""
        for e in reversed(self._entities):
            e.__del__()  # cyclonedds deletes an entity when its object goes; do it now
        self._entities = []


class RosBridge:
    """Publish the records of ``service`` per ``cfg`` (module docstring).

    Call :meth:`start` after the service has started and :meth:`stop` before it stops; the
    topics of each fixture are named by :class:`~hexapod_model.ros.convert.FixtureNames`.

    Args:
        service: the service; the bridge subscribes to its records here.
        cfg: the ``[ros]`` table.
    """

    def __init__(self, service: FixtureService, cfg: RosConfig):
        self.service, self.cfg = service, cfg
        self.names: dict[str, FixtureNames] = {}  # by fixture, once the service has its hexapods
        self.error: str | None = None
        self.published = self.dropped = self.failed_writes = 0
        self._queue: queue.Queue = queue.Queue(QUEUE_LENGTH)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._writers: _Writers | None = None
        self._last_diag: dict[str, tuple[float, str, tuple[str, ...]]] = {}
        service.subscribe(self._on_record)
        service.health_sections["ros"] = self.health

    # ----- the cycle thread -----
    def _on_record(self, rec: PoseRecord) -> None:
        if self._thread is None:
            return  # not publishing (yet, or DDS failed)
        q = rec.q
        if q is not None:
            q = q.copy()  # the publisher thread reads it later
        try:
            self._queue.put_nowait((rec, q))
        except queue.Full:
            self.dropped += 1

    # ----- life cycle -----
    def start(self) -> RosBridge:
        """Create the DDS entities and the publisher thread; a failure is kept in :attr:`error`, not raised.

        Call it once the service is :attr:`~hexapod_model.service.FixtureService.ready` (its hexapods are loaded).
        """
        self.names = {
            f.name: FixtureNames.of(f.name, self.cfg.namespace, self.service.hexapods[f.name])
            for f in self.service.config.fixtures
        }
        try:
            self._writers = _Writers(self.cfg, self.names, self.service)
        except ImportError as exc:
            self._fail(f"cannot publish ROS 2 topics: {exc.name or exc} is not installed ({INSTALL_HINT})")
            return self
        except Exception as exc:  # noqa: BLE001 - DDSException and its like: shown on /health
            self._fail(f"cannot create the DDS participant (domain {self.cfg.domain_id}): {exc}")
            return self
        try:
            self._publish_placements()
        except ValueError as exc:  # a placement that is no transform: the other topics go on
            self._fail(f"/tf_static: {exc}")
        self._stop.clear()
        self._thread = NamedThread(target=self._loop, name="hx-ros")
        self._thread.start()
        log.info(
            "publishing ROS 2 topics /%s/<fixture>/... on domain %d (interface %s, peers %s)",
            self.cfg.namespace,
            self.cfg.domain_id,
            self.cfg.interface,
            ", ".join(self.cfg.peers),
        )
        return self

    def stop(self) -> None:
        """Stop the publisher thread and delete the DDS entities."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._writers is not None:
            self._writers.close()
            self._writers = None

    def health(self) -> dict:
        """The bridge's state for ``/health``: ``error`` is None while every write succeeds."""
        return {
            "namespace": self.cfg.namespace,
            "domain_id": self.cfg.domain_id,
            "publishing": self._thread is not None and self._thread.is_alive(),
            "published": self.published,
            "dropped": self.dropped,
            "failed_writes": self.failed_writes,
            "error": self.error,
        }

    def publish_plan(self, plan: Plan) -> None:
        """Publish a played plan once on ``/hexapod/changeover/trajectory`` (:mod:`~hexapod_model.ros.plan_topic`).

        Transient local: a subscriber that joins later still gets it. A failure is kept in
        :attr:`error` (``/health``), never raised.
        """
        if self._writers is None:
            return  # not publishing: start() said why
        from rosbags.typesys import Stores, get_typestore

        from .plan_topic import ROS_NAME, JointTrajectory, trajectory
        from .trajectory import TOPIC

        try:
            typehash = get_typestore(Stores.ROS2_JAZZY).hash_rihs01(ROS_NAME)
            w = self._writers.writer(TOPIC, JointTrajectory, 1, transient=True, typehash=typehash)
            msg = trajectory(plan, time.time())
        except Exception as exc:  # noqa: BLE001 - DDSException and its like: shown on /health
            self._fail(f"{TOPIC}: {exc}")
            return
        self._write(lambda _: w.write(msg))
        log.info("published the changeover plan (%d points) on %s", len(plan.t), TOPIC)

    def _fail(self, message: str) -> None:
        """Keep ``message`` for ``/health``; log it when it is new (not once per record)."""
        if self.error is None:
            log.error("ros: %s", message)
        self.error = message

    # ----- the publisher thread -----
    def _publish_placements(self) -> None:
        """``/tf_static``: every fixture's configured cell placement (``[fixtures.cell] base_in_robot``), once."""
        from .convert import placement
        from .messages import TFMessage

        now, transforms = time.time(), []
        for f in self.service.config.fixtures:
            if f.cell is not None:
                transforms.append(placement(f.cell.base_in_robot, self.cfg.robot_frame, self.names[f.name], now))
        if transforms:
            self._write(lambda w: w.tf_static.write(TFMessage(transforms)))

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                if self._writers is not None:
                    self._writers.changeover.tick(time.monotonic())  # guidance out, targets in
            except Exception as exc:  # noqa: BLE001 - on /health, the poses go on
                self._fail(f"changeover topics: {exc}")
            try:
                rec, q = self._queue.get(timeout=0.05)
            except queue.Empty:
                continue
            try:
                self._publish(rec, q)
            except Exception as exc:  # noqa: BLE001 - a record that cannot be converted: on /health, go on
                self._fail(f"record of {rec.fixture!r} at t={rec.t!r} not published: {exc}")

    def _publish(self, rec: PoseRecord, q) -> None:
        from .convert import diagnostic, joint_state, pose_stamped, stamp, transform
        from .messages import DiagnosticArray, Header, TFMessage

        names = self.names[rec.fixture]
        pose, tf, joints = pose_stamped(rec, names), transform(rec, names), joint_state(rec, names, q)
        if pose is not None:
            self._write(lambda w: w.pose[names.fixture].write(pose))
        if joints is not None:
            self._write(lambda w: w.joints[names.fixture].write(joints))
        if tf is not None:
            self._write(lambda w: w.tf.write(TFMessage([tf])))
        last = self._last_diag.get(names.fixture)
        key = (rec.status, tuple(rec.flags))
        if last is None or last[1:] != key or rec.t - last[0] >= self.cfg.diagnostics_period:
            self._last_diag[names.fixture] = (rec.t, *key)
            store_error = None if self.service.writer is None else self.service.writer.error
            status = diagnostic(rec, names, f"{self.cfg.namespace}/{names.fixture}", store_error)
            array = DiagnosticArray(Header(stamp(rec.t), ""), [status])
            self._write(lambda w: w.diagnostics.write(array))

    def _write(self, write) -> None:
        assert self._writers is not None
        try:
            write(self._writers)
        except Exception as exc:  # noqa: BLE001 - a DDS failure is on /health, the service goes on
            self.failed_writes += 1
            self._fail(f"DDS write failed: {exc}")
            return
        self.published += 1
        if self.error is not None and self.error.startswith("DDS write failed"):
            self.error = None  # writing again (failed_writes keeps the count)
            log.info("ros: writing again after %d failed writes", self.failed_writes)
