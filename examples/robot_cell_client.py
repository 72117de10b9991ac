"""Read a fixture's locked pose from the pose service in a robot-cell script (HTTP, standard library only).

    python examples/robot_cell_client.py [--url http://127.0.0.1:8765] [--fixture right] [--timeout 120]
        [--token-file fixture.token]

Start the service first, for instance with simulated encoders (docs/service.md):

    hexapod serve docs/examples/fixture.toml --simulate docs/examples/sim.toml

The script waits until the service answers (it says ``503`` while it starts), lists the
fixtures, then polls the fixture's record until its pose is one a robot may couple to: status
``ok``, ``locked`` and ``stored``, and recent. It never uses the pose of any other record:
only an ``ok`` record carries a pose right to its stated ``sigma``.

A service with ``[http] token_file`` (docs/changeover.md, docs/service.md §3) needs the token
for reads too: pass the same file with ``--token-file`` (or the token with ``--token``, or in
the ``HEXAPOD_TOKEN`` environment variable). A ``401`` or ``403`` stops the script at once and
says which.
"""

import argparse
import json
import os
import sys
import time
import urllib.error
import urllib.request

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--url", default="http://127.0.0.1:8765")
ap.add_argument("--fixture", default="right")
ap.add_argument("--timeout", type=float, default=120.0, help="s to wait for the service and a locked pose")
ap.add_argument("--max-age", type=float, default=1.0, help="s: an older record is not used")
ap.add_argument("--token-file", help="the file of the service's [http] token_file (a token for reads)")
ap.add_argument("--token", help="the bearer token itself (default: $HEXAPOD_TOKEN; --token-file is safer)")
args = ap.parse_args()
token = args.token or os.environ.get("HEXAPOD_TOKEN")
if args.token_file:
    try:
        with open(args.token_file, encoding="utf-8") as f:
            token = f.read().strip()
    except OSError as exc:
        raise SystemExit(f"--token-file: {exc}") from None
HEADERS = {"Authorization": f"Bearer {token}"} if token else {}
FIX = {
    401: "the service wants its bearer token: pass --token-file with the file of its [http] token_file"
    if not token
    else "the token is not the service's: pass the file of its [http] token_file with --token-file",
    403: "the service refuses this request without a configured token: set [http] token_file",
}


def get(path: str) -> dict:
    """One GET of the service, as JSON; a 401 or 403 stops the script with the fix."""
    request = urllib.request.Request(f"{args.url}{path}", headers=HEADERS)
    try:
        with urllib.request.urlopen(request, timeout=2.0) as response:
            return json.load(response)
    except urllib.error.HTTPError as exc:
        if exc.code in FIX:
            raise SystemExit(f"{args.url}{path}: {exc.code} {exc.reason}: {FIX[exc.code]}") from None
        raise


def waiting(what: str, said: set) -> None:
    """Say on stderr, once per distinct ``what``, what the script waits for."""
    if what not in said:
        said.add(what)
        print(f"waiting up to {args.timeout:g} s: {what}", file=sys.stderr, flush=True)


deadline = time.monotonic() + args.timeout
said: set = set()
while True:  # the service may still be starting (connection refused, or 503 while it prepares)
    try:
        fixtures = get("/fixtures")["fixtures"]
        break
    except (urllib.error.URLError, ConnectionError, TimeoutError) as exc:
        if time.monotonic() > deadline:
            raise SystemExit(f"no pose service at {args.url}: {exc}") from None
        starting = isinstance(exc, urllib.error.HTTPError) and exc.code == 503
        waiting(f"the pose service at {args.url} ({'starting' if starting else 'not answering yet'})", said)
        time.sleep(0.5)
print(f"{args.url}: fixtures {', '.join(fixtures)}")
if args.fixture not in fixtures:
    raise SystemExit(f"--fixture {args.fixture!r}: not one of {fixtures}")

while True:
    record = get(f"/fixtures/{args.fixture}/pose")
    fresh = record["t"] is not None and time.time() - record["t"] <= args.max_age
    if record["status"] == "ok" and record["state"] == "locked" and record["stored"] and fresh:
        break
    if time.monotonic() > deadline:
        raise SystemExit(f"{args.fixture}: no locked pose ({record['status']}, {record['state']}, {record['flags']})")
    waiting(f"a locked, stored pose of {args.fixture} (now {record['status']}, {record['state']})", said)
    time.sleep(0.1)

pose, sigma = record["pose"], record["sigma"]  # the platform in the hexapod's base frame: m and degrees
print(
    f"{args.fixture}: locked at x {pose['x']:.6f} y {pose['y']:.6f} z {pose['z']:.6f} m, "
    f"roll {pose['roll']:.4f} pitch {pose['pitch']:.4f} yaw {pose['yaw']:.4f} deg "
    f"(1-sigma {sigma['translation_mm']:.4f} mm, {sigma['rotation_deg']:.4f} deg)"
)
