"""The service over HTTP: the Starlette application and its server (optional ``[service]`` extra), the client.

The application and the server import Starlette and uvicorn: import them from
:mod:`~hexapod_model.service.http.app` and :mod:`~hexapod_model.service.http.server`.
"""

from .client import RequestError, ServiceClient
from .health import health

__all__ = ["RequestError", "ServiceClient", "health"]
