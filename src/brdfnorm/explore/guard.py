"""The explorer's HTTP connections, bounded (issue 35): uvicorn's h11 protocol with a deadline for reading each
request and limits on the connections held.

uvicorn times out idle keep-alive connections only after a response; a connection that sends nothing, or half a
request's headers, and waits, was held forever (200 such sockets were all still open after 20 s). Here every
connection must deliver a complete request (headers and body) within :data:`REQUEST_READ_SECONDS` of starting to
wait for one, or it is closed; at most :data:`MAX_CONNECTIONS` connections are held at once and at most
:data:`MAX_PER_CLIENT` from one peer address (the explorer listens on loopback, where every client is 127.0.0.1,
so the second bound matters where ``--host`` opens it wider); a connection beyond either is closed at once.
"""

from __future__ import annotations

import asyncio

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

#: Seconds a connection may take to send one complete request (a browser sends it at once).
REQUEST_READ_SECONDS = 5.0
#: Connections held at once (a page holds two or three: its requests and its event stream).
MAX_CONNECTIONS = 64
#: Connections held at once from one peer address.
MAX_PER_CLIENT = 32
#: States of the client's side in which a request has been read whole: no deadline runs.
_READ = (h11.DONE, h11.MUST_CLOSE, h11.CLOSED, h11.ERROR)


class GuardedH11Protocol(H11Protocol):
    """:class:`H11Protocol` with a request-read deadline and connection limits (see the module docstring)."""

    _read_deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        peer = self.client[0] if self.client else None
        same = sum(1 for other in self.connections if (getattr(other, "client", None) or (None,))[0] == peer)
        if len(self.connections) > MAX_CONNECTIONS or same > MAX_PER_CLIENT:
            transport.close()
            return
        self._arm()

    def data_received(self, data: bytes) -> None:
        super().data_received(data)
        if self.conn.their_state in _READ:
            self._disarm()
        else:
            self._arm()  # waiting for (the rest of) a request, e.g. the next one on a kept-alive connection

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def _arm(self) -> None:
        if self._read_deadline is None:
            self._read_deadline = self.loop.call_later(REQUEST_READ_SECONDS, self._read_timeout)

    def _disarm(self) -> None:
        if self._read_deadline is not None:
            self._read_deadline.cancel()
            self._read_deadline = None

    def _read_timeout(self) -> None:
        self._read_deadline = None
        if self.conn.their_state not in _READ and not self.transport.is_closing():
            self.transport.close()
