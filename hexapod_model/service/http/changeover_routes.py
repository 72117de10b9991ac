"""The changeover's HTTP endpoints and the dashboard (Starlette routes joined to the service's application).

Writes need the bearer token (``401`` without it) and name who made them: the optional ``by``
of the body (or the ``X-Operator`` header: a person's name) and the peer's address. Bad bodies are ``422`` with
one line naming the field (``{"error": ..., "field": ...}``; a target the machine's body refuses
adds ``limit`` and its figures: ``docs/changeover.md``); unknown fixtures and recipes ``404``.

* ``PUT /fixtures/NAME/target`` ``{"pose": {...}, "tolerance": {...}}`` -> ``{"target": ...}``;
  ``DELETE`` clears it (``{"cleared": true | false}``); ``GET`` -> ``{"target": ... | null}``
* ``GET /fixtures/NAME/guidance`` -> deviation, per-leg changes, ``in_tolerance``, the clearance of the
  pose and of the target (``docs/changeover.md``)
* ``PUT /recipes/NAME`` ``{"targets": {fixture: target}}``; ``POST /recipes/NAME/activate``;
  ``GET /recipes`` -> every recipe and the active one
* ``GET /`` the dashboard, ``GET /dashboard/FILE`` its assets, ``GET /events`` the server-sent
  event stream it reads (every fixture's guidance, :data:`EVENT_INTERVAL` apart)
"""

from __future__ import annotations

import asyncio
import json
import re
from collections.abc import Callable
from importlib import resources
from typing import Any

from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import Response, StreamingResponse
from starlette.routing import BaseRoute, Route

from ..changeover.changeover import Changeover, UnknownError
from ..targets.target import Target, TargetError
from .app import error_response, json_response, read_json, requires_token, service_of

EVENT_INTERVAL = 0.25  # s between two dashboard events
ASSETS = {"dashboard.js": "text/javascript", "dashboard.css": "text/css", "index.html": "text/html"}
_OPERATOR = re.compile(r"^[\w .@-]{1,64}$")


def _who(request: Request, body: dict | None = None) -> str:
    """``NAME (host:port)`` for the store's ``set_by``: the body's ``by`` or the ``X-Operator`` header, and the peer.

    ``by`` is taken out of ``body``; a name that is not 1-64 letters, digits, spaces, ``. @ -``
    is a :class:`TargetError`.
    """
    client = getattr(request.state, "client", "?")
    by = None if body is None else body.pop("by", None)
    if by is not None and (not isinstance(by, str) or not _OPERATOR.match(by)):
        raise TargetError("by", by, "expected a name of 1-64 letters, digits, spaces, '.', '@' or '-'")
    operator = by or request.headers.get("x-operator", "").strip()
    return f"{operator} ({client})" if operator and _OPERATOR.match(operator) else client


def _changeover(request: Request) -> Changeover:
    """The service's changeover (there once the service is ready, which the application checks first)."""
    changeover = service_of(request).changeover
    if changeover is None:
        raise HTTPException(503, "starting")
    return changeover


async def _call(request: Request, work: Callable[[Changeover], Any]) -> Response:
    """``work(changeover)`` off the event loop (store commits fsync), its JSON-ready result; errors as JSON."""
    changeover = _changeover(request)
    try:
        result = await run_in_threadpool(work, changeover)
    except TargetError as exc:
        return error_response(422, str(exc), field=exc.field, **exc.details)
    except UnknownError as exc:
        return error_response(404, str(exc))
    return json_response(result)


def _target_json(target: Target | None) -> dict[str, Any]:
    return {"target": None if target is None else target.to_json()}


async def _write(request: Request, work: Callable[[Changeover, dict, str], Any]) -> Response:
    """A write with a JSON body: ``work(changeover, body, who)`` (``by`` taken out of the body)."""
    body = await read_json(request)
    try:
        who = _who(request, body)
    except TargetError as exc:
        return error_response(422, str(exc), field=exc.field)
    return await _call(request, lambda c: work(c, body, who))


@requires_token
async def _put_target(request: Request) -> Response:
    name = request.path_params["name"]
    return await _write(request, lambda c, body, who: _target_json(c.set_target(name, body, who)))


@requires_token
async def _delete_target(request: Request) -> Response:
    name, who = request.path_params["name"], _who(request)
    return await _call(request, lambda c: {"cleared": c.clear_target(name, who)})


async def _target(request: Request) -> Response:
    if request.method == "PUT":
        return await _put_target(request)
    if request.method == "DELETE":
        return await _delete_target(request)
    name = request.path_params["name"]
    return await _call(request, lambda c: _target_json(c.target(name)))


async def _guidance(request: Request) -> Response:
    name = request.path_params["name"]
    return await _call(request, lambda c: c.guidance(name))


@requires_token
async def _put_recipe(request: Request) -> Response:
    name = request.path_params["recipe"]
    return await _write(request, lambda c, body, who: {"recipe": c.put_recipe(name, body, who).to_json()})


@requires_token
async def _activate(request: Request) -> Response:
    name, who = request.path_params["recipe"], _who(request)

    def activate(c: Any) -> dict[str, Any]:
        recipe = c.activate(name, who)
        return {"active": recipe.name, "targets": {k: _target_json(c.target(k))["target"] for k in recipe.targets}}

    return await _call(request, activate)


async def _recipes(request: Request) -> Response:
    return await _call(request, lambda c: c.recipes())


async def _events(request: Request) -> StreamingResponse:
    changeover = _changeover(request)

    async def stream():
        yield "retry: 1000\n\n"
        while not await request.is_disconnected():
            yield f"data: {json.dumps(changeover.overview(), allow_nan=False)}\n\n"
            await asyncio.sleep(EVENT_INTERVAL)

    headers = {"Cache-Control": "no-store", "X-Accel-Buffering": "no"}
    return StreamingResponse(stream(), media_type="text/event-stream", headers=headers)


def _asset(name: str) -> Response:
    data = resources.files(__package__).joinpath("dashboard", name).read_bytes()
    return Response(data, media_type=ASSETS[name], headers={"Cache-Control": "no-cache"})


async def _index(request: Request) -> Response:
    return _asset("index.html")


async def _dashboard_file(request: Request) -> Response:
    name = request.path_params["file"]
    if name not in ASSETS:
        return error_response(404, f"no dashboard file {name!r}")
    return _asset(name)


def changeover_routes() -> list[BaseRoute]:
    """The changeover's endpoints and the dashboard."""
    return [
        Route("/", _index, methods=["GET"]),
        Route("/dashboard/{file}", _dashboard_file, methods=["GET"]),
        Route("/events", _events, methods=["GET"]),
        Route("/fixtures/{name}/target", _target, methods=["GET", "PUT", "DELETE"]),
        Route("/fixtures/{name}/guidance", _guidance, methods=["GET"]),
        Route("/recipes", _recipes, methods=["GET"]),
        Route("/recipes/{recipe}", _put_recipe, methods=["PUT"]),
        Route("/recipes/{recipe}/activate", _activate, methods=["POST"]),
    ]
