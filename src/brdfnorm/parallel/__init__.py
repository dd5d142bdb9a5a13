"""Tables of albedo cells spread over all local cores or a Dask cluster, with resumable checkpoints (issue #17).

What scales is the number of cells: each cell is one independent albedo integral, so a table of many cells
splits into chunks that run anywhere. A single integral does not get faster — it stays one vectorized batch
in one process.

>>> import numpy as np, brdfnorm as bn
>>> from brdfnorm.parallel import CellsJob, albedo_cells
>>> job = CellsJob.of(bn.load("phong"), np.radians([0.0, 30.0, 60.0]), values={"n": [10.0, 100.0, 1000.0]},
...                   rtol=1e-9)
>>> table = albedo_cells(job, workers=1)
>>> table.value.shape, bool(table.converged.all())
((3, 1), True)

:class:`CellsJob` is the definition (model source, settings, cells; :mod:`.job`), :func:`albedo_cells` computes it
(:func:`run_job` computes several jobs on one open :class:`Workers`): chunks fixed by the job (so the result is
bit-for-bit the same in one process, N local processes or on Dask workers), computed in-process (``workers=1``), by
a local process pool (default: all cores) or on a Dask cluster (``scheduler="tcp://HOST:PORT"``), each finished
chunk written to ``checkpoint`` (a directory) when one is given, and only the missing chunks computed when it
already holds some.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..registry import lazy_exports

if TYPE_CHECKING:
    from .cells import CellsResult, albedo_cells, run_job, sigterm_as_interrupt
    from .cores import local_cores
    from .executors import ChunkResult, Scheduler, Workers, run_chunk
    from .job import AlbedoSettings, CellsJob, ChunkPlan, ModelSource, chunk_plan

__all__ = ["AlbedoSettings", "CellsJob", "CellsResult", "ChunkPlan", "ChunkResult", "ModelSource", "Scheduler",
           "Workers", "albedo_cells", "chunk_plan", "local_cores", "run_chunk", "run_job", "sigterm_as_interrupt"]


#: The names of :data:`__all__`, imported at first use (PEP 562): a table on this process's threads imports
#: :mod:`.threads` (and through it this package) without the process pool, the Dask client, the checkpoints and
#: :mod:`multiprocessing` (~0.03 s of a command's start, docs/performance.md, eighth round).
__getattr__, __dir__ = lazy_exports(__name__, {
    **dict.fromkeys(("CellsResult", "albedo_cells", "run_job", "sigterm_as_interrupt"), "cells"),
    "local_cores": "cores",
    **dict.fromkeys(("ChunkResult", "Scheduler", "Workers", "run_chunk"), "executors"),
    **dict.fromkeys(("AlbedoSettings", "CellsJob", "ChunkPlan", "ModelSource", "chunk_plan"), "job"),
})
