"""The HTTP endpoint (starlette + uvicorn) on 127.0.0.1: methods, limits, the token, TLS, starting."""

from __future__ import annotations

import http.client
import json
import os
import shutil
import socket
import ssl
import subprocess
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest
from starlette.routing import Route

from hexapod_model.service import ConfigError
from hexapod_model.service.http.app import build_app, json_response, read_json, requires_token, service_of
from hexapod_model.service.http.server import HttpServer

from .helpers import service_config

TOKEN = "s3cret-token-0123456789abcdef"


class StubService:
    """What the application needs of a FixtureService: no bus, no solver."""

    def __init__(self, config, ready=True):
        self.config, self.ready, self.writes = config, ready, []

    def starting(self):
        return {"status": "starting", "phase": "compiling the solver's kernels", "uptime_s": 0.1}

    def names(self):
        return ["left"]

    def record_json(self, name):
        return json.dumps({"fixture": name, "status": "ok"}) if name == "left" else None

    def health(self):
        if getattr(self, "broken", False):
            raise RuntimeError("health is broken")
        return {"status": "ok", "store": {"file": "store.sqlite", "error": None}}


@requires_token
async def _write(request):
    body = await read_json(request)
    service_of(request).writes.append((body, request.state.client))
    return json_response({"accepted": body})


def token_file(tmp_path, mode=0o600, text=TOKEN):
    p = tmp_path / "fixture.token"
    p.write_text(text + "\n")
    p.chmod(mode)
    return p


def serve(tmp_path, http=None, ready=True):
    config = service_config(tmp_path, http={"host": "127.0.0.1", "port": 0, **(http or {})})
    service = StubService(config, ready)
    server = HttpServer(build_app(service, [Route("/write", _write, methods=["POST"])]), config.http)
    server.start()
    return service, server


def request(server, method, path, body=None, headers=None, conn=None):
    host, port = server.address
    c = conn or http.client.HTTPConnection(host, port, timeout=5)
    c.request(method, path, body=body, headers=headers or {})
    r = c.getresponse()
    data = r.read()
    if conn is None:
        c.close()
    return r.status, dict(r.getheaders()), (json.loads(data) if data else None)


@pytest.fixture
def served(tmp_path):
    service, server = serve(tmp_path)
    yield service, server
    server.stop()


def test_methods_json_405_head_and_a_post_body_is_not_a_second_request(served):
    _, server = served
    status, headers, body = request(server, "OPTIONS", "/health")
    assert status == 405 and headers["content-type"] == "application/json" and "GET" in headers["allow"]
    assert "error" in body
    status, headers, body = request(server, "HEAD", "/health")
    assert status == 200 and body is None and headers["content-type"] == "application/json"
    conn = http.client.HTTPConnection(*server.address, timeout=5)
    payload = b"GET /fixtures HTTP/1.1\r\nHost: x\r\n\r\n"  # a request hidden in a body
    status, _, body = request(server, "POST", "/fixtures", payload, {"Content-Type": "text/plain"}, conn)
    assert status == 405 and "error" in body
    status, _, body = request(server, "GET", "/fixtures/left/pose", conn=conn)  # same connection: in step
    assert status == 200 and body["fixture"] == "left"
    conn.close()
    status, _, body = request(server, "GET", "/nothing")
    assert status == 404 and "/health" in body["resources"]


def test_200_concurrent_gets_all_answer_and_held_connections_are_bounded_and_timed_out(tmp_path):
    service, server = serve(tmp_path, {"max_connections": 300, "idle_timeout": 0.5})
    try:
        threads_before = threading.active_count()
        held = [socket.create_connection(server.address, timeout=5) for _ in range(150)]
        with ThreadPoolExecutor(max_workers=50) as pool:
            t0 = time.monotonic()
            answers = list(pool.map(lambda _: request(server, "GET", "/health")[0], range(200)))
            elapsed = time.monotonic() - t0
        assert answers == [200] * 200 and elapsed < 10.0
        time.sleep(1.5)  # idle_timeout: the silent connections are closed by the server
        closed = sum(s.recv(1) == b"" for s in held)
        for s in held:
            s.close()
        assert closed == len(held)
        assert threading.active_count() <= threads_before + 1  # no thread per connection
    finally:
        server.stop()


def test_more_connections_than_the_bound_get_503_not_a_hang(tmp_path):
    _, server = serve(tmp_path, {"max_connections": 4, "idle_timeout": 30, "token_file": str(token_file(tmp_path))})
    try:
        # three connections in a request (its body still to come): no place can be made by closing one,
        # and the fourth is the bound (uvicorn answers 503 there)
        held = [socket.create_connection(server.address, timeout=5) for _ in range(3)]
        for s in held:
            s.sendall(f"POST /write HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer {TOKEN}\r\n".encode())
            s.sendall(b"Content-Length: 10\r\n\r\n")
        time.sleep(0.5)
        host, port = server.address
        conn = http.client.HTTPConnection(host, port, timeout=5)
        conn.request("GET", "/health", headers={"Authorization": f"Bearer {TOKEN}"})
        assert conn.getresponse().status == 503  # uvicorn's own answer (plain text), at once
        conn.close()
        for s in held:
            s.close()
    finally:
        server.stop()


def test_token_reads_and_writes(tmp_path):
    service, server = serve(tmp_path, {"token_file": str(token_file(tmp_path))})
    good = {"Authorization": f"Bearer {TOKEN}"}
    try:
        assert request(server, "GET", "/health")[0] == 401
        assert request(server, "GET", "/health", headers={"Authorization": "Bearer wrong-token-000000000"})[0] == 401
        assert request(server, "GET", "/health", headers=good)[0] == 200
        assert request(server, "POST", "/write", b'{"a": 1}')[0] == 401
        status, _, body = request(server, "POST", "/write", b'{"a": 1}', good)
        assert status == 200 and body == {"accepted": {"a": 1}} and service.writes[0][1].startswith("127.0.0.1:")
        assert request(server, "POST", "/write", b"[1]", good)[0] == 400
        assert request(server, "POST", "/write", b"x" * 70_000, good)[0] == 413
    finally:
        server.stop()
    service, server = serve(
        tmp_path / "open", {"token_file": str(token_file(tmp_path)), "allow_unauthenticated_reads": True}
    )
    try:
        assert request(server, "GET", "/health")[0] == 200
        assert request(server, "POST", "/write", b"{}")[0] == 401
    finally:
        server.stop()


def test_without_a_token_reads_answer_and_writes_are_refused(served):
    service, server = served
    status, _, body = request(server, "POST", "/write", b"{}", {"Authorization": f"Bearer {TOKEN}"})
    assert status == 403 and "token_file" in body["error"] and service.writes == []


def test_token_file_mode_and_non_loopback_bind_are_checked(tmp_path):
    with pytest.raises(ConfigError, match="chmod 600"):
        service_config(tmp_path, http={"token_file": str(token_file(tmp_path, 0o644))})
    with pytest.raises(ConfigError, match="at least 16"):
        service_config(tmp_path, http={"token_file": str(token_file(tmp_path, 0o600, "short"))})
    with pytest.raises(ConfigError, match="token_file"):
        service_config(tmp_path, http={"host": "0.0.0.0"})
    assert service_config(tmp_path, http={"host": "0.0.0.0", "allow_unauthenticated_reads": True}).http.token is None
    token_file(tmp_path)
    cfg = service_config(tmp_path, http={"host": "0.0.0.0", "token_file": "fixture.token"})
    assert cfg.http.token == TOKEN and TOKEN not in repr(cfg)  # relative to the configuration's folder


def test_starting_is_503_json(tmp_path):
    service, server = serve(tmp_path, ready=False)
    try:
        status, headers, body = request(server, "GET", "/health")
        assert status == 503 and body["status"] == "starting" and headers["retry-after"] == "1"
        assert request(server, "GET", "/fixtures/left/pose")[0] == 503
        service.ready = True
        assert request(server, "GET", "/health")[0] == 200
    finally:
        server.stop()


def test_an_endpoint_error_is_a_json_500_and_one_log_line(served, caplog):
    service, server = served
    service.broken = True
    status, _, body = request(server, "GET", "/health")
    assert status == 500 and body == {"error": "RuntimeError: health is broken"}
    assert any("health is broken" in m and r.exc_info is None for r, m in zip(caplog.records, caplog.messages))


def test_bad_host_and_port_in_use_name_the_field(tmp_path):
    from hexapod_model.service import ServiceError
    from hexapod_model.service.http.server import bind

    with pytest.raises(ServiceError, match=r"set \[http\] host"):
        bind("no-such-host.invalid", 0)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        with pytest.raises(ServiceError, match=r"port in use \(set \[http\] port\)"):
            bind("127.0.0.1", s.getsockname()[1])


@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs the openssl command to make a certificate")
def test_https_with_certfile_and_keyfile(tmp_path):
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj", "/CN=127.0.0.1",
         "-addext", "subjectAltName=IP:127.0.0.1", "-keyout", str(key), "-out", str(cert)],
        check=True, capture_output=True,
    )  # fmt: skip
    os.chmod(key, 0o600)
    _, server = serve(tmp_path, {"certfile": str(cert), "keyfile": str(key)})
    try:
        assert server.url.startswith("https://")
        context = ssl.create_default_context(cafile=str(cert))
        conn = http.client.HTTPSConnection(*server.address, timeout=5, context=context)
        conn.request("GET", "/fixtures")
        r = conn.getresponse()
        assert r.status == 200 and json.loads(r.read()) == {"fixtures": ["left"]}
        conn.close()
    finally:
        server.stop()
