"""The HTTP server: uvicorn in a thread of its own, on a socket bound before it starts.

Bounded: at most ``[http] max_connections`` connections are served at once (more get ``503``);
a connection that sends no request, or stays idle between requests, is closed after
``idle_timeout``, and sooner when a new connection needs its place (the oldest such one, from
an address holding more than ``max_connections_per_address`` first: a slowloris of unfinished
headers cannot keep a polling client out); a stop waits at most a second for the requests underway (a server-sent event
stream is cut). HTTPS with ``[http] certfile`` / ``keyfile``.
"""

from __future__ import annotations

import asyncio
import errno
import logging
import socket
import time
from typing import Any

from ...extras import install_hint
from ..config.settings import HttpConfig
from ..errors import ServiceError
from ..threads import NamedThread

log = logging.getLogger(__name__)
GRACE = 0.25  # s: a connection this young is never closed for another (its request may be on its way)
INSTALL_HINT = f"the HTTP endpoint needs starlette and uvicorn: {install_hint('service')}"


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port``; :class:`ServiceError` names what is wrong with the address."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except (socket.gaierror, UnicodeError) as exc:
        raise ServiceError(f"[http] host {host!r}: not an address of this machine ({exc}); set [http] host") from None
    family, kind, proto, _, address = infos[0]
    sock = socket.socket(family, kind, proto)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(128)
    except OSError as exc:
        sock.close()
        if exc.errno == errno.EADDRINUSE:
            raise ServiceError(f"HTTP address {host}:{port}: port in use (set [http] port)") from None
        why = exc.strerror or str(exc)
        raise ServiceError(f"HTTP address {host}:{port}: {why} (set [http] host, or [http] port)") from None
    sock.setblocking(False)
    return sock


def _protocol(idle_timeout: float, limit: int, per_address: int) -> type:
    """The h11 protocol of uvicorn, bounded against connections that never send a request.

    * A connection that sends no complete request within ``idle_timeout`` is closed (a request
      line and headers trickled byte by byte do not keep it).
    * When a new connection brings the server to ``limit`` connections, or its address to more
      than ``per_address``, the oldest connection that is not in a request (its headers
      unfinished, or idle between requests) and older than :data:`GRACE` is closed to make
      room: from that address first.
      So 200 connections that never finish their headers cannot keep a polling client out;
      only connections in a request count against the ``503`` of ``limit``.
    """
    from uvicorn.protocols.http.h11_impl import H11Protocol

    class Protocol(H11Protocol):
        def connection_made(self, transport: Any) -> None:
            super().connection_made(transport)
            self._opened = self.loop.time()
            self._first_request = self.loop.call_later(idle_timeout, self._no_request)
            self._make_room()

        def _no_request(self) -> None:
            if self.cycle is None and not self.transport.is_closing():
                self.transport.close()

        def _make_room(self) -> None:
            peer = self.client[0] if self.client else None
            born = self._opened - GRACE  # a connection younger than GRACE may not have sent its request yet
            others = [c for c in self.connections if c is not self and isinstance(c, Protocol)]
            over_all = len(others) + 2 - limit  # leave one place: uvicorn answers 503 at `limit`
            over_address = sum(1 for c in others if c.client and c.client[0] == peer) + 1 - per_address
            if over_all <= 0 and over_address <= 0:
                return
            waiting = sorted(
                (c for c in others if c.cycle is None and c._opened < born and not c.transport.is_closing()),
                key=lambda c: (not (c.client and c.client[0] == peer), c._opened),  # this address first, oldest first
            )
            for c in waiting:
                same = bool(c.client and c.client[0] == peer)
                if over_all <= 0 and (over_address <= 0 or not same):
                    break
                c.transport.close()
                over_all -= 1
                over_address -= same

        def connection_lost(self, exc: Exception | None) -> None:
            self._first_request.cancel()
            super().connection_lost(exc)

    return Protocol


class HttpServer:
    """Serve an ASGI ``app`` on ``config``'s address, in a background thread.

    Args:
        app: the application (:func:`hexapod_model.service.http.app.build_app`).
        config: address, TLS files and limits.

    Raises:
        ServiceError: the address cannot be bound, or starlette/uvicorn are not installed.
    """

    def __init__(self, app: Any, config: HttpConfig):
        try:
            import uvicorn
        except ImportError:
            raise ServiceError(INSTALL_HINT) from None
        self.sock = bind(config.host, config.port)
        self.tls = config.certfile is not None
        uv_config = uvicorn.Config(
            app,
            http=_protocol(config.idle_timeout, config.max_connections, config.max_connections_per_address),
            lifespan="off",
            log_config=None,
            access_log=False,
            limit_concurrency=config.max_connections,
            timeout_keep_alive=max(1, round(config.idle_timeout)),
            timeout_graceful_shutdown=1,
            ssl_certfile=None if config.certfile is None else str(config.certfile),
            ssl_keyfile=None if config.keyfile is None else str(config.keyfile),
            server_header=False,
        )
        try:
            uv_config.load()
        except Exception as exc:  # noqa: BLE001 - a bad certificate or key: one line
            self.sock.close()
            raise ServiceError(f"[http] certfile/keyfile: cannot be used: {exc}") from None
        self.server = uvicorn.Server(uv_config)
        self._thread = NamedThread(target=self._run, name="hx-http")

    def _run(self) -> None:
        try:
            asyncio.run(self.server.serve(sockets=[self.sock]))
        except Exception as exc:  # noqa: BLE001 - the thread's end is logged, never a traceback
            log.error("HTTP server stopped: %s: %s", type(exc).__name__, exc)

    @property
    def address(self) -> tuple[str, int]:
        """The bound ``(host, port)``."""
        host, port = self.sock.getsockname()[:2]
        return str(host), int(port)

    @property
    def url(self) -> str:
        """``http(s)://host:port``."""
        host, port = self.address
        return f"{'https' if self.tls else 'http'}://{host}:{port}"

    def start(self, timeout: float = 5.0) -> None:
        """Serve in the background; returns once the socket is served (or after ``timeout`` s)."""
        self._thread.start()
        deadline = time.monotonic() + timeout
        while not self.server.started and self._thread.is_alive() and time.monotonic() < deadline:
            time.sleep(0.005)

    def stop(self, timeout: float = 1.5) -> None:
        """Stop serving (requests underway get up to a second) and close the socket."""
        if self._thread.is_alive():
            self.server.should_exit = True
            self._thread.join(timeout)
            if self._thread.is_alive():
                self.server.force_exit = True
                self._thread.join(0.5)
        self.sock.close()
