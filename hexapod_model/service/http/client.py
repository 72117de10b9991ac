"""A client of a running service's HTTP endpoints (the standard library's urllib): targets, recipes, guidance.

>>> from hexapod_model.service import ServiceClient, load_config
>>> client = ServiceClient.for_config(load_config("fixture.toml"), operator="anna")   # doctest: +SKIP
>>> client.set_target("right", {"x": 0.01, "y": -0.02, "z": 0.41, "roll": 5, "pitch": -3, "yaw": 10}, 0.1, 0.05)
>>> client.guidance("right")["legs"]

The token is the configuration's ``[http] token_file``. A refusal raises :class:`ServiceError`
with the service's one-line reason (and the HTTP status in :attr:`ServiceError.status`).
"""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from typing import Any
from urllib.parse import quote

from ..config.settings import ServiceConfig
from ..errors import ServiceError


class RequestError(ServiceError):
    """The service refused a request: ``status`` is the HTTP status, the message its reason."""

    def __init__(self, status: int, message: str):
        self.status = status
        super().__init__(message)


class ServiceClient:
    """Requests to ``url`` with the bearer ``token`` (``None``: reads only, where the service allows them).

    Args:
        url: ``http://HOST:PORT`` of the service.
        token: the bearer token, or None.
        operator: the name sent as ``X-Operator`` with writes (stored as who set a target).
        timeout: seconds per request.
    """

    def __init__(self, url: str, token: str | None = None, operator: str | None = None, timeout: float = 10.0):
        self.url, self.token, self.operator, self.timeout = url.rstrip("/"), token, operator, timeout

    @classmethod
    def for_config(cls, config: ServiceConfig, operator: str | None = None, url: str | None = None) -> ServiceClient:
        """A client of the service ``config`` describes (its address, scheme and token)."""
        h = config.http
        if url is None:
            if h.port == 0:
                raise ServiceError(f"{config.source}: [http] port = 0 (any free port): give the service's URL (--url)")
            host = "127.0.0.1" if h.host in ("0.0.0.0", "", "::") else h.host
            host = f"[{host}]" if ":" in host else host
            url = f"{'https' if h.certfile else 'http'}://{host}:{h.port}"
        return cls(url, h.token, operator)

    def request(self, method: str, path: str, body: Any = None) -> Any:
        """``method path`` with a JSON ``body``; the answer's JSON, or :class:`RequestError`."""
        headers = {"Accept": "application/json"}
        data = None
        if body is not None:
            data = json.dumps(body, allow_nan=False).encode("utf-8")
            headers["Content-Type"] = "application/json"
        if self.token:
            headers["Authorization"] = f"Bearer {self.token}"
        if self.operator:
            headers["X-Operator"] = self.operator
        req = urllib.request.Request(self.url + path, data=data, method=method, headers=headers)
        try:
            with urllib.request.urlopen(req, timeout=self.timeout) as r:
                return json.load(r)
        except urllib.error.HTTPError as exc:
            try:
                reason = json.load(exc).get("error", exc.reason)
            except (ValueError, AttributeError):
                reason = exc.reason
            raise RequestError(exc.code, f"{method} {path}: {exc.code} {reason}") from None
        except (urllib.error.URLError, OSError) as exc:
            why = getattr(exc, "reason", exc)
            raise RequestError(0, f"no service at {self.url} ({why}): is hexapod serve running?") from None

    # ----- the changeover -----
    def guidance(self, fixture: str) -> dict:
        """``GET /fixtures/NAME/guidance``."""
        return self.request("GET", f"/fixtures/{quote(fixture)}/guidance")

    def set_target(self, fixture: str, pose: dict, translation_mm: float, rotation_deg: float) -> dict:
        """``PUT /fixtures/NAME/target``: ``pose`` as x, y, z (m) and roll, pitch, yaw (deg) or a quaternion."""
        body = {"pose": pose, "tolerance": {"translation_mm": translation_mm, "rotation_deg": rotation_deg}}
        return self.request("PUT", f"/fixtures/{quote(fixture)}/target", body)["target"]

    def clear_target(self, fixture: str) -> bool:
        """``DELETE /fixtures/NAME/target``: False when there was none."""
        return self.request("DELETE", f"/fixtures/{quote(fixture)}/target")["cleared"]

    def put_recipe(self, name: str, targets: dict) -> dict:
        """``PUT /recipes/NAME`` with ``{"targets": targets}``."""
        return self.request("PUT", f"/recipes/{quote(name)}", {"targets": targets})["recipe"]

    def activate(self, name: str) -> dict:
        """``POST /recipes/NAME/activate``."""
        return self.request("POST", f"/recipes/{quote(name)}/activate")

    def recipes(self) -> dict:
        """``GET /recipes``: ``{"active", "recipes"}``."""
        return self.request("GET", "/recipes")
