#!/usr/bin/env python
"""`brdfnorm report` (what `make demo` runs) on a fresh machine and again: issue 39 item 5's report row (≤ 30 s).

Usage: ``python benchmarks/bench_report.py [--runs N]``. Each run gives the command new, empty caches — the kernel
cache (``BRDFNORM_CACHE_DIR``) and Numba's cache of the package's own kernels (``NUMBA_CACHE_DIR``), as on a fresh
clone — then runs it a second time on the caches it filled. Printed per run: wall seconds, CPU seconds of the command
with the child that compiles ahead on the second core (``brdfnorm.parallel.warm``; user + system, from rusage: on a
shared machine the wall time grows with the load, the CPU time hardly), the load average before, and whether the
page is byte-identical to the first run's. Idle, the cold run's wall time is about half its CPU seconds where the
two processes' shares balance (docs/performance.md has the timeline).
"""

from __future__ import annotations

import argparse
import filecmp
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _run(caches: Path, out: Path) -> dict:
    env = dict(os.environ, BRDFNORM_CACHE_DIR=str(caches / "kernels"), NUMBA_CACHE_DIR=str(caches / "numba"),
               PYTHONPATH=str(ROOT / "src"))
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "brdfnorm", "report", "-o", str(out)], env=env, check=True,
                   capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)  # the command and its child
    return {"wall_s": wall, "cpu_s": cpu, "load": load}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    runs = parser.parse_args().runs
    with tempfile.TemporaryDirectory() as scratch:
        first = None
        for index in range(runs):
            caches = Path(scratch) / f"caches{index}"
            for state in ("empty caches", "warm caches"):
                out = Path(scratch) / f"report{index}-{state[:4]}"
                row = _run(caches, out)
                page = out / "index.html"
                first = first or page
                same = "same page" if filecmp.cmp(first, page, shallow=False) else "PAGE DIFFERS"
                print(f"run {index + 1}, {state}: {row['wall_s']:.1f} s wall, {row['cpu_s']:.1f} CPU s "
                      f"(load {row['load']:.2f} before), {same}", flush=True)


if __name__ == "__main__":
    main()
