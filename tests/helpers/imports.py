"""Which modules a snippet of code imports, seen from a new process (``sys.modules`` of the test process holds
whatever the other tests imported): the probe of the import-cost tests."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Sequence

from .paths import SRC


def imported(code: str, modules: Sequence[str]) -> dict[str, bool]:
    """Per module of ``modules``, whether it is in ``sys.modules`` after ``code`` ran in a new interpreter on the
    repository's sources."""
    env = {**os.environ, "PYTHONPATH": str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    probe = f"import sys, json\n{code}\nprint(json.dumps({{m: m in sys.modules for m in {list(modules)!r}}}))"
    done = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])
