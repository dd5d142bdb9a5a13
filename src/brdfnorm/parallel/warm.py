"""Compiling the kernels a command will need on a second core, while the first computes.

The compiled backend compiles each lobe's kernels once per machine (about 2 s of CPU per lobe, then loaded from the
per-user disk cache, :mod:`brdfnorm.engine.compiled.drivers`). A first run of a command that visits several lobes —
the demo's report visits eight — used to compile them one after the other on one core, while the other core idled:
on an idle 2-core machine the first report took 32 s against 15 s once compiled (docs/performance.md).

:func:`ahead` starts one child process (``python -m brdfnorm.parallel.warm``) that compiles, into the same disk
cache, the kernels of the given models that are not there yet, in the reverse of the order the command needs them:
the command compiles its first lobes itself as it reaches them, the child the last ones, and where the two meet the
command loads what the child wrote. The child's results are only compiled code: every albedo is still computed by the
command, so its numbers do not depend on whether or when the child ran. Numba and :func:`~brdfnorm.engine.compiled.
drivers.kernels_file` write their cache files by atomic renames, so a kernel both compile is written whole by one.

Nothing is started where the backend is numpy, where one core is all there is, or where every kernel is compiled;
the child is stopped when the block ends (what it finished stays in the cache for the next run).
"""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
from collections.abc import Iterator, Sequence

from ..errors import ArgumentError
from ..models.base import Model
from .executors import local_cores
from .job import ModelSource

#: The view angle (radians) and tolerance of the child's one albedo per model: any albedo compiles every kernel.
_ANGLE, _RTOL = 0.5, 1e-3


def pending(models: Sequence[Model]) -> list[ModelSource]:
    """The sources of ``models`` (first need first, one per kernel) whose compiled kernels are not in the cache."""
    from ..engine.compiled.backend import resolve
    from ..engine.compiled.drivers import kernels_compiled

    if resolve() != "compiled":
        return []
    out, seen = [], set()
    for model in models:
        kernel = model.native_kernel()
        if kernel is None or kernel.key in seen or kernels_compiled(kernel.key):
            continue
        seen.add(kernel.key)
        try:
            out.append(ModelSource.of(model))
        except ArgumentError:  # a model that cannot travel (a Python subclass) compiles where it is used
            continue
    return out


@contextlib.contextmanager
def ahead(models: Sequence[Model]) -> Iterator[int]:
    """Within the block, a child process compiles the missing kernels of ``models`` (given in the order the block
    first needs them); yields how many it was given (0: no child)."""
    sources = pending(models)
    if len(sources) < 2 or local_cores() < 2:  # the first is needed at once: the child would only race for it
        yield 0
        return
    child = subprocess.Popen([sys.executable, "-m", __name__], stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
    try:
        with child.stdin:
            child.stdin.write(json.dumps([s.to_json() for s in reversed(sources)]).encode())
        yield len(sources)
    finally:
        if child.poll() is None:
            child.terminate()
        child.wait()


def _compile(sources: list[dict]) -> None:
    """The child: one albedo of each model on the compiled backend (which compiles and caches its kernels)."""
    import warnings

    from ..engine.methods import albedo

    for data in sources:
        with contextlib.suppress(Exception), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            albedo(ModelSource.from_json(data).load(), _ANGLE, method="quadrature", rtol=_RTOL, backend="compiled")


if __name__ == "__main__":
    _compile(json.loads(sys.stdin.read()))
