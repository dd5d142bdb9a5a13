"""The explorer's server against abandoned connections (issue 35): 200 half-open sockets on 127.0.0.1 — some
silent, some having sent half a request's headers, some half a body — are dropped within seconds
(:data:`brdfnorm.explore.guard.REQUEST_READ_SECONDS`), and the server keeps answering."""

from __future__ import annotations

import os
import socket
import time

import httpx
import pytest

os.environ.setdefault("BRDFNORM_NO_BROWSER", "1")
from brdfnorm.explore import Catalog, background  # noqa: E402
from brdfnorm.explore.guard import MAX_CONNECTIONS, REQUEST_READ_SECONDS  # noqa: E402

PARTIAL = [b"", b"GET / HTTP/1.1\r\nHost: 127.0.0.1", b"POST /api/evaluate HTTP/1.1\r\nHost: 127.0.0.1\r\n"
           b"Content-Type: application/json\r\nContent-Length: 100\r\n\r\n{\"model\":"]


def _closed_by_server(sock: socket.socket) -> bool:
    """True once the server has closed (or reset) the connection; False while it still holds it."""
    sock.setblocking(False)
    try:
        while True:
            data = sock.recv(65536)
            if not data:
                return True
    except BlockingIOError:
        return False
    except OSError:  # ECONNRESET
        return True


@pytest.mark.slow
def test_two_hundred_half_open_connections_are_dropped_within_seconds():
    with background(Catalog.build(["phong"])) as url:
        host, port = url.split("//")[1].rstrip("/").split(":")
        sockets = []
        start = time.monotonic()
        for i in range(200):
            sock = socket.create_connection((host, int(port)), timeout=5)
            if PARTIAL[i % 3]:
                sock.sendall(PARTIAL[i % 3])
            sockets.append(sock)
        time.sleep(1.0)  # the server accepts them in its own thread
        open_now = sum(not _closed_by_server(s) for s in sockets)
        assert open_now <= MAX_CONNECTIONS  # the limit: the rest were closed at once
        while time.monotonic() - start < REQUEST_READ_SECONDS + 5:
            if all(_closed_by_server(s) for s in sockets):
                break
            time.sleep(0.2)
        dropped_after = time.monotonic() - start
        held = sum(not _closed_by_server(s) for s in sockets)
        for sock in sockets:
            sock.close()
        assert held == 0, f"{held} of 200 half-open connections still held after {dropped_after:.1f} s"
        assert dropped_after < REQUEST_READ_SECONDS + 5
        # and the server still answers
        assert httpx.get(url, timeout=30).status_code == 200


@pytest.mark.slow
def test_a_silent_connection_is_closed_after_the_read_deadline():
    with background(Catalog.build(["phong"])) as url:
        host, port = url.split("//")[1].rstrip("/").split(":")
        sock = socket.create_connection((host, int(port)), timeout=5)
        sock.sendall(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n")
        start = time.monotonic()
        sock.settimeout(REQUEST_READ_SECONDS + 10)
        try:
            data = sock.recv(65536)
        except OSError:
            data = b""
        assert data == b"" and REQUEST_READ_SECONDS - 0.5 < time.monotonic() - start < REQUEST_READ_SECONDS + 5
        sock.close()
        assert httpx.get(url, timeout=30).status_code == 200
