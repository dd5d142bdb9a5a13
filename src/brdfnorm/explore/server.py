"""The explorer's web server: a Starlette application served by uvicorn on a socket bound before start-up.

Routes (nothing else is served, and no path from a request is ever opened):

* ``GET /`` the page; ``GET /static/{app.js,plots.js,style.css,plotly-basic.min.js}`` its assets — plotly.js's official
  *basic* partial bundle (scatter traces only, all the page draws: 1.2 MB against the full bundle's 4.8 MB, which
  took 1.4–3 s of a first load to compile), vendored beside the page (``static/VENDORED.md``: source,
  version, checksum, licence), so the page needs no network. The assets are read once, gzipped once, and served
  under content-hashed URLs (``?v=HASH``, cached for a year) with ETags; the page itself is never cached.
* ``GET /api/models`` the catalog (:mod:`.catalog`); ``GET /api/models/{id}`` one model's declared parameters.
* ``POST /api/evaluate`` one view of a model (:func:`.compute.evaluate_view`; ``phi`` the view azimuth,
  ``overlay`` a second ``{model, params}`` drawn beside it), ``POST /api/fit`` the fit panel.
* ``GET /api/events`` server-sent events: a watched ``.brdf`` file was reloaded (or failed to compile).

Heavy work runs in worker threads, one computation at a time in each of two lanes — the coarse passes a slider
move waits for, and the background (refinements, fits) — so a move never queues behind a long refinement.
Each request carries the client's id and a *generation* number; a request with a newer generation makes the
running one raise :class:`.compute.Superseded` at its next integrand batch (and so does a client that hangs
up), so stale work never holds a lane. A bad request gets a JSON ``{"error": ...}`` with status 4xx; an
unexpected exception a 500 — the server keeps serving either way.
"""

from __future__ import annotations

import asyncio
import contextlib
import gzip
import hashlib
import html
import ipaddress
import json
import logging
import os
import signal
import socket
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import anyio
import anyio.to_thread
import uvicorn
import watchfiles
from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import JSONResponse, Response, StreamingResponse
from starlette.routing import Route

from ..errors import ArgumentError, BrdfnormError, ModelNotFoundError
from ..output.formats import jsonable
from .catalog import Catalog, Entry
from .compute import (
    CONVENTIONS,
    FIT_LANGUAGES,
    VIEW_MAX_DEG,
    Superseded,
    Verdicts,
    describe_parameters,
    evaluate_view,
    fit_factor,
    view_angle,
    view_azimuth,
)
from .guard import MAX_CONNECTIONS, GuardedH11Protocol

STATIC = Path(__file__).with_name("static")
#: Largest request body accepted (a page request is well under 1 KiB).
MAX_BODY = 64 * 1024
#: Clients whose generation numbers are remembered (the oldest are forgotten first).
MAX_CLIENTS = 1024
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1", "[::1]")
#: The page runs only its own three scripts (no eval: the basic bundle has no WebGL layer; plotly sets inline
#: styles) and talks only to this server.
PAGE_POLICY = ("default-src 'none'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
               "img-src 'self' data: blob:; connect-src 'self'; font-src 'self' data:; base-uri 'none'; "
               "form-action 'none'; frame-ancestors 'none'")
log = logging.getLogger("brdfnorm.explore")


#: The page's assets (nothing else under /static/ exists) and their media types.
ASSET_TYPES = {"app.js": "text/javascript; charset=utf-8", "plots.js": "text/javascript; charset=utf-8",
               "style.css": "text/css; charset=utf-8",
               "plotly-basic.min.js": "text/javascript; charset=utf-8"}
#: A content-hashed asset URL never changes meaning: browsers may keep it a year without asking again.
IMMUTABLE = "public, max-age=31536000, immutable"


@dataclass(frozen=True)
class Asset:
    """One static file, read at start-up: its bytes, their gzip, and a tag that changes with the content."""

    body: bytes
    gzipped: bytes
    media_type: str
    tag: str

    @classmethod
    def read(cls, path: Path, media_type: str) -> Asset:
        body = path.read_bytes()
        # mtime=0: the same bytes give the same gzip (and the tag names the content, not the start time).
        return cls(body, gzip.compress(body, compresslevel=6, mtime=0), media_type,
                   hashlib.sha256(body).hexdigest()[:16])

    def response(self, request: Request) -> Response:
        """The asset, gzipped where the client accepts it; 304 when its ETag matches; cached for a year when asked
        for under its current hash."""
        # Weak: the gzipped and the plain bytes are one content in two encodings (RFC 9110 §8.8.1).
        etag = f'W/"{self.tag}"'
        cache = IMMUTABLE if request.query_params.get("v") == self.tag else "no-cache"
        headers = {"Cache-Control": cache, "ETag": etag, "Vary": "Accept-Encoding", "X-Content-Type-Options": "nosniff"}
        asked = [t.strip().removeprefix("W/") for t in request.headers.get("if-none-match", "").split(",")]
        if f'"{self.tag}"' in asked or "*" in asked:
            return Response(status_code=304, headers=headers)
        if accepts_gzip(request.headers.get("accept-encoding", "")):
            return Response(self.gzipped, media_type=self.media_type, headers={**headers, "Content-Encoding": "gzip"})
        return Response(self.body, media_type=self.media_type, headers=headers)


def accepts_gzip(header: str) -> bool:
    """Whether an Accept-Encoding header allows gzip (RFC 9110 §12.5.3: named or ``*``; a q of 0 refuses it)."""
    weights = {}
    for item in header.lower().split(","):
        coding, *params = (part.strip() for part in item.split(";"))
        q = next((p[2:] for p in params if p.startswith("q=")), "1")
        try:
            weights[coding] = float(q)
        except ValueError:
            weights[coding] = 0.0
    return weights.get("gzip", weights.get("*", 0.0)) > 0


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


class RequestError(Exception):
    """A request the server refuses before any model is involved (status and message)."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


class Explorer:
    """The application state: the catalog, the clients' generations, the event subscribers, the watcher."""

    def __init__(self, catalog: Catalog, *, loopback_only: bool = True, host: str = "127.0.0.1") -> None:
        self.catalog = catalog
        self.generations: OrderedDict[tuple[str, str], int] = OrderedDict()
        self.subscribers: set[asyncio.Queue] = set()
        self.lanes: dict[str, anyio.CapacityLimiter] = {}
        self.verdicts = Verdicts()
        self.stop_watching = asyncio.Event()
        routes = [
            Route("/", self.page),
            Route("/static/{name}", self.static),
            Route("/api/models", self.models),
            Route("/api/models/{model_id:path}", self.model),
            Route("/api/evaluate", self.evaluate, methods=["POST"]),
            Route("/api/fit", self.fit, methods=["POST"]),
            Route("/api/events", self.events),
        ]
        # Against DNS rebinding: a page from another site that resolves its name to 127.0.0.1 is refused.
        allowed = [*LOOPBACK_NAMES, host, f"[{host}]"]
        middleware = [Middleware(TrustedHostMiddleware, allowed_hosts=allowed)] if loopback_only else []
        self.app = Starlette(routes=routes, middleware=middleware, lifespan=self.lifespan)
        self.assets = {name: Asset.read(STATIC / name, media_type) for name, media_type in ASSET_TYPES.items()}
        # The page names each asset by its content hash, so a browser may cache them for good.
        page = (STATIC / "index.html").read_text(encoding="utf-8")
        for name, asset in self.assets.items():
            page = page.replace(f'"/static/{name}"', f'"/static/{name}?v={asset.tag}"')
        # The page asks for the first model's view before the catalog arrives (see app.js).
        first = html.escape(catalog.entries()[0].id, quote=True)
        page = page.replace('<body data-state="loading">', f'<body data-state="loading" data-first-model="{first}">')
        self.page_html = page.encode()

    @contextlib.asynccontextmanager
    async def lifespan(self, app: Starlette):
        # Two lanes of one computation each: a slider's coarse pass never queues behind a refinement or a fit
        # (another tab's, say, which may take seconds); a client's own stale work is cancelled anyway.
        self.lanes = {"coarse": anyio.CapacityLimiter(1), "background": anyio.CapacityLimiter(1)}
        self.stop_watching = asyncio.Event()
        watcher = asyncio.create_task(self.watch())
        try:
            yield
        finally:
            self.stop_watching.set()
            watcher.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await watcher

    # -- pages and assets ---------------------------------------------------------------------------------------
    async def page(self, request: Request) -> Response:
        return Response(self.page_html, media_type="text/html; charset=utf-8",
                        headers={"Cache-Control": "no-cache", "Content-Security-Policy": PAGE_POLICY,
                                 "X-Content-Type-Options": "nosniff"})

    async def static(self, request: Request) -> Response:
        asset = self.assets.get(request.path_params["name"])
        if asset is None:
            return JSONResponse({"error": "not found"}, status_code=404)
        return asset.response(request)

    async def models(self, request: Request) -> Response:
        return JSONResponse({"models": [entry.describe() for entry in self.catalog.entries()],
                             "conventions": list(CONVENTIONS), "languages": list(FIT_LANGUAGES),
                             "view_max_deg": VIEW_MAX_DEG})

    async def model(self, request: Request) -> Response:
        async def describe() -> dict:
            entry = self.catalog.entry(request.path_params["model_id"])
            model = entry.model or await anyio.to_thread.run_sync(self.catalog.get, entry.id)
            return {**entry.describe(), "name": model.name, "formula": model.formula, "channels": model.channels,
                    "parameters": describe_parameters(model), "error": entry.error}

        return await self.respond(describe)

    # -- computations -------------------------------------------------------------------------------------------
    async def evaluate(self, request: Request) -> Response:
        async def run() -> dict:
            body = await read_json(request)
            check = self.claim("view", body, request)  # first: a newer move must cancel older work at once
            entry, model = await self.model_of(body)
            view, phi = view_angle(body.get("view")), view_azimuth(body.get("phi"))
            overlay = await self.overlay_of(body.get("overlay"))
            received = time.perf_counter()
            started = []

            def timed() -> dict:
                started.append(time.perf_counter())
                return evaluate_view(model, view, body.get("convention", "normal"), body.get("quality", "coarse"),
                                     check, params=body.get("params"), source=entry.source,
                                     verdicts=self.verdicts, model_key=(entry.id, entry.version), phi_deg=phi,
                                     overlay=overlay)

            lane = "coarse" if body.get("quality", "coarse") == "coarse" else "background"
            result = await self.compute(request, check, timed, lane)
            finished = time.perf_counter()
            timing = {"queued_ms": 1e3 * (started[0] - received), "compute_ms": 1e3 * (finished - started[0])}
            return {**result, "model": {"id": entry.id, "version": entry.version, "error": entry.error},
                    "generation": body["generation"], "timing": timing}

        return await self.respond(run)

    async def fit(self, request: Request) -> Response:
        async def run() -> dict:
            body = await read_json(request)
            check = self.claim("fit", body, request)
            entry, model = await self.model_of(body)
            result = await self.compute(request, check, lambda: fit_factor(
                model, body.get("parameter"), body.get("low"), body.get("high"), body.get("samples"), body.get("at"),
                body.get("language"), body.get("scale", "linear"), body.get("form", "auto"), check,
                params=body.get("params")), "background")
            return {**result, "generation": body["generation"]}

        return await self.respond(run)

    async def model_of(self, body: dict) -> tuple[Entry, object]:
        """The entry and its model; a first use compiles it (in a thread, outside the computation queue)."""
        entry = self.catalog.entry(body.get("model"))
        model = entry.model or await anyio.to_thread.run_sync(self.catalog.get, entry.id)
        return entry, model

    async def overlay_of(self, raw: object) -> tuple[object, object, str] | None:
        """The overlay's (model, page values, label), or None when the request has none."""
        if raw is None:
            return None
        if not isinstance(raw, dict):
            raise ArgumentError("overlay must be an object {model, params}", where="overlay")
        entry, model = await self.model_of(raw)
        return model, raw.get("params"), entry.label

    async def compute(self, request: Request, check: Callable[[], None], work: Callable[[], dict], lane: str) -> dict:
        """Run ``work`` in a worker thread, one at a time per lane; a client that hangs up cancels it (``check``)."""

        async def watch_disconnect() -> None:
            while (await request.receive())["type"] != "http.disconnect":
                pass
            check.gone.set()  # type: ignore[attr-defined]

        watcher = asyncio.create_task(watch_disconnect())
        try:
            return await anyio.to_thread.run_sync(work, limiter=self.lanes[lane])
        finally:
            watcher.cancel()

    def claim(self, kind: str, body: dict, request: Request | None = None) -> Callable[[], None]:
        """Record the request's generation for its client; the returned check raises once a newer one arrives
        or the client has gone."""
        client, generation = body.get("client"), body.get("generation")
        if not isinstance(client, str) or not 0 < len(client) <= 64:
            raise ArgumentError("client must be a short string", where="client")
        if not isinstance(generation, int) or isinstance(generation, bool) or not 0 <= generation < 2**53:
            raise ArgumentError("generation must be a whole number", where="generation")
        key = (kind, client)
        if generation < self.generations.get(key, -1):
            raise Superseded
        self.generations[key] = generation
        self.generations.move_to_end(key)
        while len(self.generations) > MAX_CLIENTS:
            self.generations.popitem(last=False)
        gone = threading.Event()

        def check() -> None:
            if gone.is_set() or self.generations.get(key, generation) != generation:
                raise Superseded

        check.gone = gone  # type: ignore[attr-defined]
        return check

    async def respond(self, work: Callable[[], object]) -> Response:
        """Run a handler body; map every failure to a JSON error so one bad request never stops the server."""
        try:
            return JSONResponse(jsonable(await work()))
        except Superseded:
            return JSONResponse({"stale": True}, status_code=409)
        except RequestError as error:
            return JSONResponse({"error": str(error)}, status_code=error.status)
        except ModelNotFoundError as error:
            return JSONResponse({"error": str(error)}, status_code=404)
        except BrdfnormError as error:
            return JSONResponse({"error": str(error).replace("\n", " ")}, status_code=400)
        except Exception as error:  # noqa: BLE001 — logged, answered, and the server goes on
            log.exception("internal error")
            detail = str(error).splitlines()[0] if str(error) else ""
            return JSONResponse({"error": f"internal error: {type(error).__name__}: {detail}"}, status_code=500)

    # -- live files ---------------------------------------------------------------------------------------------
    async def events(self, request: Request) -> Response:
        queue: asyncio.Queue = asyncio.Queue(maxsize=64)
        self.subscribers.add(queue)

        async def stream():
            try:
                yield "retry: 1000\n\n"
                while True:
                    try:
                        message = await asyncio.wait_for(queue.get(), timeout=10.0)
                    except TimeoutError:
                        yield ": keep-alive\n\n"
                        continue
                    if message is None:  # the server is stopping
                        return
                    yield f"data: {json.dumps(jsonable(message))}\n\n"
            finally:
                self.subscribers.discard(queue)

        return StreamingResponse(stream(), media_type="text/event-stream", headers={"Cache-Control": "no-cache"})

    def close_streams(self) -> None:
        """End every event stream (at shutdown, so that no connection holds the server open)."""
        for queue in list(self.subscribers):
            with contextlib.suppress(asyncio.QueueFull):
                queue.put_nowait(None)

    def publish(self, entry: Entry) -> None:
        message = {"model": entry.id, "version": entry.version, "error": entry.error}
        for queue in list(self.subscribers):
            with contextlib.suppress(asyncio.QueueFull):  # a client that stopped reading misses events, no more
                queue.put_nowait(message)

    async def watch(self) -> None:
        """Reload a watched file when it changes (its directory is watched: editors save by renaming)."""
        watched = self.catalog.watched()
        if not watched:
            return
        directories = sorted({path.parent for path in watched}, key=str)
        async for changes in watchfiles.awatch(*directories, debounce=100, step=30, recursive=False,
                                               stop_event=self.stop_watching, watch_filter=None):
            touched = {os.path.realpath(path) for _, path in changes}
            for path, entry in watched.items():
                if str(path) in touched:
                    await anyio.to_thread.run_sync(self.catalog.reload, entry)
                    self.publish(entry)


async def read_json(request: Request) -> dict:
    """The request's JSON object, at most :data:`MAX_BODY` bytes.

    Only ``Content-Type: application/json`` from this server's own pages: another site's page cannot send
    that cross-origin without a CORS preflight, which this server never grants (no computing on its behalf).
    """
    origin = request.headers.get("origin")
    if origin is not None and origin != f"{request.url.scheme}://{request.headers.get('host', '')}":
        raise RequestError(403, "requests from other sites are refused")
    if request.headers.get("content-type", "").split(";")[0].strip().lower() != "application/json":
        raise RequestError(415, "the request body must be JSON (Content-Type: application/json)")
    length = request.headers.get("content-length")
    if length is not None and (not length.isdigit() or int(length) > MAX_BODY):
        raise RequestError(413, f"request body over {MAX_BODY} bytes")
    data = bytearray()
    async for chunk in request.stream():
        data += chunk
        if len(data) > MAX_BODY:
            raise RequestError(413, f"request body over {MAX_BODY} bytes")
    try:
        body = json.loads(data)
    except (ValueError, RecursionError):
        raise RequestError(400, "the request body is not valid JSON") from None
    if not isinstance(body, dict):
        raise RequestError(400, "the request body must be a JSON object")
    return body


# -- serving --------------------------------------------------------------------------------------------------

class _Server(uvicorn.Server):
    """uvicorn's server, ending the explorer's event streams first at shutdown, and without re-raising the
    signal that stopped it: Ctrl-C ends ``serve`` normally."""

    def __init__(self, config: uvicorn.Config, explorer: Explorer) -> None:
        super().__init__(config)
        self.explorer = explorer

    async def shutdown(self, sockets: list[socket.socket] | None = None) -> None:
        self.explorer.close_streams()
        await super().shutdown(sockets=sockets)

    @contextlib.contextmanager
    def capture_signals(self) -> Iterator[None]:
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        previous = {sig: signal.signal(sig, self.handle_exit) for sig in (signal.SIGINT, signal.SIGTERM)}
        try:
            yield
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)


def bind(host: str, port: int) -> socket.socket:
    """A listening socket on (host, port); port 0 picks a free one."""
    family = socket.AF_INET6 if ":" in host.strip("[]") else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host.strip("[]"), port))
    except OSError as error:
        sock.close()
        where = "--port" if port else "--host"
        raise ArgumentError(f"cannot listen on {host}:{port}: {error.strerror}", where=where) from None
    sock.listen(128)
    sock.set_inheritable(True)
    return sock


def url_of(sock: socket.socket) -> str:
    host, port = sock.getsockname()[:2]
    return f"http://[{host}]:{port}/" if ":" in host else f"http://{host}:{port}/"


def make_server(catalog: Catalog, host: str) -> _Server:
    explorer = Explorer(catalog, loopback_only=is_loopback(host), host=host.strip("[]"))
    # the h11 protocol with a request-read deadline, connection limits and eviction (.guard); uvicorn's own 503
    # limit sits above the guard's (evicted connections leave its count a moment after they are closed)
    config = uvicorn.Config(explorer.app, log_level="warning", access_log=False, lifespan="on",
                            timeout_graceful_shutdown=2, http=GuardedH11Protocol,
                            limit_concurrency=2 * MAX_CONNECTIONS, h11_max_incomplete_event_size=16 * 1024)
    return _Server(config, explorer)


def serve(catalog: Catalog, sock: socket.socket) -> None:
    """Serve until Ctrl-C (SIGINT) or SIGTERM."""
    make_server(catalog, sock.getsockname()[0]).run(sockets=[sock])


@contextlib.contextmanager
def background(catalog: Catalog, host: str = "127.0.0.1", port: int = 0) -> Iterator[str]:
    """Serve in a thread (tests, benchmarks); yields the URL and stops the server on exit."""
    sock = bind(host, port)
    server = make_server(catalog, host)
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    try:
        for _ in range(400):
            if server.started or not thread.is_alive():
                break
            threading.Event().wait(0.025)
        if not server.started:
            raise RuntimeError("the explorer server did not start")
        yield url_of(sock)
    finally:
        server.should_exit = True
        thread.join(timeout=10)
        sock.close()
