"""``hexapod fixture acknowledge``: acknowledge a latched fault of a running pose service over HTTP."""

from __future__ import annotations

import argparse
import json
import ssl
import sys
import urllib.error
import urllib.request

from ._common import note


def register_action(actions: argparse._SubParsersAction) -> None:
    """Add ``fixture acknowledge`` to the ``fixture`` command's actions."""
    a = actions.add_parser(
        "acknowledge",
        help="acknowledge a fixture's latched fault (a discontinuity, a leg moved while locked)",
        description="POST /fixtures/NAME/acknowledge to the service of FIXTURE.toml, with the bearer token of its "
        "[http] token_file. The service logs who acknowledged, from where and when; records can be ok again "
        "from the next reading set (a locked fixture takes a new lock from its readings as they are).",
    )
    a.add_argument("config", metavar="FIXTURE.toml")
    a.add_argument("fixture", help="the fixture's name")
    a.add_argument("--by", required=True, help="who acknowledges (logged)")
    a.add_argument("--note", default="", help="what was checked or done (logged)")
    a.add_argument("--url", help="the service's URL (default: from [http] in FIXTURE.toml)")
    a.set_defaults(func=run_acknowledge)


def service_url(http) -> str:
    """``http(s)://host:port`` of a service configured with ``http`` (a wildcard host: this machine)."""
    host = "127.0.0.1" if http.host in ("0.0.0.0", "::", "") else http.host
    host = f"[{host}]" if ":" in host else host
    return f"{'https' if http.certfile else 'http'}://{host}:{http.port}"


def run_acknowledge(args: argparse.Namespace) -> int:
    """``hexapod fixture acknowledge``."""
    from ..service import ServiceError, load_config

    config = load_config(args.config)
    if config.http.token is None:
        raise ServiceError(f"{args.config}: writes need a token: set [http] token_file (docs/service.md)")
    url = f"{(args.url or service_url(config.http)).rstrip('/')}/fixtures/{args.fixture}/acknowledge"
    body = json.dumps({"by": args.by, "note": args.note}).encode()
    headers = {"Authorization": f"Bearer {config.http.token}", "Content-Type": "application/json"}
    req = urllib.request.Request(url, data=body, headers=headers, method="POST")
    context = None
    if url.startswith("https:") and config.http.certfile is not None:
        context = ssl.create_default_context(cafile=str(config.http.certfile))
    try:
        with urllib.request.urlopen(req, timeout=10, context=context) as r:
            answer = json.load(r)
    except urllib.error.HTTPError as exc:
        try:
            reason = json.load(exc).get("error", exc.reason)
        except ValueError:
            reason = exc.reason
        raise ServiceError(f"{url}: {exc.code}: {reason}") from None
    except (urllib.error.URLError, OSError) as exc:
        raise ServiceError(f"{url}: cannot reach the service: {getattr(exc, 'reason', exc)}") from None
    fault = answer["acknowledged"]["fault"]
    legs = ", ".join(f"leg {k}" for k in fault["legs"]) or "no leg named"
    note("fixture", f"{args.fixture}: {fault['kind']} ({legs}) acknowledged by {args.by}")
    sys.stdout.flush()
    return 0
