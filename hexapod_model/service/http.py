"""The HTTP endpoint: the standard library's threaded server, JSON out, GET only.

* ``GET /fixtures`` -> ``{"fixtures": [names]}``
* ``GET /fixtures/NAME/pose`` -> the fixture's latest record (404 for an unknown name)
* ``GET /health`` -> ``{"status": "ok" | "degraded", ...}`` (see :meth:`FixtureService.health`)

Anything else is 404 (405 for other methods). Requests are logged at DEBUG level through
:mod:`logging`; nothing is printed.
"""

from __future__ import annotations

import errno
import json
import logging
import threading
from collections.abc import Callable
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import unquote, urlsplit

from .errors import ServiceError

log = logging.getLogger(__name__)


class Routes:
    """What the server answers: callables returning JSON-ready objects (``None``: not found)."""

    def __init__(
        self,
        names: Callable[[], list[str]],
        record: Callable[[str], dict | None],
        health: Callable[[], dict],
        record_json: Callable[[str], str | None] | None = None,
    ):
        self.names, self.record, self.health = names, record, health
        self.record_json = record_json  # the latest record as JSON text, serialised once per record

    def get(self, path: str) -> tuple[int, object]:
        """Status code and body of ``GET path`` (a ``str`` body is JSON text already)."""
        parts = [unquote(p) for p in urlsplit(path).path.split("/") if p]
        if parts == ["fixtures"]:
            return 200, {"fixtures": self.names()}
        if parts == ["health"]:
            return 200, self.health()
        if len(parts) == 3 and parts[0] == "fixtures" and parts[2] == "pose":
            rec = self.record(parts[1]) if self.record_json is None else self.record_json(parts[1])
            if rec is not None:
                return 200, rec
            return 404, {"error": f"no fixture {parts[1]!r}", "fixtures": self.names()}
        return 404, {
            "error": f"no such resource {path!r}",
            "resources": ["/fixtures", "/fixtures/NAME/pose", "/health"],
        }


class _Handler(BaseHTTPRequestHandler):
    server: _Server
    protocol_version = "HTTP/1.1"

    def _send(self, code: int, body: object) -> None:
        text = body if isinstance(body, str) else json.dumps(body, allow_nan=False)
        data = text.encode("utf-8")
        self.send_response(code)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(data)

    def do_GET(self) -> None:  # noqa: N802 - the stdlib's name
        """Answer from the routes."""
        try:
            code, body = self.server.routes.get(self.path)
        except Exception as exc:  # noqa: BLE001 - a request must not kill the server
            log.exception("GET %s failed", self.path)
            code, body = 500, {"error": f"{type(exc).__name__}: {exc}"}
        self._send(code, body)

    def _refuse(self) -> None:
        self._send(405, {"error": "only GET is served"})

    do_POST = do_PUT = do_DELETE = do_PATCH = _refuse  # noqa: N815

    def log_message(self, format: str, *args) -> None:  # noqa: A002 - the stdlib's signature
        """Requests go to the ``logging`` DEBUG level, not to stderr."""
        log.debug("%s " + format, self.address_string(), *args)


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    routes: Routes


class HttpEndpoint:
    """A :class:`ThreadingHTTPServer` on ``host:port`` in a thread of its own.

    Args:
        host: address to bind (``127.0.0.1`` unless you mean to serve other machines).
        port: port; 0 takes a free one (see :attr:`address`).
        routes: what to answer.

    Raises:
        ServiceError: the address is in use or cannot be bound.
    """

    def __init__(self, host: str, port: int, routes: Routes):
        try:
            self.server = _Server((host, port), _Handler)
        except OSError as exc:
            why = "port in use" if exc.errno == errno.EADDRINUSE else (exc.strerror or str(exc))
            raise ServiceError(f"HTTP address {host}:{port}: {why} (set [http] port in the configuration)") from None
        self.server.routes = routes
        self._thread = threading.Thread(target=self.server.serve_forever, name="hexapod-http", daemon=True)

    @property
    def address(self) -> tuple[str, int]:
        """The bound ``(host, port)``."""
        host, port = self.server.server_address[:2]
        return str(host), int(port)

    def start(self) -> None:
        """Serve in the background."""
        self._thread.start()

    def stop(self) -> None:
        """Stop serving and close the socket."""
        if self._thread.is_alive():
            self.server.shutdown()
        self.server.server_close()
