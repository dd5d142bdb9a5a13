"""The native backend of ``.brdf`` shaders (issue 39): nanoseconds per evaluation of examples/ggx.brdf compiled to
one scalar Numba function (:mod:`brdfnorm.glsl.native`), against the numpy backend's closures on the same random
direction pairs, and what compiling costs cold (empty disk cache) and warm (a second process).

* per evaluation: the compiled function called by an ``njit`` loop over the pairs (the way the compiled engine
  calls it), best of ``cfg.repeats``; the numpy backend evaluating the same pairs as one batch
  (``BrdfModel.evaluate``), best of the same. Their largest relative difference is reported with them.
* compile: fresh interpreters, each timing ``load_brdf(...).native_kernel()`` after the imports; the first on
  an empty ``BRDFNORM_CACHE_DIR`` (trace, write, Numba compiles and caches), the second on the same directory
  (trace, Numba reads its cache). The import of brdfnorm and Numba is timed apart.
* ``brdfnorm albedo examples/ggx.brdf``: wall time of the command, first and second run on a fresh cache.

Run alone: ``.venv/bin/python benchmarks/bench_glsl_native.py [--quick]``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHADER = ROOT / "examples" / "ggx.brdf"

_COLD_SCRIPT = """
import json, sys, time
start = time.perf_counter()
import numba
from brdfnorm.brdffile import load_brdf
imported = time.perf_counter()
model = load_brdf(sys.argv[1])
loaded = time.perf_counter()
kernel = model.native_kernel()
ready = time.perf_counter()
print(json.dumps({"import_s": imported - start, "load_s": loaded - imported, "kernel_s": ready - loaded,
                  "cache_hits": sum(kernel.function.stats.cache_hits.values()),
                  "cache_misses": sum(kernel.function.stats.cache_misses.values())}))
"""


def _environment(cache: str) -> dict:
    path = str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", "")
    return {**os.environ, "BRDFNORM_CACHE_DIR": cache, "PYTHONPATH": path}


def _directions(count: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    out = []
    for _ in range(2):
        d = rng.normal(size=(count, 3))
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        d[:, 2] = np.abs(d[:, 2])
        out.append(d)
    return out[0], out[1]


def per_evaluation(count: int, repeats: int) -> dict:
    """ns per evaluation: compiled function in an njit loop, and the numpy closures on one batch."""
    import numba

    from brdfnorm.brdffile import load_brdf

    @numba.njit(nogil=True)
    def sweep(f, L, V, u, out):
        for i in range(L.shape[0]):
            r, g, b = f(L[i, 0], L[i, 1], L[i, 2], V[i, 0], V[i, 1], V[i, 2], u)
            out[i, 0] = r
            out[i, 1] = g
            out[i, 2] = b

    model = load_brdf(SHADER)
    kernel = model.native_kernel()
    L, V = _directions(count)
    u = kernel.pack(model.params)
    native = np.empty((count, 3))
    sweep(kernel.function, L[:2], V[:2], u, native[:2])  # compile the loop itself before timing
    native_times, numpy_times = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        sweep(kernel.function, L, V, u, native)
        native_times.append(time.perf_counter() - start)
        start = time.perf_counter()
        reference = model.evaluate(L, V, model.params)
        numpy_times.append(time.perf_counter() - start)
    finite = np.isfinite(reference) & (reference != 0)
    difference = np.abs(native[finite] - reference[finite]) / np.abs(reference[finite])
    return {
        "pairs": count, "runs": repeats,
        "native_ns": min(native_times) / count * 1e9, "numpy_ns": min(numpy_times) / count * 1e9,
        "speedup": min(numpy_times) / min(native_times),
        "max_rel_difference": float(difference.max(initial=0.0)),
        "same_nan": bool(np.array_equal(np.isnan(native), np.isnan(reference))),
    }


def compile_times(cache: str) -> list[dict]:
    """Two fresh interpreters on one (initially empty) cache directory: cold, then warm."""
    runs = []
    for _ in range(2):
        done = subprocess.run([sys.executable, "-c", _COLD_SCRIPT, str(SHADER)], env=_environment(cache),
                              capture_output=True, text=True, check=True)
        runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
    return runs


def albedo_command(cache: str) -> list[float]:
    """Wall seconds of ``brdfnorm albedo examples/ggx.brdf``, first and second run on one cache directory."""
    times = []
    for _ in range(2):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "brdfnorm", "albedo", str(SHADER)], env=_environment(cache),
                       capture_output=True, check=True)
        times.append(time.perf_counter() - start)
    return times


def w_glsl_native(cfg, refs=None) -> dict:
    """The workload as benchmarks/run.py reports it (``cfg.eval_pairs`` pairs, ``cfg.repeats`` runs)."""
    evaluation = per_evaluation(int(cfg.eval_pairs), max(int(cfg.repeats), 1))
    with tempfile.TemporaryDirectory(prefix="brdfnorm-bench-cache-") as cache:
        cold, warm = compile_times(cache)
    with tempfile.TemporaryDirectory(prefix="brdfnorm-bench-cache-") as cache:
        first, second = albedo_command(cache)
    return {
        "title": f"examples/ggx.brdf compiled by the native backend: ns per evaluation "
                 f"({evaluation['pairs']:.0e} pairs), compile cold/warm",
        "status": "ok", "load_average": os.getloadavg()[0], "evaluation": evaluation,
        "compile_cold": cold, "compile_warm": warm,
        "albedo_command_s": {"first": first, "second": second},
    }


def report(result: dict) -> str:
    e, cold, warm = result["evaluation"], result["compile_cold"], result["compile_warm"]
    return "\n".join([
        result["title"],
        f"  native {e['native_ns']:.1f} ns/eval, numpy closures {e['numpy_ns']:.1f} ns/eval: "
        f"{e['speedup']:.1f}x (max rel difference {e['max_rel_difference']:.1e}, same NaN: {e['same_nan']})",
        f"  kernel cold {cold['kernel_s']:.2f} s (cache misses {cold['cache_misses']}), "
        f"warm {warm['kernel_s']:.3f} s (cache hits {warm['cache_hits']}, misses {warm['cache_misses']}); "
        f"imports {cold['import_s']:.2f} s",
        f"  brdfnorm albedo examples/ggx.brdf: first {result['albedo_command_s']['first']:.2f} s, "
        f"second {result['albedo_command_s']['second']:.2f} s",
    ])


if __name__ == "__main__":
    from types import SimpleNamespace

    quick = "--quick" in sys.argv[1:]
    print(report(w_glsl_native(SimpleNamespace(eval_pairs=10_000 if quick else 1_000_000,
                                               repeats=2 if quick else 5))))
