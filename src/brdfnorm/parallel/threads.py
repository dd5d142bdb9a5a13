"""A batch of albedo cells on every local core in this process: threads around the compiled kernels (issue #39, item 2).

The compiled backend's kernels (:mod:`brdfnorm.engine.compiled`) are compiled with ``nogil=True``: while one runs,
the interpreter lock is free, so a second Python thread can run another kernel, or the routes' Python between them,
at the same time. Threads need no second interpreter, no pickled model and no second Numba start (a local process
pool pays ~1.5 s for these, :data:`brdfnorm.parallel.executors.POOL_START_SECONDS`, more than a 32 × 32 table's E
takes), and they reach every stage of a table (E, E_avg's nodes, the DFG channels), where the process pool takes
the E cells only.

How a batch is split (:func:`cell_tasks`): into blocks of ``SPLIT × chunk`` cells, each block into :data:`SPLIT`
strided subsets (cells start, start + SPLIT, …; start + 1, …), so that each task gets a share of every row of the
table (grazing views cost 10–100× a head-on view; contiguous halves of a μ-major table would leave one thread with
all of them). The threads take the tasks in order as they finish their last.

Why the tables are bit-for-bit the same for any thread count: the tasks, and so the batches each albedo call sees,
depend on the batch only, never on the number of threads. That matters: most routes compute each case on its own,
but not all — the generic panels of ``oren-nayar`` settled a case of E_avg (μ = 0.985, σ = 0.2, rtol 2.5e-9) in
203 997 evaluations within its batch of 120 nodes and in 230 195 alone, values 6e-11 apart (within the estimate),
and a split by thread count made the E_avg of a small table differ between one and two threads
(``tests/lut/test_table_threads.py`` compares whole tables on one and two threads, that one included). Two subsets
per block cost 1 % more CPU on one thread than one call per 256 cells (the 32 × 32 ``examples/ggx.brdf`` table: 52
albedo calls instead of 28, 2.87 → 2.90 CPU s), four 10 %.

What the threads share, and why it is safe: kernels are compiled or loaded once per process under a lock
(:func:`brdfnorm.engine.compiled.drivers.native_integrand`) and under Numba's own compiler lock; each albedo call has
its own arrays, and the results are scattered back by the calling thread into distinct cells; the calling thread's
context (the backend :func:`brdfnorm.engine.compiled.backend.scope`, numpy's error state) is copied into each task;
the warning filters are set once by the caller around the whole batch (``warnings.catch_warnings`` is not thread
safe: per thread, it could leave a filter behind).

How many threads: :func:`scope` (a context variable, as the backend's
:func:`brdfnorm.engine.compiled.backend.scope`), set where a table or an audit starts and read where a batch is cut
into tasks; no stage passes it on. Two stages that do not depend on each other (a table's E and E_avg) run at once
with :func:`beside`; the warning filter the batches need is set once around both (:func:`albedo_warnings_ignored`).

Which task runs when two stages share the cores (:class:`Slots`): at most ``threads`` tasks at once. The stage
beside is the critical path (a table's E_avg: a chain of dependent albedo calls, ~1.2 CPU s of the 32 × 32
``examples/ggx.brdf`` table's ~2.4): it holds one slot from its start to its end, its Python between calls
included, and takes every other slot that frees before the caller's tasks do (its tasks on its own thread and on
helpers that wait for a slot); the caller's tasks (E) run in the slots left. Before, three threads (E_avg's and
E's two) shared two cores, and E_avg, starved, ended ~0.3 s after E (docs/performance.md, "Eighth round: the
E_avg chain"). A task keeps its slot to its end (a compiled kernel cannot be stopped), so while E's costliest task (256
grazing cells, ~0.7 s) runs, E_avg's batches run on its own slot alone: in effect E_avg has one core and E the
other, and E_avg takes both wherever E's tasks leave a slot free; a batch nested in a task runs in the task's slot.
Which thread runs a task changes nothing in its result.

Only where it pays: :func:`local_threads` is 1 under the numpy backend (its numpy calls hold the lock between
short array operations) and for a Dask cluster (its workers compute the cells).
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import threading
import warnings
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from numbers import Integral
from typing import TypeVar

import numpy as np

Result = TypeVar("Result")
Function = TypeVar("Function", bound=Callable)
#: The threads a batch of cells runs on (:func:`scope`), as the backend's scope is carried
#: (:func:`brdfnorm.engine.compiled.backend.scope`): set once where a table or an audit starts, read where the cells
#: are cut into tasks (:func:`current`), through every stage between without being passed by hand.
_THREADS: contextvars.ContextVar[int] = contextvars.ContextVar("brdfnorm_threads", default=1)
#: Set where the albedo batches' UserWarnings are already being ignored (:func:`albedo_warnings_ignored`).
_QUIET: contextvars.ContextVar[bool] = contextvars.ContextVar("brdfnorm_quiet", default=False)
#: Set in a stage that runs beside another (:func:`beside`): its next batch of cells does not start once it is set.
_STOP: contextvars.ContextVar[threading.Event | None] = contextvars.ContextVar("brdfnorm_stop", default=None)
#: Set while two stages share the cores (:func:`beside`): the slots, and whether this context's stage holds one (the
#: stage beside, the critical path) or takes one per task (the caller's).
_SLOTS: contextvars.ContextVar[tuple[Slots, bool] | None] = contextvars.ContextVar("brdfnorm_slots", default=None)


class Stopped(Exception):
    """A stage running :func:`beside` the caller's was stopped because the caller's failed."""

#: Strided subsets per block of cells (module docstring): a constant, so that the batches do not depend on the
#: number of threads.
SPLIT = 2


def local_threads(workers: int | None = None, scheduler: object = None) -> int:
    """Threads a table's cells run on in this process: ``workers`` (None: every core this process may run on) where
    the compiled backend computes (as :func:`brdfnorm.engine.compiled.backend.resolve` says now) and no Dask
    ``scheduler`` is given; else 1."""
    from ..engine.compiled.backend import resolve
    from .cores import local_cores

    if scheduler is not None or resolve() != "compiled":
        return 1
    if workers is None:
        return local_cores()
    # (a value that is not a whole number ≥ 1 is refused where the workers are validated: Workers)
    return int(workers) if isinstance(workers, Integral) and not isinstance(workers, bool) and workers > 1 else 1


@contextlib.contextmanager
def scope(threads: int | None) -> Iterator[None]:
    """Within the block, batches of cells run on ``threads`` threads of this process (None: no change; outside
    every scope, one: the caller's thread)."""
    token = _THREADS.set(_THREADS.get() if threads is None else max(1, int(threads)))
    try:
        yield
    finally:
        _THREADS.reset(token)


def current() -> int:
    """The threads of the innermost :func:`scope` (1 outside every scope)."""
    return _THREADS.get()


def scoped(function: Function) -> Function:
    """``function`` with its ``threads`` keyword (None: the caller's scope) setting :func:`scope` for its call —
    public functions keep the argument, and nothing below them passes it on."""

    @functools.wraps(function)
    def within(*args, **kwargs):
        with scope(kwargs.get("threads")):
            return function(*args, **kwargs)

    return within  # type: ignore[return-value]


@contextlib.contextmanager
def albedo_warnings_ignored() -> Iterator[None]:
    """Within the block, :func:`brdfnorm.albedo`'s UserWarnings (unconverged cells, which a table reports per cell)
    are ignored. The filter is set by the first thread to enter, once, around everything under it, threads it
    starts included: ``warnings.catch_warnings`` changes the process's filters and restores them on exit, so two
    threads entering it at once can leave a filter behind or lift one early; threads whose context says the filter
    is set (the tasks of :func:`run_tasks`, a stage :func:`beside`) enter nothing."""
    if _QUIET.get():
        yield
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        token = _QUIET.set(True)
        try:
            yield
        finally:
            _QUIET.reset(token)


class Slots:
    """At most ``count`` tasks at once (module docstring): :meth:`acquire` a slot, ``urgent`` before every waiting
    task that is not; ``wanted`` (called under the lock) says whether a waiter still wants one."""

    def __init__(self, count: int) -> None:
        self.lock = threading.Condition()
        self._free = max(1, int(count))
        self._urgent = 0

    def acquire(self, urgent: bool = False, wanted: Callable[[], bool] = lambda: True) -> bool:
        """Wait for a slot and take it (True), or give up once ``wanted()`` is false (False)."""
        with self.lock:
            self._urgent += urgent
            try:
                while wanted() and (self._free == 0 or (self._urgent and not urgent)):
                    self.lock.wait()
                if not wanted():
                    return False
                self._free -= 1
                return True
            finally:
                self._urgent -= urgent
                self.lock.notify_all()  # (an urgent waiter that leaves may let the others in)

    def release(self) -> None:
        with self.lock:
            self._free += 1
            self.lock.notify_all()


@contextlib.contextmanager
def beside(function: Callable[..., Result], *args, **kwargs) -> Iterator[Callable[[], Result]]:
    """``function(*args, **kwargs)`` on a thread of its own while the block runs (in a copy of the caller's context:
    the scopes, the warning filter's flag); yields a callable that waits for it and returns its result or raises
    its exception. The two share :func:`current` threads' worth of :class:`Slots`, ``function`` first (the
    critical path: module docstring). Where the block fails, the other stage stops before its next batch of cells
    (:class:`Stopped`) and is waited for (a compiled kernel cannot be stopped midway)."""
    stop = threading.Event()
    slots = Slots(current())
    context = contextvars.copy_context()
    context.run(_STOP.set, stop)
    context.run(_SLOTS.set, (slots, True))

    def holding() -> Result:
        try:
            return function(*args, **kwargs)
        finally:
            slots.release()

    slots.acquire(urgent=True)  # (here, before the caller's first task can take it)
    pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="brdfnorm-stage")
    future = pool.submit(context.run, holding)
    token = _SLOTS.set((slots, False))
    try:
        yield future.result
    except BaseException:
        stop.set()
        raise
    finally:
        _SLOTS.reset(token)
        pool.shutdown(wait=True)


def cell_tasks(count: int, chunk: int, split: int = SPLIT) -> list[np.ndarray]:
    """The cells 0 … count − 1 as tasks of at most ``chunk`` cells: blocks of ``split × chunk`` cells, each split
    into ``split`` strided subsets (module docstring)."""
    tasks = []
    for start in range(0, count, split * chunk):
        stop = min(count, start + split * chunk)
        tasks.extend(np.arange(start + t, stop, split) for t in range(min(split, stop - start)))
    return tasks


def run_tasks(function: Callable[[np.ndarray], Result], tasks: Sequence[np.ndarray], threads: int) -> list[Result]:
    """``function(task)`` for every task, in order of the tasks; on ``threads`` threads of this process where that
    is more than one (each task in a copy of the caller's context), else here. A failure in any task, or Ctrl-C
    (:class:`KeyboardInterrupt` in the calling thread), is raised here after the tasks not yet started are cancelled
    and the running ones have finished: a compiled kernel cannot be stopped midway, so Ctrl-C waits for at most one
    albedo call per thread (a 32 × 32 ``examples/ggx.brdf`` table's costliest, 256 grazing cells, ~0.7 s)."""
    stop = _STOP.get()
    if stop is not None:
        original = function

        def function(task: np.ndarray) -> Result:
            if stop.is_set():
                raise Stopped("stopped: the stage beside this one failed")
            return original(task)

    shared = _SLOTS.get()
    if shared is not None and shared[1]:
        return _run_holding(function, tasks, threads, shared[0])
    if shared is not None:  # the caller's stage beside a critical one: one slot per task
        slots, ungated = shared[0], function

        def function(task: np.ndarray) -> Result:
            slots.acquire()
            token = _SLOTS.set(None)  # (a batch nested in the task runs in the slot the task holds)
            try:
                return ungated(task)
            finally:
                _SLOTS.reset(token)
                slots.release()

    if threads <= 1 or len(tasks) <= 1:
        return [function(task) for task in tasks]
    pool = ThreadPoolExecutor(max_workers=min(threads, len(tasks)), thread_name_prefix="brdfnorm-cells")
    try:
        futures = [pool.submit(contextvars.copy_context().run, function, task) for task in tasks]
        return [future.result() for future in futures]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _run_holding(function: Callable[[np.ndarray], Result], tasks: Sequence[np.ndarray], threads: int,
                 slots: Slots) -> list[Result]:
    """:func:`run_tasks` for the stage that holds a slot (:func:`beside`): its thread takes the tasks in order, and
    up to ``threads`` − 1 helpers take them too once each gets a slot (before any task of the other stage does);
    the helpers give up their wait when no task is left. The first failing task's exception (in the tasks'
    order) is raised once every started task has finished."""
    results: list = [None] * len(tasks)
    failures: dict[int, BaseException] = {}
    taken = [0]

    def left() -> bool:
        return taken[0] < len(tasks)

    def claim() -> int | None:
        with slots.lock:
            if not left():
                return None
            taken[0] += 1
            if not left():
                slots.lock.notify_all()  # (helpers still waiting for a slot give up)
            return taken[0] - 1

    def work() -> None:
        while (index := claim()) is not None:
            try:
                results[index] = function(tasks[index])
            except BaseException as failure:  # (KeyboardInterrupt included: raised below, in the caller)
                failures[index] = failure
                with slots.lock:
                    taken[0] = len(tasks)
                    slots.lock.notify_all()

    def helper() -> None:
        with slots.lock:
            wanted = left()
        if wanted and slots.acquire(urgent=True, wanted=left):
            try:
                work()
            finally:
                slots.release()

    helpers = min(threads, len(tasks)) - 1
    pool = ThreadPoolExecutor(max_workers=helpers, thread_name_prefix="brdfnorm-cells") if helpers > 0 else None
    try:
        waiting = [pool.submit(contextvars.copy_context().run, helper) for _ in range(helpers)] if pool else []
        work()
    finally:
        with slots.lock:  # (where the caller's own work was interrupted, no helper starts another task)
            taken[0] = len(tasks)
            slots.lock.notify_all()
        if pool is not None:
            pool.shutdown(wait=True)
    for future in waiting:
        future.result()
    if failures:
        raise failures[min(failures)]
    return results
