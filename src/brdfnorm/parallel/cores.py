"""The cores this process may run on: the default number of local workers (:mod:`.executors`) and of a table's
threads (:mod:`.threads`), in a module of its own so that the threads do not import the process pool."""

from __future__ import annotations

import os


def local_cores() -> int:
    """Cores this process may run on (the default number of local workers)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)
