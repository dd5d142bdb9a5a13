"""The explorer's HTTP connections, bounded (issues 35, 46): uvicorn's h11 protocol with a deadline for reading
each request, limits on the connections held, and a slot always kept for a new request.

uvicorn times out idle keep-alive connections only after a response; a connection that sends nothing, or half a
request's headers, and waits, was held forever (200 such sockets were all still open after 20 s). Here every
connection must deliver a complete request (headers and body) within :data:`REQUEST_READ_SECONDS` of starting to
wait for one, or it is closed.

At most :data:`MAX_CONNECTIONS` connections are held at once and at most :data:`MAX_PER_CLIENT` from one peer
address (the explorer listens on loopback, where every client is 127.0.0.1). A new connection beyond either bound
is not refused (that locked the browser out once 200 event streams or 200 half-open sockets were held, issue 46):
the oldest *evictable* connection makes room for it — first one waiting for a request (idle or half-open, nothing
lost), then the oldest event stream (``/api/events``: the page's ``EventSource`` reconnects by itself). Only when
every held connection is computing a response is the new one closed. Event streams are bounded on their own too:
at most :data:`MAX_STREAMS_PER_CLIENT` per peer, the oldest closed when another opens.
"""

from __future__ import annotations

import asyncio
import itertools

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

#: Seconds a connection may take to send one complete request (a browser sends it at once).
REQUEST_READ_SECONDS = 5.0
#: Connections held at once (a page holds two or three: its requests and its event stream).
MAX_CONNECTIONS = 64
#: Connections held at once from one peer address.
MAX_PER_CLIENT = 32
#: Event streams held at once from one peer address (one per open page).
MAX_STREAMS_PER_CLIENT = 8
#: Paths whose responses stream for as long as the page is open.
STREAM_PATHS = ("/api/events",)
#: States of the client's side in which a request has been read whole: no deadline runs.
_READ = (h11.DONE, h11.MUST_CLOSE, h11.CLOSED, h11.ERROR)
_ORDER = itertools.count()


class GuardedH11Protocol(H11Protocol):
    """:class:`H11Protocol` with a request-read deadline, connection limits and eviction (see the module
    docstring)."""

    _read_deadline: asyncio.TimerHandle | None = None
    _order: int = 0

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._order = next(_ORDER)
        peer = self._peer()
        while True:
            held = [c for c in self.connections if c is not self and not c.transport.is_closing()]
            same = [c for c in held if _peer_of(c) == peer]
            if len(held) < MAX_CONNECTIONS and len(same) < MAX_PER_CLIENT:
                break
            victim = _evictable(same if len(same) >= MAX_PER_CLIENT else held)
            if victim is None:  # every held connection is computing: no room
                transport.close()
                return
            victim.transport.close()
        self._arm()

    def data_received(self, data: bytes) -> None:
        super().data_received(data)
        if self.conn.their_state in _READ:
            self._disarm()
        else:
            self._arm()  # waiting for (the rest of) a request, e.g. the next one on a kept-alive connection
        if self._streaming():
            peer = self._peer()
            streams = sorted((c for c in self.connections if c is not self and _peer_of(c) == peer
                              and c._streaming() and not c.transport.is_closing()), key=lambda c: c._order)
            for old in streams[:max(0, len(streams) + 1 - MAX_STREAMS_PER_CLIENT)]:
                old.transport.close()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def _peer(self) -> object:
        return _peer_of(self)

    def _waiting(self) -> bool:
        """Waiting for a request (idle between requests, or part of one read): closing it loses nothing."""
        return self.cycle is None or self.cycle.response_complete or self.conn.their_state not in _READ

    def _streaming(self) -> bool:
        return (self.cycle is not None and not self.cycle.response_complete
                and self.cycle.scope.get("path") in STREAM_PATHS)

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


def _peer_of(connection: object) -> object:
    client = getattr(connection, "client", None)
    return client[0] if client else None


def _evictable(connections: list) -> GuardedH11Protocol | None:
    """The oldest connection waiting for a request, else the oldest event stream, else None."""
    guarded = [c for c in connections if isinstance(c, GuardedH11Protocol)]
    for kind in (GuardedH11Protocol._waiting, GuardedH11Protocol._streaming):
        candidates = [c for c in guarded if kind(c)]
        if candidates:
            return min(candidates, key=lambda c: c._order)
    return None
