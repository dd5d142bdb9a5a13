#!/usr/bin/env python
"""Time ``brdfnorm fit --lut`` with ``--form auto`` (the default) on N × N GGX E(μ, α) tables (issue 12 item 5).

Usage: ``python benchmarks/bench_fit_lut.py [--sizes 16 32] [--slow]``. For each size it builds the table as the
README does (``brdfnorm lut ggx --axis mu=0:1:N --axis alpha=0.02:1:N --clamp mu=1e-4``), runs
:func:`brdfnorm.lut.fitting.fit_table` and prints a markdown table to stdout: CPU and wall seconds, candidates
fitted and pruned (proved unable to enter the Pareto front), the front and the chosen fit. ``--slow`` also runs
it with ``prune=False`` (every candidate fitted, minutes) and says whether the fronts agree. Goals (this 2-core
machine): 16 × 16 ≤ 15 s CPU, 32 × 32 ≤ 60 s.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))

import brdfnorm as bn  # noqa: E402
from brdfnorm import lut  # noqa: E402
from brdfnorm.lut.fitting import fit_table  # noqa: E402


def _table(n: int) -> lut.Lut:
    mu = np.linspace(0.0, 1.0, n)
    mu[0] = 1e-4
    axes = {"mu": mu, "alpha": np.linspace(0.02, 1.0, n)}
    return lut.Lut({"E": lut.compute(bn.load("ggx"), axes, rtol=1e-10, average=False)["E"]}, axes, {"model": "ggx"})


def _timed(table: lut.Lut, prune: bool):
    cpu, wall = time.process_time(), time.perf_counter()
    result = fit_table(table, prune=prune)
    return result, time.process_time() - cpu, time.perf_counter() - wall


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[16, 32])
    parser.add_argument("--slow", action="store_true", help="also fit every candidate (prune=False) and compare")
    args = parser.parse_args(argv)
    lines = ["| table | pruning | CPU s | wall s | fitted | pruned | front (coefficients: form) | chosen |",
             "|---|---|---|---|---|---|---|---|"]
    for n in args.sizes:
        table = _table(n)
        for prune in (True, False) if args.slow else (True,):
            result, cpu, wall = _timed(table, prune)
            pruned = sum(bool(e["skipped"]) for e in result.tried)
            front = ", ".join(f"{e['coefficients']}: {e['form']} {e['max_abs_error']:.3g}" for e in result.front)
            lines.append(f"| {n} × {n} | {'on' if prune else 'off'} | {cpu:.1f} | {wall:.1f} | "
                         f"{len(result.tried) - pruned} | {pruned} | {front} | {result.best.form} |")
            print(lines[-1], file=sys.stderr, flush=True)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
