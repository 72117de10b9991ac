"""The HTTP application (Starlette): JSON in and out, the bearer token, ``503`` while starting.

Endpoints of the service itself:

* ``GET /fixtures`` -> ``{"fixtures": [names]}``
* ``GET /fixtures/NAME/pose`` -> the fixture's latest record (404 for an unknown name)
* ``GET /health`` -> ``{"status": "ok" | "degraded", "problems": [...], ...}`` (``FixtureService.health``)
* ``POST /fixtures/NAME/acknowledge`` ``{"by": "who", "note": "..."}`` (token) -> the fault acknowledged

Every answer is JSON, errors too (``{"error": ...}``): 404 for an unknown path, 405 (with
``Allow``) for a method a path does not serve, ``401`` without the right bearer token, ``503
{"status": "starting"}`` until the solver's kernels are compiled. Add endpoints by passing
Starlette routes to :func:`build_app` (or ``FixtureService(..., routes=[...])``)::

    from starlette.routing import Route
    from hexapod_model.service.http.app import json_response, read_json, requires_token, service_of

    @requires_token                              # a write: the bearer token, always
    async def set_target(request):
        body = await read_json(request)          # 400/413 as JSON when it is not a small JSON object
        service = service_of(request)            # the FixtureService
        return json_response({"accepted": body, "by": request.state.client})

    FixtureService(config, routes=[Route("/fixtures/{name}/target", set_target, methods=["POST"])])

Reads need the token too when one is configured, unless ``[http] allow_unauthenticated_reads``;
that check covers every route, added ones included (HTTP and WebSocket).
"""

from __future__ import annotations

import functools
import json
import logging
from collections.abc import Awaitable, Callable, Mapping, Sequence
from typing import Any

from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import Response
from starlette.routing import BaseRoute, Route
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from ..config.token import bearer_matches
from ..config.token_watch import TokenWatch
from .view import ServiceView

log = logging.getLogger(__name__)
Endpoint = Callable[[Request], Awaitable[Response]]
MAX_BODY = 65_536  # bytes of a request body read by read_json
MAX_DEPTH = 32  # nesting of a request body's arrays and objects
RESOURCES = ["/fixtures", "/fixtures/NAME/pose", "/fixtures/NAME/acknowledge", "/health"]


def json_response(body: object, status: int = 200, headers: Mapping[str, str] | None = None) -> Response:
    """A JSON response (``body`` a JSON-ready object, or a ``str`` that is JSON text already); never cached."""
    text = body if isinstance(body, str) else json.dumps(body, allow_nan=False)
    all_headers = {"Cache-Control": "no-store", **(headers or {})}
    return Response(text, status, all_headers, media_type="application/json")


def error_response(status: int, message: str, headers: Mapping[str, str] | None = None, **extra: Any) -> Response:
    """``{"error": message, **extra}`` with ``status``."""
    return json_response({"error": message, **extra}, status, headers)


def service_of(request: Request) -> ServiceView:
    """The :class:`~hexapod_model.service.service.FixtureService` behind the application."""
    return request.app.state.service


def client_of(scope: Scope) -> str:
    """``host:port`` of the peer (``?`` when the server does not know it)."""
    client = scope.get("client")
    return f"{client[0]}:{client[1]}" if client else "?"


def requires_token(endpoint: Endpoint) -> Endpoint:
    """Decorate a write endpoint: ``401`` without ``Authorization: Bearer <token>``, ``403`` when no token is set.

    A service without ``[http] token_file`` accepts no writes at all. The endpoint finds the
    peer's ``host:port`` in ``request.state.client`` (for its log line of who did what).
    """

    @functools.wraps(endpoint)
    async def checked(request: Request) -> Response:
        tokens: TokenWatch = request.app.state.tokens
        if not tokens.configured:
            return error_response(403, "writes need a token: set [http] token_file in the configuration")
        token, problem = tokens.current()
        if token is None:
            return error_response(503, problem or "no token in force", {"Retry-After": "5"})
        if not bearer_matches(request.headers.get("authorization"), token):
            return _unauthorized()
        request.state.client = client_of(request.scope)
        return await endpoint(request)

    return checked


async def read_json(request: Request, max_bytes: int = MAX_BODY) -> dict:
    """The request body as a JSON object; ``HTTPException`` 413 (too long), 400 (not a JSON object) or 422.

    422: arrays and objects nested deeper than :data:`MAX_DEPTH` (checked before parsing: no
    recursion error).
    """
    declared = request.headers.get("content-length")
    if declared is not None and (not declared.isdigit() or int(declared) > max_bytes):
        raise HTTPException(413, f"body longer than {max_bytes} bytes")
    data = b""
    async for chunk in request.stream():
        data += chunk
        if len(data) > max_bytes:
            raise HTTPException(413, f"body longer than {max_bytes} bytes")
    depth = nesting(data)
    if depth > MAX_DEPTH:
        raise HTTPException(422, f"body nested {depth} deep; at most {MAX_DEPTH} levels of arrays and objects")
    try:
        body = json.loads(data) if data else None
    except (ValueError, UnicodeDecodeError) as exc:
        raise HTTPException(400, f"body is not JSON: {exc}") from None
    if not isinstance(body, dict):
        raise HTTPException(400, "body must be a JSON object")
    return body


def nesting(data: bytes) -> int:
    """Deepest nesting of ``[`` and ``{`` in JSON text ``data`` (brackets inside strings not counted).

    A body with at most :data:`MAX_DEPTH` opening brackets is not scanned: their number, an
    upper bound of the nesting, is returned (enough for the check against the limit).
    """
    opening = data.count(b"[") + data.count(b"{")
    if opening <= MAX_DEPTH:
        return opening
    depth = deepest = 0
    in_string = escaped = False
    for byte in data:
        if in_string:
            if escaped:
                escaped = False
            elif byte == 0x5C:  # backslash
                escaped = True
            elif byte == 0x22:  # quote
                in_string = False
        elif byte == 0x22:
            in_string = True
        elif byte in (0x5B, 0x7B):  # [ {
            depth += 1
            deepest = max(deepest, depth)
        elif byte in (0x5D, 0x7D):  # ] }
            depth -= 1
    return deepest


def _unauthorized() -> Response:
    return error_response(401, "missing or wrong bearer token", {"WWW-Authenticate": "Bearer"})


# ----- the service's own endpoints -----
async def _fixtures(request: Request) -> Response:
    return json_response({"fixtures": service_of(request).names()})


async def _pose(request: Request) -> Response:
    service, name = service_of(request), request.path_params["name"]
    text = service.record_json(name)
    if text is None:
        return error_response(404, f"no fixture {name!r}", fixtures=service.names())
    return json_response(text)


async def _health(request: Request) -> Response:
    return json_response(service_of(request).health())


@requires_token
async def _acknowledge(request: Request) -> Response:
    service, name = service_of(request), request.path_params["name"]
    body = await read_json(request)
    by, note = body.get("by"), body.get("note", "")
    if not isinstance(by, str) or not 0 < len(by.strip()) <= 100:
        return error_response(400, 'give who acknowledges: {"by": "NAME"} (1 to 100 characters)')
    if not isinstance(note, str) or len(note) > 1000:
        return error_response(400, "note: text of at most 1000 characters")
    if name not in service.names():
        return error_response(404, f"no fixture {name!r}", fixtures=service.names())
    ack = service.acknowledge(name, by.strip(), request.state.client, note)
    if ack is None:
        return error_response(409, f"fixture {name!r}: no fault waits for an acknowledgement")
    return json_response({"acknowledged": ack.describe()})


def core_routes() -> list[BaseRoute]:
    """The service's endpoints: reads (``GET``; ``HEAD`` answers the same headers) and the acknowledgement."""
    return [
        Route("/fixtures", _fixtures, methods=["GET"]),
        Route("/fixtures/{name}/pose", _pose, methods=["GET"]),
        Route("/fixtures/{name}/acknowledge", _acknowledge, methods=["POST"]),
        Route("/health", _health, methods=["GET"]),
    ]


# ----- the application -----
def _static(path: str) -> bool:
    """The dashboard's page and assets: no data, served without the token (its script sends the token)."""
    return path == "/" or path.startswith("/dashboard/")


class _Gate:
    """ASGI middleware: ``503 starting`` before the service is ready, the read token, no traceback out."""

    def __init__(self, app: ASGIApp, service: ServiceView, tokens: TokenWatch):
        self.app, self.service, self.tokens = app, service, tokens

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        refusal = None
        if not self.service.ready:
            refusal = json_response(self.service.starting(), 503, {"Retry-After": "1"})
        elif self.service.config.http.reads_need_token and not _static(scope.get("path", "")):
            token, problem = self.tokens.current()
            headers = dict(scope.get("headers") or [])
            if token is None:
                refusal = error_response(503, problem or "no token in force", {"Retry-After": "5"})
            elif not bearer_matches(headers.get(b"authorization", b"").decode("latin-1"), token):
                refusal = _unauthorized()
        if refusal is not None:
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 1008})
            else:
                await refusal(scope, receive, send)
            return
        started = False

        async def tracked(message: Message) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, receive, tracked)
        except Exception as exc:  # noqa: BLE001 - one line in the log, a JSON 500 out, no traceback
            log.error("%s %s failed: %s: %s", scope.get("method", "WS"), scope.get("path"), type(exc).__name__, exc)
            if scope["type"] == "http" and not started:
                await error_response(500, f"{type(exc).__name__}: {exc}")(scope, receive, send)


async def _http_error(request: Request, exc: Exception) -> Response:
    assert isinstance(exc, HTTPException)
    if exc.status_code == 404:
        return error_response(404, f"no such resource {request.url.path!r}", resources=RESOURCES)
    if exc.status_code == 405:
        return error_response(405, f"{request.method} is not served here", exc.headers)
    return error_response(exc.status_code, str(exc.detail), exc.headers)


def build_app(service: ServiceView, routes: Sequence[BaseRoute] = ()) -> Starlette:
    """The Starlette application of ``service``: its endpoints, then ``routes`` (yours).

    ``app.state.service`` is the service (:func:`service_of` in an endpoint); ``app.state.tokens``
    the watched token file (:class:`~hexapod_model.service.config.token_watch.TokenWatch`).
    """
    http = service.config.http
    tokens = TokenWatch(http.token_file, http.token)
    app = Starlette(
        routes=[*core_routes(), *routes],
        middleware=[Middleware(_Gate, service=service, tokens=tokens)],
        exception_handlers={HTTPException: _http_error},
    )
    app.state.service, app.state.tokens = service, tokens
    return app
