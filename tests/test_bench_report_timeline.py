"""benchmarks/bench_report.py's compile log: its ``sitecustomize`` hook, run in a real process, records each Numba
compile and each wait on another process's compile mark (brdfnorm.engine.compiled.marks.AWAIT_EVENT) with their
wall and CPU times and the process's CPU in all, and ``_kernels`` reads them back into the per-process timeline."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import time

from helpers.paths import REPO, SRC


def _bench():
    spec = importlib.util.spec_from_file_location("bench_report", REPO / "benchmarks" / "bench_report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_hook_logs_compiles_and_waits_and_the_timeline_reads_them(tmp_path, capsys):
    bench = _bench()
    log = tmp_path / "log"
    log.mkdir()
    (log / "sitecustomize.py").write_text(bench._HOOK, encoding="utf-8")
    # the mark held by this (live) process: the child waits on it for its whole patience, 0.3 s
    mark = tmp_path / "lobe.compiling"
    mark.write_text(str(os.getpid()), encoding="ascii")
    code = ("from numba import njit\n"
            "from pathlib import Path\n"
            "from brdfnorm.engine.compiled import marks\n"
            "@njit\n"
            "def twice(x):\n"
            "    return 2 * x\n"
            "assert twice(2) == 4\n"
            f"assert marks.await_other(Path({str(mark)!r}), patience=0.3) >= 0.3\n")
    env = {**os.environ, "PYTHONPATH": f"{log}{os.pathsep}{SRC}", "BRDFNORM_BENCH_COMPILES": str(log)}
    started = time.time()
    subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True)
    rows = [line.split("\t") for path in log.glob("*.tsv") for line in path.read_text().splitlines()]
    kinds = [row[0] for row in rows]
    assert kinds.count("await") == 1 and kinds[-1] == "end"
    assert any(row[0] == "compile" and row[1].endswith("twice") and float(row[6]) > 0 for row in rows)
    bench._kernels(log, started)
    out = capsys.readouterr().out
    head = out.splitlines()[0]
    assert head.startswith("  command: ") and "s waiting on the other's marks" in head
    waited = float(head.split("CPU s of compile, ")[1].split(" s waiting")[0])
    assert 0.3 <= waited < 5.0
    assert "waits on lobe.compiling" in out and "CPU s in all" in head
