#!/usr/bin/env python
"""Time the anisotropic energy table of issue 45: GGX E over 32 μ × 32 α × 16 aspect, averaged over the view
azimuth, with E_avg over 32 α × 16 aspect (rtol 1e-5), on local processes; and the same smaller table on 1 and 2
local workers and on a 2-worker Dask cluster, compared bit for bit.

Usage: ``python benchmarks/bench_anisotropy.py [--size 32] [--workers 2] [--rtol 1e-5]`` or
``benchmarks/run.py --only anisotropy``; ``--quarter``: every fourth α only, in one process (CPU seconds and
evaluations); ``--profile``: that quarter by stage, μ band, α and aspect. Goal (this 2-core machine): the
32 × 32 × 16 table within 60 s. The wall
time and the CPU time (this process and its workers) are both reported: on a shared machine the wall time is what
the neighbours left.
"""

from __future__ import annotations

import argparse
import logging
import resource
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))

import brdfnorm as bn  # noqa: E402
from brdfnorm import lut  # noqa: E402
from brdfnorm.lut import anisotropy  # noqa: E402

GOAL_S = 60.0


def _axes(mu: int, alpha: int, aspect: int) -> dict[str, np.ndarray]:
    return {"mu": lut.grid_values(0.0, 1.0, mu, "texel"), "alpha": lut.grid_values(0.0, 1.0, alpha, "texel"),
            "aspect": np.linspace(np.sqrt(0.1), 1.0, aspect)}


def _cpu() -> float:
    """CPU seconds of this process. A pool's workers are stopped, not waited for, so RUSAGE_CHILDREN does not count
    them: runs on several workers report their CPU time as None, and ``--workers 1`` measures it."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    return own.ru_utime + own.ru_stime


def timed(axes, rtol, **spread):
    anisotropy.compute(bn.load("ggx"), {"mu": [0.5], "alpha": [0.5], "aspect": [0.5]}, anisotropy="aspect",
                       rtol=rtol)  # compile (or load the cached machine code) before the clock starts
    wall, cpu = time.perf_counter(), _cpu()
    table = anisotropy.compute(bn.load("ggx"), axes, anisotropy="aspect", rtol=rtol, **spread)
    in_process = spread.get("workers") == 1 and spread.get("scheduler") is None
    return table, time.perf_counter() - wall, (_cpu() - cpu) if in_process else None


def w_anisotropy(cfg, refs=None, size: int = 32, workers: int = 2, rtol: float = 1e-5) -> dict:
    """The workload as benchmarks/run.py reports it (``cfg.quick`` shrinks the tables)."""
    warnings.simplefilter("ignore")
    n = 4 if cfg.quick else size
    axes = _axes(n, n, max(2, n // 2))
    table, wall, cpu = timed(axes, rtol, workers=workers)
    cells = int(np.prod([len(v) for v in axes.values()]))
    cpu_text = "(workers: not measured here)" if cpu is None else f"{cpu:.1f} s"
    methods = {f"{n}×{n}×{max(2, n // 2)}, {workers} workers": {
        "time_s": wall, "cpu_s": cpu, "timing": "measured, once", "runs": 1, "points": cells,
        "warnings": int(table.meta["unconverged"]),
        "note": f"CPU {cpu_text}; max E error estimate {table['E_error'].max():.2g}, E_avg "
                f"{table['E_avg_error'].max():.2g}; {table.meta['evaluations']:.3g} evaluations; goal {GOAL_S:g} s"}}
    small = _axes(6, 4, 3) if not cfg.quick else _axes(3, 2, 2)
    runs = {name: timed(small, rtol, **kw) for name, kw in (("1 worker", {"workers": 1}),
                                                             ("2 local workers", {"workers": 2}))}
    try:
        from distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=":0", silence_logs=logging.CRITICAL) as cluster:
            runs["dask, 2 workers"] = timed(small, rtol, workers=None, scheduler=cluster.scheduler_address)
    except ImportError:
        pass
    base = runs["1 worker"][0]
    for name, (result, seconds, cpu_s) in runs.items():
        identical = all(np.array_equal(result[t], base[t]) for t in base)
        methods[f"small table, {name}"] = {"time_s": seconds, "cpu_s": cpu_s, "timing": "measured, once", "runs": 1,
                                           "points": int(base["E"].size), "bit_identical": identical,
                                           "note": f"bit-identical to 1 worker: {'yes' if identical else 'NO'}"}
    return {"title": f"anisotropic GGX table (μ, α, aspect), view-azimuth average, rtol {rtol:g}", "status": "ok",
            "reference": "error estimates of the compiled cubature (tests/lut/test_anisotropy.py checks them)",
            "methods": methods}


def profile(size: int, rtol: float) -> None:
    """The quarter table by stage, in this process: E cells and E_avg (evaluations, CPU seconds), the cells'
    evaluations per μ band and per aspect, E_avg's per α and per aspect (× 4 for the whole table)."""
    from brdfnorm.engine.routes import anisotropic as kernel

    axes = _axes(size, size, max(2, size // 2))
    mu, alpha, aspect = axes["mu"], axes["alpha"][::4], axes["aspect"]
    kernel.albedo("ggx", "height-correlated", [0.5], [0.5], [0.2], rtol=rtol)  # compile before the clock
    kernel.average_albedo("ggx", "height-correlated", [0.5], [0.3], rtol=rtol)
    a, s = np.meshgrid(alpha, aspect, indexing="ij")
    ax, ay = (np.broadcast_to(w[..., None], a.shape + (mu.size,)) for w in (a / s, a * s))
    cpu = _cpu()
    _, error, cells, _ = kernel.albedo("ggx", "height-correlated", np.broadcast_to(mu, ax.shape).ravel(), ax.ravel(),
                                       ay.ravel(), rtol=rtol)
    cells_cpu, cpu = _cpu() - cpu, _cpu()
    _, average_error, averages, _ = kernel.average_albedo("ggx", "height-correlated", (a / s).ravel(),
                                                          (a * s).ravel(), rtol=rtol)
    averages_cpu = _cpu() - cpu
    cells, averages = cells.reshape(ax.shape), averages.reshape(a.shape)
    print(f"quarter table ({alpha.size} α × {mu.size} μ × {aspect.size} aspect; × 4 for the whole), one process:")
    print(f"  E cells {cells.sum():.4g} evaluations, {cells_cpu:.1f} s CPU (max estimate {error.max():.2g}); "
          f"E_avg {averages.sum():.4g}, {averages_cpu:.1f} s CPU (max estimate {average_error.max():.2g})")
    bands = np.array_split(np.arange(mu.size), 8)
    print("  cells by μ band: " + ", ".join(f"{mu[b[0]]:.3g}–{mu[b[-1]]:.3g} {cells[..., b].sum():.3g}"
                                          for b in bands))
    print("  cells by aspect: " + ", ".join(f"{v:.3g} {n:.3g}" for v, n in zip(aspect, cells.sum(axis=(0, 2)),
                                                                                strict=True)))
    print("  E_avg by α: " + ", ".join(f"{v:.3g} {n:.3g}" for v, n in zip(alpha, averages.sum(axis=1), strict=True)))
    print("  E_avg by aspect: " + ", ".join(f"{v:.3g} {n:.3g}" for v, n in zip(aspect, averages.sum(axis=0),
                                                                              strict=True)))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=32)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rtol", type=float, default=1e-5)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--quarter", action="store_true",
                        help="only every fourth α of the table, in this process (CPU seconds and evaluations: the "
                             "before/after measure of a kernel change)")
    parser.add_argument("--profile", action="store_true",
                        help="the quarter table by stage (E cells, E_avg), μ band, α and aspect, in this process")
    args = parser.parse_args(argv)
    if args.profile:
        profile(args.size, args.rtol)
        return 0
    if args.quarter:
        axes = _axes(args.size, args.size, max(2, args.size // 2))
        axes["alpha"] = axes["alpha"][::4]
        table, wall, cpu = timed(axes, args.rtol, workers=1)
        print(f"quarter table {args.size}×{args.size}×{max(2, args.size // 2)} (every fourth α), 1 process: "
              f"{wall:.1f} s wall, {cpu:.1f} s CPU, {table.meta['evaluations']:.4g} evaluations, "
              f"max E error estimate {table['E_error'].max():.2g}, {table.meta['unconverged']} unconverged")
        return 0

    class _Config:
        quick = args.quick

    result = w_anisotropy(_Config(), size=args.size, workers=args.workers, rtol=args.rtol)
    print(result["title"])
    for method, line in result["methods"].items():
        cpu = "-" if line["cpu_s"] is None else f"{line['cpu_s']:.2f}"
        print(f"{method:34s} {line['time_s']:8.2f} s wall  {cpu:>8s} s CPU  {line['note']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
