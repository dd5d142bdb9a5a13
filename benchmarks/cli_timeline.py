"""Where the wall time of one ``brdfnorm lut`` run goes, from the process's start to its end (docs/performance.md,
"Eighth round: the CLI's serial start"): the issue-39 row ``lut examples/ggx.brdf`` 32 × 32, E + E_avg, ≤ 2 s.

Each run is a new process that runs the command line as ``brdfnorm`` does (``brdfnorm.cli.main()``), with marks
(wall seconds since the process started, from ``/proc/self/stat``, and the process's CPU seconds) put by wrapping,
from outside, the functions a run passes through: ``brdfnorm.cli`` imported; the ``lut`` command's modules
imported (where ``main()`` imports them; in a checkout that imports every command with ``brdfnorm.cli``, there);
the model loaded (``cli.lut.load_model``: the ``.brdf`` file parsed and its GLSL compiled to numpy closures); the
shader's Numba function ready (``glsl.native.native_kernel``: generated, loaded from the disk cache, Numba's start);
the engine's kernels loaded (``engine.compiled.drivers.native_integrand``); the first batch of cells back; E and
E_avg done (their stage lines); the file written; ``main()`` ending (its ``atexit`` functions); the process's end
as its parent sees it. Nothing of the package is changed; Linux only (``/proc``).

``.venv/bin/python benchmarks/cli_timeline.py [--runs 5] [--workers 1] [--src DIR]``: the median and best of each
mark over the runs (the kernel cache is warmed by one untimed run first); ``--src`` times another checkout's
sources (``PYTHONPATH``), to compare two branches in one session.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ARGS = ["lut", str(ROOT / "examples" / "ggx.brdf"), "--axis", "mu=0:1:n=32", "--axis", "roughness=0.05:1:n=32",
        "--clamp", "mu=1e-4", "-p", "f0=1", "--rtol", "1e-10"]

#: The child: marks on stderr as "@MARK wall cpu label", then the command line as the brdfnorm script runs it.
CHILD = r'''
import atexit, os, sys, threading, time
def _start():
    ticks = os.sysconf("SC_CLK_TCK")
    started = int(open("/proc/self/stat").read().rsplit(")", 1)[1].split()[19]) / ticks
    return time.time() - (float(open("/proc/uptime").read().split()[0]) - started)
T0 = _start()
LOCK = threading.Lock()
SEEN = set()
def mark(label, once=True):
    with LOCK:
        if once and label in SEEN:
            return
        SEEN.add(label)
        sys.stderr.write(f"@MARK {time.time() - T0:.4f} {time.process_time():.4f} {label}\n")
mark("interpreter up")
atexit.register(lambda: mark("main() ends (atexit)"))
import brdfnorm.cli as cli
mark("brdfnorm.cli imported")
def wrap(owner, name, label, at_start=None):
    function = getattr(owner, name)
    def wrapper(*args, **kwargs):
        if at_start:
            mark(at_start)
        result = function(*args, **kwargs)
        mark(label)
        return result
    setattr(owner, name, wrapper)
def install():
    import brdfnorm.cli.lut as lut_cli
    import brdfnorm.lut.table as table
    import brdfnorm.glsl.native as native
    from brdfnorm.engine.compiled import drivers
    mark("command's modules imported")
    wrap(lut_cli, "load_model", "model loaded (.brdf parsed)")
    wrap(native, "native_kernel", "shader's Numba function ready")
    wrap(drivers, "native_integrand", "engine kernels loaded")
    wrap(table, "compute_cells", "first batch of cells back")
    wrap(lut_cli, "write_file", "file written")
    echo = lut_cli.typer.echo
    def echoed(message=None, *args, **kwargs):
        text = str(message)
        if ": E: " in text:
            mark("E done")
        elif ": E_avg: " in text:
            mark("E_avg done")
        return echo(message, *args, **kwargs)
    lut_cli.typer.echo = echoed
if hasattr(cli, "register"):  # a checkout that imports the command's modules in main(): marked where it does
    register = cli.register
    def registered(names=None):
        app = register(names)
        install()
        return app
    cli.register = registered
else:  # every command's modules imported with brdfnorm.cli
    install()
sys.argv[0] = "brdfnorm"
cli.main()
'''


def one_run(src: Path, args: list[str]) -> tuple[dict[str, tuple[float, float]], float, float]:
    """The marks of one run, its wall time seen from here, and its CPU seconds (children's rusage)."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    before = os.times()
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CHILD, *args], env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    after = os.times()
    marks = {}
    for line in done.stderr.splitlines():
        if line.startswith("@MARK "):
            _, at, cpu, label = line.split(" ", 3)
            marks[label] = (float(at), float(cpu))
    return marks, wall, (after.children_user - before.children_user) + (after.children_system - before.children_system)


def timeline(src: Path, runs: int, workers: int | None) -> dict:
    with tempfile.TemporaryDirectory() as out:
        args = [*ARGS, "-o", str(Path(out) / "table.json")] + ([] if workers is None else ["--workers", str(workers)])
        one_run(src, args)  # untimed: the kernel cache warm, the files in the page cache
        results = [one_run(src, args) for _ in range(runs)]
    labels = list(results[0][0])
    rows = {label: {"wall_median": statistics.median(r[0][label][0] for r in results if label in r[0]),
                    "wall_best": min(r[0][label][0] for r in results if label in r[0]),
                    "cpu_median": statistics.median(r[0][label][1] for r in results if label in r[0])}
            for label in labels}
    rows["process ended (parent)"] = {"wall_median": statistics.median(r[1] for r in results),
                                      "wall_best": min(r[1] for r in results),
                                      "cpu_median": statistics.median(r[2] for r in results)}
    return {"src": str(src), "runs": runs, "workers": workers, "load_average": os.getloadavg(),
            "bytecode_cache": not sys.dont_write_bytecode, "marks": rows}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--src", type=Path, default=ROOT / "src")
    parser.add_argument("--json", action="store_true", help="the result as JSON")
    options = parser.parse_args()
    result = timeline(options.src.resolve(), options.runs, options.workers)
    if options.json:
        print(json.dumps(result, indent=1))
        return
    print(f"{result['src']}, {options.runs} runs, workers {options.workers or 'default'}, load average "
          f"{result['load_average'][0]:.2f}, bytecode cache {'on' if result['bytecode_cache'] else 'off'}")
    print(f"{'mark':40s} {'wall median':>12s} {'wall best':>10s} {'CPU median':>11s}")
    for label, row in result["marks"].items():
        print(f"{label:40s} {row['wall_median']:12.3f} {row['wall_best']:10.3f} {row['cpu_median']:11.3f}")


if __name__ == "__main__":
    main()
