"""The guided changeover on ROS 2: each fixture's guidance out, targets in (signed with the token).

Topics (all ``std_msgs/msg/String`` holding JSON; reliable, volatile, keep last 10):

* ``/<ns>/<fixture>/guidance`` (out): the fixture's guidance, the body of ``GET
  /fixtures/NAME/guidance``, every :data:`GUIDANCE_PERIOD` s.
* ``/<ns>/target`` (in): ``{"payload": TEXT, "hmac": HEX}``, ``TEXT`` the JSON ``{"fixture",
  "target": {"pose", "tolerance"} | null (clears it), "by", "t"}`` (``t`` Unix time, s) and
  ``HEX`` its HMAC-SHA256 keyed with the service's bearer token (``[http] token_file``), as
  :func:`sign` makes it. A topic is readable by every participant of the domain, so the token
  itself never travels: the signature proves the sender holds it. A request older or newer
  than :data:`MAX_AGE` s, or one already taken, is refused (a replayed message does nothing).
  Without a token the service takes no target over ROS 2, as over HTTP.
* ``/<ns>/target_result`` (out): per request ``{"fixture", "t", "ok", "target"}`` (the stored
  target, as HTTP returns it) or ``{"fixture", "t", "ok": false, "error"}``.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import logging
import math
import time
from typing import Any

from ..exceptions import HexapodError
from ..service.service import FixtureService
from .names import FixtureNames

log = logging.getLogger(__name__)
GUIDANCE_PERIOD = 0.25  # s between two guidance messages of a fixture (the dashboard's event period)
TICK = 0.05  # s between two looks at the target requests
MAX_AGE = 10.0  # s: a target request's t must be this close to the service's clock


def sign(payload: str, token: str) -> str:
    """HMAC-SHA256 of ``payload`` (UTF-8) keyed with ``token``, in hex: the ``hmac`` of a target request."""
    return hmac.new(token.encode(), payload.encode(), hashlib.sha256).hexdigest()


def request(fixture: str, target: dict | None, by: str, token: str, t: float | None = None) -> str:
    """The ``data`` of a ``/<ns>/target`` message setting (or, with ``target=None``, clearing) a target."""
    payload = json.dumps({"fixture": fixture, "target": target, "by": by, "t": time.time() if t is None else t})
    return json.dumps({"payload": payload, "hmac": sign(payload, token)})


class ChangeoverTopics:
    """The changeover topics of ``service`` on ``participant`` (module docstring).

    Args:
        service: the running service (its changeover and its token).
        participant: the bridge's Cyclone DDS participant.
        namespace: the ``[ros]`` namespace (no leading ``/``).
        names: each fixture's topic names.
        qos: the writers' and the reader's QoS.
        hash_of_string: the ``RIHS01_...`` type hash of ``std_msgs/msg/String``.
    """

    def __init__(
        self,
        service: FixtureService,
        participant,
        namespace: str,
        names: dict[str, FixtureNames],
        qos,
        hash_of_string: str,
    ):
        from cyclonedds.pub import DataWriter
        from cyclonedds.qos import Policy, Qos
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        from .messages import String

        self.service, self.names = service, names
        qos = Qos(*qos, Policy.Userdata(f"typehash={hash_of_string};".encode()))

        def topic(name: str) -> Any:
            return Topic(participant, "rt" + name, String, qos=qos)

        self.guidance = {n: DataWriter(participant, topic(v.topic("guidance")), qos=qos) for n, v in names.items()}
        self.results = DataWriter(participant, topic(f"/{namespace}/target_result"), qos=qos)
        self.requests = DataReader(participant, topic(f"/{namespace}/target"), qos=qos)
        self.entities: list[Any] = [*self.guidance.values(), self.results, self.requests]  # the bridge deletes them
        self._last_guidance = self._last_tick = -math.inf
        self._taken: dict[str, float] = {}  # signatures of the requests taken within MAX_AGE, and their t

    def tick(self, now: float) -> None:
        """Publish the guidance when due and answer the target requests that came (the bridge's thread)."""
        from .messages import String

        changeover = self.service.changeover
        if changeover is None or now - self._last_tick < TICK:
            return
        self._last_tick = now
        if now - self._last_guidance >= GUIDANCE_PERIOD:
            self._last_guidance = now
            for name, writer in self.guidance.items():
                writer.write(String(json.dumps(changeover.guidance(name))))
        for msg in self.requests.take(N=100):
            data = getattr(msg, "data", None)  # an InvalidSample (a writer gone) has none
            if isinstance(data, str):
                self.results.write(String(json.dumps(self.answer(data, time.time()))))

    def answer(self, data: str, now: float) -> dict[str, Any]:
        """The result of one ``/<ns>/target`` message (set or clear the target, or why not)."""
        try:
            body = json.loads(data)
            payload, signature = body["payload"], body["hmac"]
            req = json.loads(payload)
            fixture, target, by, t = req["fixture"], req["target"], req["by"], float(req["t"])
        except (ValueError, KeyError, TypeError) as exc:
            return {"fixture": None, "t": None, "ok": False, "error": f"malformed target request: {exc}"}
        out: dict[str, Any] = {"fixture": fixture, "t": t, "ok": False}
        token = self.service.config.http.token
        if token is None:
            return {**out, "error": "targets need a token: set [http] token_file in the configuration"}
        if not isinstance(signature, str) or not hmac.compare_digest(signature, sign(payload, token)):
            return {**out, "error": "wrong signature: sign the payload with the service's token"}
        if abs(now - t) > MAX_AGE:
            return {**out, "error": f"t = {t!r} is {now - t:.1f} s from the service's clock (at most {MAX_AGE:g} s)"}
        self._taken = {k: v for k, v in self._taken.items() if abs(now - v) <= MAX_AGE}
        if signature in self._taken:
            return {**out, "error": "this request was already taken"}
        self._taken[signature] = t
        changeover = self.service.changeover
        assert changeover is not None
        who = f"{by} (ROS 2)"
        try:
            if target is None:
                return {**out, "ok": True, "cleared": changeover.clear_target(fixture, who)}
            return {**out, "ok": True, "target": changeover.set_target(fixture, target, who).to_json()}
        except (HexapodError, KeyError) as exc:  # a bad target, an unknown fixture
            log.warning("ros: target request of %r refused: %s", fixture, exc)
            return {**out, "error": str(exc)}
