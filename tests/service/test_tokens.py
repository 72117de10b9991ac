"""The token file is watched: rotation, deletion, a BOM; a deeply nested JSON body is a 422."""

from __future__ import annotations

import logging
import os

import pytest

from hexapod_model.service.config.token import read_token

from .test_http import TOKEN, request, serve, token_file

NEW = "n3w-token-abcdefghijklmnopqrstuv"


def _bearer(token):
    return {"Authorization": f"Bearer {token}", "Content-Type": "application/json"}


@pytest.fixture
def guarded(tmp_path):
    path = token_file(tmp_path)
    service, server = serve(tmp_path, {"token_file": str(path)})
    yield service, server, path
    server.stop()


def test_a_bom_and_trailing_whitespace_are_stripped(tmp_path):
    path = tmp_path / "t.token"
    path.write_bytes(b"\xef\xbb\xbf" + TOKEN.encode() + b" \t\r\n\n")
    path.chmod(0o600)
    assert read_token(path) == TOKEN


@pytest.mark.parametrize("how", ["in place", "by rename"])
def test_a_rotated_token_is_in_force_at_once_and_logged(guarded, caplog, how):
    service, server, path = guarded
    assert request(server, "POST", "/write", b"{}", _bearer(TOKEN))[0] == 200
    if how == "in place":
        path.write_text(NEW + "\n")
    else:
        fresh = path.with_name("fresh.token")
        fresh.write_text(NEW + "\n")
        fresh.chmod(0o600)
        os.replace(fresh, path)
    with caplog.at_level(logging.INFO, logger="hexapod_model.service"):
        assert request(server, "POST", "/write", b"{}", _bearer(TOKEN))[0] == 401  # the old one is refused
        assert request(server, "POST", "/write", b"{}", _bearer(NEW))[0] == 200
        assert request(server, "GET", "/health", headers=_bearer(NEW))[0] == 200
    assert any("token file" in r.getMessage() and "changed" in r.getMessage() for r in caplog.records)
    assert not any(NEW in r.getMessage() or TOKEN in r.getMessage() for r in caplog.records)


@pytest.mark.parametrize("how", ["deleted", "unreadable", "too short"])
def test_a_deleted_or_unreadable_token_file_refuses_writes_and_says_so(guarded, caplog, how):
    service, server, path = guarded
    if how == "deleted":
        path.unlink()
    elif how == "unreadable":
        if os.geteuid() == 0:
            pytest.skip("root reads any file")
        path.chmod(0o000)
    else:
        path.write_text("short\n")
    with caplog.at_level(logging.INFO, logger="hexapod_model.service"):
        status, _, body = request(server, "POST", "/write", b"{}", _bearer(TOKEN))
        assert status == 503 and "token file" in body["error"] and str(path) in body["error"], body
        assert request(server, "GET", "/health", headers=_bearer(TOKEN))[0] == 503
    assert service.writes == []
    assert [r.levelname for r in caplog.records if "token file" in r.getMessage()] == ["ERROR"]  # said once
    path.chmod(0o600) if path.exists() else None
    path.write_text(NEW + "\n")
    path.chmod(0o600)
    assert request(server, "POST", "/write", b"{}", _bearer(NEW))[0] == 200  # fixed: in force again


@pytest.mark.parametrize(
    "body", [b"[" * 100_000 + b"]" * 100_000, b'{"a":' * 200 + b"1" + b"}" * 200], ids=["lists", "objects"]
)
def test_a_deeply_nested_json_body_is_a_422_not_a_recursion_error(guarded, caplog, body):
    service, server, _ = guarded
    with caplog.at_level(logging.INFO):
        status, _, answer = request(server, "POST", "/write", body[:60_000], _bearer(TOKEN))
    assert status in (413, 422) and "error" in answer
    status, _, answer = request(server, "POST", "/write", body[:20_000] if len(body) > 20_000 else body, _bearer(TOKEN))
    assert status == 422 and "deep" in answer["error"], answer
    assert not any("RecursionError" in r.getMessage() for r in caplog.records) and service.writes == []


def test_the_service_takes_a_rotated_token_file_and_refuses_once_it_is_deleted(tmp_path):
    from hexapod_model.service import FixtureService

    from ..conftest import hexapod
    from .helpers import service_config

    path = token_file(tmp_path)
    config = service_config(tmp_path, http={"host": "127.0.0.1", "port": 0, "token_file": str(path)})
    with FixtureService(config, hexapods={"left": hexapod("reference")}) as service:
        server = service.endpoint
        ack = b'{"by": "A. Operator"}'
        assert request(server, "POST", "/fixtures/left/acknowledge", ack, _bearer(TOKEN))[0] == 409  # none waits
        fresh = path.with_name("fresh.token")
        fresh.write_text(NEW + "\n")
        fresh.chmod(0o600)
        os.replace(fresh, path)
        assert request(server, "POST", "/fixtures/left/acknowledge", ack, _bearer(TOKEN))[0] == 401
        assert request(server, "POST", "/fixtures/left/acknowledge", ack, _bearer(NEW))[0] == 409
        assert request(server, "GET", "/health", headers=_bearer(NEW))[0] == 200
        path.unlink()
        status, _, body = request(server, "GET", "/fixtures/left/pose", headers=_bearer(NEW))
        assert status == 503 and str(path) in body["error"]
