"""Compiling the kernels a command will need on a second core, while the first computes.

The compiled backend compiles each lobe's kernels once per machine (about 3 s of CPU per lobe, then loaded from the
per-user disk cache, :mod:`brdfnorm.engine.compiled.drivers`), and some routes have kernels of their own, shared by
every lobe they integrate: the microfacet lobes' half-vector route (:data:`ROUTE_KERNELS`: its rectangle integrand
and its fused global rule, 13 s of CPU, cached by Numba beside the package). A first run of a command that visits
several lobes — the demo's report visits eight and the microfacet route — used to compile them one after the other
on one core, while the other core idled (docs/performance.md).

:func:`ahead` starts one child process (``python -m brdfnorm.parallel.warm``) that compiles, into the same disk
caches, the kernels of the given models that are not there yet. The models come in the order the command first
needs them, each with the method that integrates it; the child takes the route's kernels first (the longest
compile, with the global rules' shared kernels, :func:`brdfnorm.engine.compiled.global_rule.shared_kernels`, which
the command's :func:`~brdfnorm.engine.compiled.global_rule.shader_global` then loads; a command reaches the route
only after its first lobes), then the lobes in the order the command needs them from the second on, the first last:
the command compiles its first lobe itself at once, with the shaders' global rule, which the child leaves to it, and
by the time the child is through the route the command is at its next lobes, which the child then compiles just
ahead of it (docs/performance.md, the seventh round's timeline). Whoever compiles a lobe's or a route's kernels
holds a mark in the cache (:mod:`brdfnorm.engine.compiled.marks`): where the command reaches a lobe the child is
compiling, it waits for it and loads it; before each job, the child looks again and skips what the command
compiled, or is compiling, meanwhile. The child's results are only compiled code: every albedo is still computed
by the command, so its numbers do not depend on whether or when the child ran. Numba and
:func:`~brdfnorm.engine.compiled.drivers.kernels_file` write their cache files by atomic renames, so a kernel both
compile is written whole by one.

Nothing is started where the backend is numpy, where one core is all there is, or where every kernel is compiled;
the child is stopped when the block ends (what it finished stays in the cache for the next run).
"""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from ..errors import ArgumentError
from ..models.base import Model
from .cores import local_cores
from .job import ModelSource

#: The view angle (radians) and tolerance of the child's one albedo per job: any albedo compiles every kernel.
_ANGLE, _RTOL = 0.5, 1e-3

#: The albedo method whose route has kernels of its own (compiled once per machine for every lobe it takes, not per
#: shader), and those kernels as (module of ``brdfnorm.engine.compiled``, function).
ROUTE_KERNELS = {"microfacet": (("slopes", "microfacet_grid"), ("global_rule", "fused_global"))}


def _microfacet_route(model: Model) -> None:
    """Compile the microfacet route's kernels as tables call them: a 2 × 2 split-sum (DFG) table of ``model``
    (:func:`brdfnorm.lut.compute`) at rtol 1e-8, whose cell (μ, α) = (3/64, 1/64), of the report's 32 × 32 texel
    grid, leaves the global rule for the rectangles. (One albedo does not do: with one case the global rule is given
    a read-only array, another signature, and at a view where it converges the rectangles never compile.)"""
    import numpy as np

    from ..lut import compute

    compute(model, {"mu": np.array([3 / 64, 0.5]), "alpha": np.array([1 / 64, 0.5])},
            clamp={"mu": 1e-4, "alpha": 1e-8}, rtol=1e-8, channels=["dfg"], average=False, backend="compiled")


#: How the child compiles a route's kernels, given a model the route takes.
_ROUTE_RUNS = {"microfacet": _microfacet_route}


def _microfacet_mark():
    from ..engine.compiled.global_rule import route_mark

    return route_mark()


#: The mark (or None) a process holds while it compiles a route's kernels, the command's side included.
_ROUTE_MARKS = {"microfacet": _microfacet_mark}


@dataclass(frozen=True)
class Job:
    """One thing for the child to compile: a model's own kernels (``method`` "quadrature", the generic route that
    compiles every kernel of its shader), or the kernels of the route ``method`` (:data:`ROUTE_KERNELS`)."""

    source: ModelSource
    method: str = "quadrature"

    def to_json(self) -> dict:
        return {"source": self.source.to_json(), "method": self.method}

    @classmethod
    def from_json(cls, data: dict) -> Job:
        return cls(ModelSource.from_json(data["source"]), data["method"])

    def done(self) -> bool:
        """Whether its kernels are in the disk caches now."""
        if self.method in ROUTE_KERNELS:
            return route_compiled(self.method)
        from ..engine.compiled.drivers import kernels_compiled

        kernel = self.source.load().native_kernel()
        return kernel is None or kernels_compiled(kernel.key)


def route_compiled(method: str) -> bool:
    """Whether Numba's disk cache holds every kernel of route ``method`` (:data:`ROUTE_KERNELS`) for this source."""
    import importlib

    for module, name in ROUTE_KERNELS[method]:
        dispatcher = getattr(importlib.import_module(f"brdfnorm.engine.compiled.{module}"), name)
        try:  # the cache's index of compiled signatures, empty where missing or stale (another source, Numba)
            if not dispatcher._cache._cache_file._load_index():
                return False
        except Exception:  # noqa: BLE001 - a Numba without this index: compile (the child costs the other core)
            return False
    return True


#: What a command needs compiled: a model (its own kernels, for the generic quadrature), or (method, model): the
#: model integrated by ``method`` (the route's kernels where :data:`ROUTE_KERNELS` has it, else the model's own).
Need = Model | tuple[str, Model]


def pending(needs: Sequence[Need]) -> list[Job]:
    """What the child is to compile for ``needs`` (given in the order first needed), in that order, one job per
    route and per kernel key, and only what is not in the caches."""
    from ..engine.compiled.backend import resolve
    from ..engine.compiled.drivers import kernels_compiled

    if resolve() != "compiled":
        return []
    out, seen = [], set()
    for need in needs:
        method, model = need if isinstance(need, tuple) else ("quadrature", need)
        if method in ROUTE_KERNELS:
            key, compiled = method, route_compiled
        else:
            kernel = model.native_kernel()
            if kernel is None:
                continue
            key, compiled, method = kernel.key, kernels_compiled, "quadrature"
        if key in seen or compiled(key):
            continue
        seen.add(key)
        try:
            out.append(Job(ModelSource.of(model), method))
        except ArgumentError:  # a model that cannot travel (a Python subclass) compiles where it is used
            continue
    return out


def order(jobs: Sequence[Job]) -> list[Job]:
    """The child's order of ``jobs`` (in the order first needed): the route jobs first, then the lobes in the order
    needed from the second on, the first last (the command compiles it at once); where no route job, all from the
    last back (the command compiles the first lobes as it reaches them, the child the last)."""
    routes = [job for job in jobs if job.method in ROUTE_KERNELS]
    if not routes:
        return list(reversed(jobs))
    lobes = [job for job in jobs if job.method not in ROUTE_KERNELS]
    return routes + lobes[1:] + lobes[:1]


@contextlib.contextmanager
def ahead(needs: Sequence[Need]) -> Iterator[int]:
    """Within the block, a child process compiles the missing kernels of ``needs`` (:data:`Need`, given in the order
    the block first needs them); yields how many jobs it was given (0: no child)."""
    jobs = pending(needs)
    # one lobe alone is needed at once: the child would only race for it (a route is needed later)
    if not jobs or (len(jobs) == 1 and jobs[0].method not in ROUTE_KERNELS) or local_cores() < 2:
        yield 0
        return
    child = subprocess.Popen([sys.executable, "-m", __name__], stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
    try:
        with child.stdin:
            child.stdin.write(json.dumps([job.to_json() for job in order(jobs)]).encode())
        yield len(jobs)
    finally:
        if child.poll() is None:
            child.terminate()
        child.wait()
        from ..engine.compiled.drivers import cache_directory
        from ..engine.compiled.marks import release

        release(cache_directory(), child.pid)  # the mark of a lobe it was stopped compiling


def _compile(jobs: list[dict]) -> None:
    """The child: per job, one albedo by the generic quadrature on the compiled backend (which compiles and caches
    the lobe's kernels) or the route's run (:data:`_ROUTE_RUNS`), skipping what is compiled by then, or being
    compiled by the command; the shaders' global rule it leaves to the command, which compiles it at its first lobe
    (:func:`~brdfnorm.engine.compiled.global_rule.shader_rule_left_to_others`)."""
    import warnings

    from ..engine.compiled.drivers import compiling_mark
    from ..engine.compiled.global_rule import shader_rule_left_to_others
    from ..engine.compiled.marks import holder, holding
    from ..engine.methods import albedo

    for data in jobs:
        with contextlib.suppress(Exception), warnings.catch_warnings(), shader_rule_left_to_others():
            warnings.simplefilter("ignore")
            job = Job.from_json(data)
            if job.done():
                continue
            model = job.source.load()
            if job.method in _ROUTE_RUNS:
                mark = _ROUTE_MARKS[job.method]()
                if mark is not None and holder(mark) is not None:  # the command compiling them now
                    continue
                with holding(mark) if mark is not None else contextlib.nullcontext():
                    _ROUTE_RUNS[job.method](model)
                continue
            mark = compiling_mark(model.native_kernel().key)
            if holder(mark) is not None:  # the command compiling them now: the next job
                continue
            with holding(mark):  # the command waits for these, not compiles
                albedo(model, _ANGLE, method="quadrature", rtol=_RTOL, backend="compiled")

if __name__ == "__main__":
    _compile(json.loads(sys.stdin.read()))
