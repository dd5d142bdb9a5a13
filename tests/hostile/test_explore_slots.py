"""The explorer keeps a slot for the user (issue 46): 200 open ``/api/events`` streams, or 200 connections that
never finish their headers, or both, held from the same address as the browser, and a normal request is still
served within a second (:mod:`brdfnorm.explore.guard` evicts the oldest waiting connection, then the oldest
stream, to make room)."""

from __future__ import annotations

import os
import socket
import time

import httpx
import pytest

os.environ.setdefault("BRDFNORM_NO_BROWSER", "1")
from brdfnorm.explore import Catalog, background  # noqa: E402
from brdfnorm.explore.guard import MAX_CONNECTIONS  # noqa: E402


def _open(host: str, port: int, count: int, request: bytes) -> list[socket.socket]:
    sockets = []
    for _ in range(count):
        sock = socket.create_connection((host, port), timeout=5)
        sock.sendall(request)
        sockets.append(sock)
    return sockets


def _held(sockets: list[socket.socket]) -> int:
    """How many of ``sockets`` the server still holds open (reading what it sent, without blocking)."""
    count = 0
    for sock in sockets:
        sock.setblocking(False)
        try:
            while True:
                if not sock.recv(65536):
                    break
        except BlockingIOError:
            count += 1
        except OSError:
            pass
    return count


@pytest.mark.slow
@pytest.mark.parametrize("streams, half_open", [(200, 0), (0, 200), (200, 200)])
def test_a_normal_request_is_served_within_a_second(streams: int, half_open: int):
    with background(Catalog.build(["phong"])) as url:
        host, port = url.split("//")[1].rstrip("/").split(":")
        head = f"Host: {host}:{port}\r\n".encode()
        stream = b"GET /api/events HTTP/1.1\r\n" + head + b"Accept: text/event-stream\r\n\r\n"
        held = _open(host, int(port), streams, stream)
        held += _open(host, int(port), half_open, b"GET /api/models HTTP/1.1\r\n" + head + b"X-Slow: 1")
        time.sleep(0.5)  # the server has accepted them all
        with httpx.Client(timeout=5) as client:
            start = time.monotonic()
            response = client.get(url + "api/models")
            elapsed = time.monotonic() - start
        assert response.status_code == 200 and response.json(), response.text[:200]
        assert elapsed < 1.0, f"served after {elapsed:.2f} s"
        assert _held(held) <= MAX_CONNECTIONS
        for sock in held:
            sock.close()
