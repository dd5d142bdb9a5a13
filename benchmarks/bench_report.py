#!/usr/bin/env python
"""`brdfnorm report` (what `make demo` runs) on a fresh machine and again: issue 39 item 5's report row (≤ 30 s).

Usage: ``python benchmarks/bench_report.py [--runs N] [--kernels]``. Each run gives the command new, empty caches — the
kernel cache (``BRDFNORM_CACHE_DIR``) and Numba's cache of the package's own kernels (``NUMBA_CACHE_DIR``), as on a
fresh clone — then runs it a second time on the caches it filled. Printed per run: wall seconds, CPU seconds of the
command with the child that compiles ahead on the second core (``brdfnorm.parallel.warm``; user + system, from rusage:
on a shared machine the wall time grows with the load, the CPU time hardly), the load average before, and whether the
page is byte-identical to the first run's. Idle, the cold run's wall time is about half its CPU seconds where the two
processes' shares balance (docs/performance.md has the timeline).

``--kernels``: the first run's empty-cache pass also lists every function Numba compiled, per process (the command,
the child), with its CPU seconds of compile less those of the functions compiled within it (Numba's
``numba:compile`` events, recorded by a ``sitecustomize`` hook put first on the command's path; loads from a cache
are not compiles and are not listed), then each process's timeline: its outermost compiles and its waits on the
other's compile marks (:data:`brdfnorm.engine.compiled.marks.AWAIT_EVENT`), in wall seconds from the command's start,
with their CPU seconds: who waited on what, and for how long against the other's work.
"""

from __future__ import annotations

import argparse
import collections
import filecmp
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from brdfnorm.cli import BLAS_THREADS

ROOT = Path(__file__).resolve().parent.parent


#: The compile log's hook: per process, one line per compile (name, CPU s less nested compiles, depth, wall start and
#: end, CPU s with nested compiles) and per wait on another process's compile mark (marks.AWAIT_EVENT).
_HOOK = """\
import atexit, os, signal, time
from numba.core import event
_stack = []
def _write(kind, name, own, start, spent, clock):
    # (written at once: the child is stopped, not left to exit, where the command ends first)
    with open(os.path.join(os.environ["BRDFNORM_BENCH_COMPILES"], f"{os.getpid()}.tsv"), "a") as out:
        out.write(f"{kind}\\t{name}\\t{own:.3f}\\t{len(_stack)}\\t{start:.3f}\\t{time.time():.3f}\\t{spent:.3f}\\t{clock:.3f}\\n")
class _Compiles(event.Listener):
    def on_start(self, ev):
        f = ev.data["dispatcher"].py_func
        _stack.append([f"{f.__module__}.{f.__qualname__}", time.process_time(), 0.0, time.time()])
    def on_end(self, ev):
        name, start, inner, wall = _stack.pop()
        spent = time.process_time() - start
        if _stack:
            _stack[-1][2] += spent
        _write("compile", name, spent - inner, wall, spent, start)
class _Waits(event.Listener):
    def on_start(self, ev):
        self.wall, self.cpu = time.time(), time.process_time()
    def on_end(self, ev):
        _write("await", ev.data["mark"], 0.0, self.wall, time.process_time() - self.cpu, self.cpu)
event.register("numba:compile", _Compiles())
event.register("brdfnorm:await", _Waits())
def _end(*_):
    _write("end", "-", 0.0, time.time(), time.process_time(), time.process_time())
    if _:  # stopped (SIGTERM): the child, whose command ended first
        os._exit(0)
atexit.register(_end)
signal.signal(signal.SIGTERM, _end)
"""


def _run(caches: Path, out: Path, log: Path | None = None) -> dict:
    env = dict(os.environ, BRDFNORM_CACHE_DIR=str(caches / "kernels"), NUMBA_CACHE_DIR=str(caches / "numba"),
               PYTHONPATH=str(ROOT / "src"))
    if log is not None:
        log.mkdir()
        (log / "sitecustomize.py").write_text(_HOOK, encoding="utf-8")
        env.update(PYTHONPATH=f"{log}{os.pathsep}{ROOT / 'src'}", BRDFNORM_BENCH_COMPILES=str(log))
        # The hook imports numpy (through Numba) before the command line can ask for one BLAS thread
        # (cli._one_blas_thread): asked here instead, so the logged run computes as the others do (the fits' residuals
        # differ in their last bits with the BLAS threads, and the page with them).
        if not any(name in os.environ for name in BLAS_THREADS):
            env.update(OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start, started = time.perf_counter(), time.time()
    subprocess.run([sys.executable, "-m", "brdfnorm", "report", "-o", str(out)], env=env, check=True,
                   capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)  # the command and its child
    return {"wall_s": wall, "cpu_s": cpu, "load": load, "started": started}


def _short(name: str) -> str:
    return name.replace("numba.np.", "").replace("brdfnorm.engine.compiled.", "").split(".<locals>")[0]


def _kernels(log: Path, started: float) -> None:
    """The compile log of one run: per process (the first to start is the command), CPU s per function, then its
    timeline: each outermost compile and each wait on the other's compile mark, in wall seconds from the command's
    start, with its CPU seconds (nested compiles included)."""
    files = sorted(log.glob("*.tsv"), key=lambda path: int(path.stem))
    for role, path in zip(("command", "child"), files, strict=False):
        spent, timeline, ended = collections.Counter(), [], (math.nan, math.nan)
        for line in path.read_text(encoding="utf-8").splitlines():
            kind, name, own, depth, start, end, cpu, clock = line.split("\t")
            if kind == "end":
                ended = (float(start) - started, float(cpu))
                continue
            if kind == "compile":
                spent[_short(name)] += float(own)
            if int(depth) == 0 or kind == "await":
                timeline.append((float(start) - started, float(end) - started, float(cpu), float(clock), kind,
                                 _short(name)))
        total = sum(spent.values())
        waited = sum(end - start for start, end, _, _, kind, _ in timeline if kind == "await")
        print(f"  {role}: {total:.1f} CPU s of compile, {waited:.1f} s waiting on the other's marks; ended at "
              f"{ended[0]:.1f} s wall, {ended[1]:.1f} CPU s in all", flush=True)
        for name, seconds in spent.most_common():
            if seconds >= 0.2:
                print(f"    {seconds:6.2f}  {name}")
        print(f"  {role}'s timeline (wall s from the command's start; the process's CPU clock then, which is its wall "
              "clock on an idle machine less its waits; CPU s; outermost compiles >= 0.3 s, and waits):")
        for start, end, cpu, clock, kind, name in sorted(timeline):
            if kind == "await" or cpu >= 0.3:
                what = f"waits on {name}" if kind == "await" else name
                print(f"    {start:6.1f} – {end:6.1f}  clock {clock:6.1f}  {cpu:6.2f}  {what}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--kernels", action="store_true", help="list what the first run compiles, per process")
    arguments = parser.parse_args()
    runs = arguments.runs
    with tempfile.TemporaryDirectory() as scratch:
        first = None
        for index in range(runs):
            caches = Path(scratch) / f"caches{index}"
            for state in ("empty caches", "warm caches"):
                out = Path(scratch) / f"report{index}-{state[:4]}"
                log = Path(scratch) / "compiles" if arguments.kernels and index == 0 and state[0] == "e" else None
                row = _run(caches, out, log)
                page = out / "index.html"
                first = first or page
                same = "same page" if filecmp.cmp(first, page, shallow=False) else "PAGE DIFFERS"
                print(f"run {index + 1}, {state}: {row['wall_s']:.1f} s wall, {row['cpu_s']:.1f} CPU s "
                      f"(load {row['load']:.2f} before), {same}", flush=True)
                if log is not None:
                    _kernels(log, row["started"])


if __name__ == "__main__":
    main()
