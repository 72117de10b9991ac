"""Capacity under a slowloris: connections that never finish their headers do not starve a polling client."""

from __future__ import annotations

import http.client
import socket
import time

from .test_http import TOKEN, serve, token_file


def status_of(server, path, headers) -> int:
    """The status of one GET (uvicorn's own ``503`` is plain text)."""
    c = http.client.HTTPConnection(*server.address, timeout=5)
    try:
        c.request("GET", path, headers=headers)
        r = c.getresponse()
        r.read()
        return r.status
    except OSError as exc:
        return -1 if exc else 0
    finally:
        c.close()


def test_a_polling_client_reads_through_200_partial_header_connections(tmp_path):
    service, server = serve(tmp_path, {"token_file": str(token_file(tmp_path))})  # default limits: 64 connections
    held: list[socket.socket] = []
    try:
        for _ in range(200):  # from other ports of this machine; each sends a request line and one header
            try:
                s = socket.create_connection(server.address, timeout=2)
                s.sendall(b"GET /health HTTP/1.1\r\nHost: x\r\n")
                held.append(s)
            except OSError:
                pass
        time.sleep(0.5)  # a slowloris holds its connections open for long
        headers = {"Authorization": f"Bearer {TOKEN}"}
        answers = []
        deadline = time.monotonic() + 20.0
        for _ in range(30):  # a robot polling its fixture's pose
            if time.monotonic() > deadline:
                break
            for s in held[:50]:  # the slowloris keeps its connections busy with one more header byte
                try:
                    s.send(b"X")
                except OSError:
                    pass
            answers.append(status_of(server, "/fixtures/left/pose", headers))
            time.sleep(0.02)
        assert answers.count(200) == len(answers) == 30, answers
    finally:
        for s in held:
            s.close()
        server.stop()
