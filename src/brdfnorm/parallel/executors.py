"""Where chunks run: in this process, in a local process pool, or on a Dask cluster — the same chunk task each time.

:func:`run_chunk` is the one task: it receives the job's header (JSON text: the model's source and the albedo
settings) and one chunk's cells (plain arrays), rebuilds the model from its source (cached per process), and
computes the chunk as one vectorized batch. Nothing else crosses a process boundary — no closure, no model
object — so a worker on another machine only needs the same brdfnorm version (checked).

:class:`Workers` (held open across the jobs of one run: a check asks for many small jobs) yields
:class:`ChunkResult` objects as chunks finish, in completion order, from one of:

* this process (``workers=1``, or a job with one chunk to compute; with the default ``workers``, also a job whose
  chunks after the first, predicted from its time, would not repay the pool's start, :data:`POOL_START_SECONDS`);
* a local :class:`concurrent.futures.ProcessPoolExecutor` with the ``forkserver`` start method (``spawn`` where
  there is none): fresh interpreters, never a fork of a process that may hold threads or a Dask client;
* ``dask.distributed`` (``scheduler="tcp://HOST:PORT"``): one task per chunk with a key derived from the job's
  hash and a token of the submission (a job asked for twice never meets its own released key), ``retries`` for
  failures inside a task; a worker lost mid-chunk is rescheduled by Dask itself.

Stopping early (an exception, SIGTERM turned into :class:`KeyboardInterrupt`) cancels the chunks not started
and stops local workers at once: at most the chunks in flight are lost.
"""

from __future__ import annotations

import functools
import ipaddress
import json
import multiprocessing
import os
import re
import socket
import struct
import sys
import threading
import time
import uuid
import warnings
from collections.abc import Iterator, Mapping
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError
from ..models import Model
from .cores import local_cores
from .job import CellsJob, ChunkPlan, ModelSource, canonical_json

#: Dask re-runs a chunk task that raised this many more times (an unexpected failure on one worker).
DASK_RETRIES = 2
#: Seconds to reach a Dask scheduler, all in all: the TCP connection, its handshake and the client's start, unless
#: a :class:`Scheduler` says otherwise (the command line's ``--connect-timeout``).
DASK_CONNECT_TIMEOUT = 10.0
#: Largest first message a Dask scheduler's handshake may announce (it is a few hundred bytes; an HTTP server's
#: "HTTP/1.1" read as a length is 3.5·10¹⁸).
HANDSHAKE_BYTES = 1024**2
#: Seconds of wall time a local pool takes before its first chunk computes: a fresh interpreter per worker importing
#: brdfnorm, rebuilding the model and loading its kernels from the disk cache. Measured on the 2-core machine
#: (docs/performance.md, fourth session): a new process's import + .brdf load + kernel load + one albedo is 0.7–0.9 s
#: of CPU idle, and two start at once on two cores; a 32 × 32 ``lut examples/ggx.brdf`` E stage of 1.6–1.7 s in this
#: process took 1.8 s on 2 workers at load 1.2 and 3.0 s at load 2.5.
POOL_START_SECONDS = 1.5
_SCHEMES = ("tcp", "tls")
_HOST = re.compile(r"[A-Za-z0-9](?:[A-Za-z0-9.-]{0,252}[A-Za-z0-9])?\Z")


@dataclass(frozen=True)
class Scheduler:
    """A Dask scheduler's address with its own deadline for being reached: ``scheduler=`` takes one wherever it takes
    a plain address (which gets :data:`DASK_CONNECT_TIMEOUT`). Each value carries its deadline, so two runs in one
    process with different deadlines never share one."""

    address: str
    connect_timeout: float = DASK_CONNECT_TIMEOUT

    def __post_init__(self) -> None:
        timeout = self.connect_timeout
        if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not 0 < timeout < float("inf"):
            raise ArgumentError(f"connect_timeout must be a number of seconds > 0, got {timeout!r}",
                                where="connect_timeout")
        object.__setattr__(self, "address", scheduler_address(self.address))

    def __str__(self) -> str:
        return self.address


@dataclass(frozen=True)
class ChunkResult:
    """One chunk's results, cells in the chunk's order (``value``/``error`` (n, C), the rest (n,))."""

    index: int
    value: np.ndarray
    error: np.ndarray
    evaluations: np.ndarray  # integrand evaluations per cell; -1 where not counted (task "max")
    converged: np.ndarray
    nonfinite_fraction: np.ndarray  # 0 unless nonfinite="zero" zeroed some of the hemisphere
    theta: np.ndarray  # the direction the value belongs to (the argmax for task "max")
    phi: np.ndarray
    method: str
    seconds: float
    lower: np.ndarray | None = None  # (n, C) decimal strings: guaranteed bounds (method "certified")
    upper: np.ndarray | None = None
    reason: np.ndarray | None = None  # (n,) why a cell did not converge ("" where it did), where albedo says
    reflected: np.ndarray | None = None  # (n, C) the parts of a BSDF's albedo (models that transmit)
    transmitted: np.ndarray | None = None


#: Per-cell fields an AlbedoResult may carry: name -> (trailing shape of one cell, dtype); text is held as object
#: arrays of str (certified bounds, reasons).
OPTIONAL_FIELDS = {"lower": ("channels", object), "upper": ("channels", object), "reason": ("cell", object),
                   "reflected": ("channels", float), "transmitted": ("channels", float)}


@functools.lru_cache(maxsize=8)
def _model(source_json: str) -> Model:
    """The model of a source, built once per process (a .brdf shader compiles once, not once per chunk)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # slider-range warnings were shown where the job was made
        return ModelSource.from_json(json.loads(source_json)).load()


def run_chunk(header_json: str, index: int, theta: np.ndarray, phi: np.ndarray,
              values: Mapping[str, np.ndarray]) -> ChunkResult:
    """Compute chunk ``index`` of a job (the task every executor runs; importable by any worker), with the
    model rebuilt from the job's source once per process."""
    from .. import __version__

    header = json.loads(header_json)
    if header["brdfnorm"] != __version__:
        raise ArgumentError(f"this worker runs brdfnorm {__version__}, the job needs {header['brdfnorm']}",
                            where="scheduler")
    return compute_chunk(_model(canonical_json(header["source"])), header, index, theta, phi, values)


def compute_chunk(model: Model, header: Mapping, index: int, theta: np.ndarray, phi: np.ndarray,
                  values: Mapping[str, np.ndarray]) -> ChunkResult:
    """Compute chunk ``index`` of the job ``header`` with its model (loaded here, or the caller's own)."""
    from ..engine.methods import albedo
    from ..normalization import normalize

    settings = header["settings"]
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the caller reports unconverged and non-finite cells once, for the table
        if header["task"] == "albedo":
            result = albedo(model.with_params(**values), theta, phi, **settings)
            n = theta.size
            fraction = result.nonfinite_fraction
            text = {name: np.asarray(getattr(result, name), dtype=dtype).reshape((n, -1) if tail == "channels" else n)
                    for name, (tail, dtype) in OPTIONAL_FIELDS.items() if getattr(result, name, None) is not None}
            return ChunkResult(index, result.value.reshape(n, -1), result.error.reshape(n, -1),
                               result.evaluations.reshape(n), result.converged.reshape(n),
                               np.zeros(n) if fraction is None else fraction.reshape(n),
                               theta, phi, result.method, time.perf_counter() - start, **text)
        (name, sweep), = values.items() if values else ((None, np.zeros(1)),)
        found = normalize(model, at="max", sweep=None if name is None else {name: sweep}, over=settings["over"],
                          rtol=settings["rtol"], method=settings["method"])
        n = found.values.size
        return ChunkResult(index, found.albedo.reshape(n, -1), found.error.reshape(n, -1),
                           np.full(n, -1, dtype=np.int64), found.converged.reshape(n), np.zeros(n),
                           found.theta.reshape(n), found.phi.reshape(n), found.method, time.perf_counter() - start)


class Workers:
    """Where the chunks of one or more jobs run, held open between jobs (one pool, one Dask client per run).

    ``workers``: local processes (None: all cores, where they pay, :func:`pool_pays`; 1: this process);
    ``scheduler``: a Dask scheduler address (then ``workers`` must be None). Validated here, before any work; the
    pool starts at the first job with more than one chunk to compute (given ``workers``) or whose chunks after its
    first, computed here, are predicted to repay the pool's start (the default), the Dask client at :meth:`start`.
    ``placed``: where the last job's chunks ran, as :meth:`placement` says it. Use it as a context manager: leaving it
    stops the pool's processes at once (an exception, SIGTERM turned into KeyboardInterrupt) and closes the
    client.
    """

    def __init__(self, workers: int | None = None, scheduler: str | Scheduler | None = None) -> None:
        if scheduler is not None and workers is not None:
            raise ArgumentError("give either workers (a local process pool) or a Dask scheduler (on the command "
                                "line also taken from DASK_SCHEDULER_ADDRESS), not both", where="workers")
        if workers is not None and (isinstance(workers, bool) or int(workers) != workers or workers < 1):
            raise ArgumentError(f"workers must be a whole number ≥ 1, got {workers!r}", where="workers")
        target = scheduler if isinstance(scheduler, Scheduler) or scheduler is None else Scheduler(scheduler)
        self.scheduler = None if target is None else target.address
        self.connect_timeout = DASK_CONNECT_TIMEOUT if target is None else target.connect_timeout
        self.count = int(workers) if workers is not None else local_cores()
        self.adaptive = workers is None and target is None  # (the default: the pool where it pays)
        self.placed = ("in-process", 1)
        self._pool: ProcessPoolExecutor | None = None
        self._client = None

    def __enter__(self) -> Workers:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def start(self) -> None:
        """Connect to the Dask scheduler (once) and count its workers."""
        if self.scheduler is not None and self._client is None:
            self._client = dask_client(self.scheduler, self.connect_timeout)
            self.count = len(self._client.scheduler_info().get("workers", {}))

    def placement(self, chunks: int) -> tuple[str, int]:
        """Where ``chunks`` chunks to compute run, in words, and on how many workers; a Dask scheduler without
        workers is refused when there is anything to compute (its tasks would wait forever)."""
        if self.scheduler is not None:
            self.start()
            if self.count == 0 and chunks:
                self.close()
                raise ArgumentError(f"the Dask scheduler at {self.scheduler} has no workers (start some with "
                                    f"`dask worker {self.scheduler}`)", where="scheduler")
            return f"dask {self.scheduler}", self.count
        if self.count <= 1 or chunks <= 1:
            return "in-process", 1
        return "local processes", min(self.count, chunks)

    def run(self, job: CellsJob, plan: ChunkPlan, missing: list[int],
            model: Model | None = None) -> Iterator[ChunkResult]:
        """Compute the ``missing`` chunks of ``job``, yielding each as it finishes (in completion order); in this
        process with ``model`` (the job's, already loaded) where given, never parsing it again."""
        header = canonical_json(job.header())
        tasks = [(header, k, *job.cells(plan.chunk(k))) for k in missing]
        where, count = self.placed = self.placement(len(tasks))
        if self.scheduler is not None:
            return _on_dask(tasks, self._client, job.digest)
        if where == "in-process":
            if model is None:
                return (run_chunk(*task) for task in tasks)
            data = job.header()
            return (compute_chunk(model, data, *task[1:]) for task in tasks)
        if self.adaptive and self._pool is None and model is not None:
            return self._first_here(job.header(), tasks, model)
        return _in_pool(self._local_pool(), tasks)

    def _first_here(self, header: Mapping, tasks: list[tuple], model: Model) -> Iterator[ChunkResult]:
        """The first chunk in this process, then the rest on the pool only where :func:`pool_pays` for their time
        predicted from the first's (chunks are cut at equal estimated cost, :func:`.job.chunk_plan`)."""
        first = compute_chunk(model, header, *tasks[0][1:])
        yield first
        rest = tasks[1:]
        if pool_pays(first.seconds * len(rest), min(self.count, len(rest))):
            self.placed = ("local processes", min(self.count, len(rest)))
            yield from _in_pool(self._local_pool(), rest)
        else:
            self.placed = ("in-process", 1)
            yield from (compute_chunk(model, header, *task[1:]) for task in rest)

    def map(self, function, tasks: list[tuple]) -> list:
        """``function(*task)`` for every task, in order, where the chunks of a job would run (a module-level
        function of picklable arguments: it travels to the processes or the cluster)."""
        where, _ = self.placement(len(tasks))
        if self.scheduler is not None:
            futures = [self._client.submit(function, *task, retries=DASK_RETRIES, pure=False) for task in tasks]
            try:
                return self._client.gather(futures)
            finally:
                self._client.cancel(futures)
        if where == "in-process":
            return [function(*task) for task in tasks]
        return list(self._local_pool().map(function, *zip(*tasks, strict=True)))

    def _local_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            methods = multiprocessing.get_all_start_methods()
            context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
            self._pool = ProcessPoolExecutor(max_workers=self.count, mp_context=context,
                                             initializer=watch_parent, initargs=(os.getpid(),))
        return self._pool

    def close(self) -> None:
        """Stop the pool's processes now (not after their chunks) and close the Dask client."""
        pool, self._pool = self._pool, None
        if pool is not None:
            if hasattr(pool, "terminate_workers"):  # Python ≥ 3.14
                pool.terminate_workers()
            else:  # no public way before 3.14
                processes = list((getattr(pool, "_processes", None) or {}).values())
                pool.shutdown(wait=False, cancel_futures=True)
                for process in processes:
                    if process.is_alive():
                        process.terminate()
        client, self._client = self._client, None
        if client is not None:
            client.close()


def pool_pays(seconds: float, workers: int) -> bool:
    """Whether ``seconds`` of chunks (in one process) end sooner on a new pool of ``workers`` processes, which
    first takes :data:`POOL_START_SECONDS`."""
    return workers > 1 and POOL_START_SECONDS + seconds / workers < seconds


#: How often a pool worker checks that the process that started the pool is still alive (seconds).
PARENT_POLL_SECONDS = 0.5


def watch_parent(parent: int) -> None:
    """A pool worker's initializer: a daemon thread ends the worker when ``parent`` (the process that made the
    pool) is gone. A parent killed outright (SIGKILL, a test's timeout) runs no clean-up, and the workers — children
    of the forkserver, each holding both ends of the task queue — would otherwise wait for tasks forever."""

    def watch() -> None:
        while True:
            time.sleep(PARENT_POLL_SECONDS)
            if not _alive(parent):
                os._exit(1)

    threading.Thread(target=watch, name="brdfnorm-parent-watch", daemon=True).start()


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs: it exists (signal 0), is ours, and is not a zombie (a killed parent whose own
    parent has not reaped it yet still exists; Linux says so in /proc)."""
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, PermissionError):  # gone, or the pid now belongs to another user's process
        return False
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            return stat.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):  # no /proc (not Linux): existence is all there is to know
        return True


def _in_pool(pool: ProcessPoolExecutor, tasks: list[tuple]) -> Iterator[ChunkResult]:
    # Stopped early, the caller leaves its Workers, whose close() drops what has not started and ends the rest
    # (cancelling futures here would race the pool's own shutdown).
    pending = {pool.submit(run_chunk, *task) for task in tasks}
    while pending:
        done, pending = wait(pending, return_when=FIRST_COMPLETED)
        for future in done:
            yield future.result()


def scheduler_address(address: object) -> str:
    """A Dask scheduler address, checked before anything connects: ``tcp://`` or ``tls://``, a host name or IP
    address (IPv6 in brackets), a port in 1–65535, nothing else (no path, user or query)."""
    if not isinstance(address, str):
        raise ArgumentError(f"expected an address tcp://HOST:PORT, got {type(address).__name__}", where="scheduler")
    text = address.strip()
    if not text:
        raise ArgumentError("empty address (expected tcp://HOST:PORT or tls://HOST:PORT)", where="scheduler")
    shown = repr(text if len(text) <= 60 else text[:57] + "...")
    scheme, separator, rest = text.partition("://")
    if not separator or scheme.lower() not in _SCHEMES:
        raise ArgumentError(f"{shown}: expected tcp://HOST:PORT or tls://HOST:PORT", where="scheduler")
    host, colon, port = rest.rpartition(":")
    if not colon or not port.isdigit() or len(port) > 5 or not 1 <= int(port) <= 65535:
        raise ArgumentError(f"{shown}: the port must be a number in 1–65535 (tcp://HOST:PORT)", where="scheduler")
    if host.startswith("[") and host.endswith("]"):
        try:
            ipaddress.IPv6Address(host[1:-1])
        except ValueError:
            raise ArgumentError(f"{shown}: {host} is not an IPv6 address", where="scheduler") from None
    elif not _HOST.match(host):
        raise ArgumentError(f"{shown}: {host!r} is not a host name or IP address", where="scheduler")
    return f"{scheme.lower()}://{host}:{int(port)}"


def _preflight(address: str, deadline: float, timeout: float) -> None:
    """Connect to the scheduler and, for ``tcp://``, wait for the first bytes of its handshake (a Dask scheduler
    speaks first: a frame length), all before ``deadline``: a server that accepts and never answers, or answers in
    another protocol, is refused here, not left to the client (which would wait forever, or allocate what an
    HTTP reply's first bytes read as a length)."""
    scheme, _, rest = address.partition("://")
    host, _, port = rest.rpartition(":")
    host = host.strip("[]")

    def left() -> float:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            raise TimeoutError
        return remaining

    try:
        with socket.create_connection((host, int(port)), timeout=left()) as connection:
            if scheme != "tcp":
                return  # TLS is negotiated by the client, under the same deadline
            first = b""
            while len(first) < 8:
                connection.settimeout(left())
                data = connection.recv(8 - len(first))
                if not data:
                    raise ArgumentError(f"the server at {address} closed the connection without a handshake",
                                        where="scheduler")
                first += data
    except TimeoutError:
        raise ArgumentError(f"no Dask scheduler answered at {address} within {timeout:g} s "
                            "(--connect-timeout)", where="scheduler") from None
    except OSError as error:
        raise ArgumentError(f"cannot reach the Dask scheduler at {address}: {error.strerror or error}",
                            where="scheduler") from None
    (length,) = struct.unpack("<Q", first)
    if not 0 < length <= HANDSHAKE_BYTES:
        raise ArgumentError(f"the server at {address} is not a Dask scheduler (its first bytes are "
                            f"{first[:8]!r})", where="scheduler")


def dask_client(scheduler: str, connect_timeout: float = DASK_CONNECT_TIMEOUT):
    """A ``distributed.Client`` connected to ``scheduler`` within ``connect_timeout`` seconds in all, or a one-line
    error naming the address; a client that failed to start is closed here, never by its destructor."""
    from ..extras import require

    Client = require("distributed", "dask", where="scheduler").Client  # noqa: N806 - the class, by its own name
    scheduler = scheduler_address(scheduler)
    deadline = time.monotonic() + connect_timeout
    _preflight(scheduler, deadline, connect_timeout)
    remaining = max(deadline - time.monotonic(), 0.5)
    hook = sys.unraisablehook
    try:
        return Client(scheduler, timeout=remaining, set_as_default=False)
    except Exception as error:  # noqa: BLE001 — whatever the client raised, one line naming the address
        detail = str(error).splitlines()[0][:200] if str(error) else type(error).__name__
        raise ArgumentError(f"cannot reach the Dask scheduler at {scheduler}: {detail}", where="scheduler") from None
    finally:
        # a Client whose start failed is collected now, its destructor's complaints silenced (the error above says
        # what went wrong), instead of printing a traceback at exit
        sys.unraisablehook = lambda _unraisable: None
        try:
            import gc

            gc.collect()
        finally:
            sys.unraisablehook = hook


def _on_dask(tasks: list[tuple], client, digest: str) -> Iterator[ChunkResult]:
    from distributed import as_completed

    futures = []
    try:
        token = uuid.uuid4().hex[:8]
        futures = [client.submit(run_chunk, *task, key=f"brdfnorm-{digest[:16]}-{token}-chunk-{task[1]}",
                                 retries=DASK_RETRIES, pure=False) for task in tasks]
        for future in as_completed(futures, loop=client.loop):
            yield future.result()
    finally:
        client.cancel(futures)
