"""The dashboard in headless Chromium, for the tests marked ``chromium``: a page's DOM after its scripts ran.

Chromium's ``--dump-dom`` dumps the page when its virtual-time budget ends, and that budget does
not wait for a server-sent event: on a loaded machine the service's first event can reach the
page after the dump (no ``data-updated``: no fixture shown yet), or the page can show a record of
a set that a starved simulator thread left incomplete. Such a dump says nothing of what a test
checks, so :func:`render_until` loads the page again, a bounded number of times, until the dump
shows what the test needs; the test's assertions then run on the last dump either way.
"""

from __future__ import annotations

import http.client
import json
import shutil
import subprocess
from collections.abc import Callable
from html.parser import HTMLParser

from hexapod_model.viz.render import CHROMIUM_NAMES

from .test_http import TOKEN

LOADS = 3  # page loads of render_until before its last dump is taken as it is


class Fields(HTMLParser):
    """``(fixture, field) -> [text, data-value]`` of every element with a ``data-field``."""

    def __init__(self):
        super().__init__()
        self.found: dict[tuple[str | None, str], list] = {}
        self._open: list | None = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "data-field" in a:
            self._open = ["", a.get("data-value")]
            self.found[(a.get("data-fixture"), a["data-field"])] = self._open
        elif self._open is not None and tag not in ("span",):
            self._open = None

    def handle_data(self, data):
        if self._open is not None:
            self._open[0] += data

    def handle_endtag(self, tag):
        self._open = None


def fields(dom: str) -> dict[tuple[str | None, str], list]:
    """:class:`Fields` of a dump."""
    page = Fields()
    page.feed(dom)
    return page.found


def render(url: str, profile, size: tuple[int, int] | None = None) -> str:
    """The DOM of ``url`` after 4 s of Chromium's virtual time; ``size``: the window (CSS px)."""
    chromium = next(shutil.which(n) for n in CHROMIUM_NAMES if shutil.which(n))
    args = [
        chromium,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--no-first-run",
        f"--user-data-dir={profile}",
    ]
    if size is not None:
        args += ["--hide-scrollbars", f"--window-size={size[0]},{size[1]}"]
    args += ["--dump-dom", "--virtual-time-budget=4000", url]
    return subprocess.run(args, capture_output=True, text=True, timeout=120, check=True).stdout


def render_until(
    url: str, profile, ready: Callable[[str], bool], size: tuple[int, int] | None = None, loads: int = LOADS
) -> str:
    """:func:`render` ``url`` again until ``ready(dom)``, at most ``loads`` times; the last dump either way."""
    for _ in range(loads):
        dom = render(url, profile, size)
        if ready(dom):
            break
    return dom


def guidance(address, name: str) -> dict:
    """``GET /fixtures/NAME/guidance`` of the service at ``address`` (asserted 200)."""
    c = http.client.HTTPConnection(*address, timeout=5)
    c.request("GET", f"/fixtures/{name}/guidance", headers={"Authorization": f"Bearer {TOKEN}"})
    r = c.getresponse()
    body = json.loads(r.read())
    c.close()
    assert r.status == 200, body
    return body
