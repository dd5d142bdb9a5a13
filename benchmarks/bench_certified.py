"""Certified energy table (issue 33): a 32×32 GGX table E(μ, α), μ from 1e-4 to 1 and α from 1e-8 to 1 (node grid,
clamped), height-correlated, F = 1, every cell an Arb enclosure with relative radius ≤ 10^−12. Goal: ≤ 600 s on
the 2-core machine, and every float64 value of the ``method="auto"`` table (rtol 1e-10) inside its cell's
enclosure widened by its error estimate.

One run, timed with ``time.perf_counter`` (wall) and ``time.process_time`` (CPU, this process: the cells are
computed in it, one after another); the load average is recorded, since the machine is shared. E_avg is not part of
it (it has no certified route yet, see brdfnorm.lut.certified).
Run alone: ``.venv/bin/python benchmarks/bench_certified.py [--quick]`` (quick: 8×8).
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

import brdfnorm as bn
from brdfnorm.lut import certified

GOAL_S = 600.0
DIGITS = 12


def w_certified(cfg=None, refs=None, size: int | None = None) -> dict:
    """The workload as benchmarks/run.py reports it (``size`` defaults to 8 with ``cfg.quick``, else 32)."""
    size = size or (8 if getattr(cfg, "quick", False) else 32)
    axes = {"mu": np.linspace(0.0, 1.0, size), "alpha": np.linspace(0.0, 1.0, size)}
    clamp = {"mu": 1e-4, "alpha": 1e-8}
    model = bn.load("ggx", shadowing="height-correlated")
    start, cpu = time.perf_counter(), time.process_time()
    table = certified.compute(model, axes, clamp=clamp, digits=DIGITS, average=False)
    seconds, cpu_seconds = time.perf_counter() - start, time.process_time() - cpu
    auto = bn.lut.compute(model, axes, clamp=clamp, rtol=1e-10, average=False)
    inside = (table["E_lower"] - auto["E_error"] <= auto["E"]) & (auto["E"] <= table["E_upper"] + auto["E_error"])
    # Digits achieved: the reported decimal interval's relative radius, cell by cell.
    lower = np.array(table.meta["certified"]["E"]["lower"], dtype=float)
    upper = np.array(table.meta["certified"]["E"]["upper"], dtype=float)
    relative = (upper - lower) / 2 / np.minimum(np.abs(lower), np.abs(upper))
    return {
        "title": f"certified {size}×{size} ggx E table, {DIGITS} digits (goal ≤ {GOAL_S:g} s)",
        "status": "ok", "time_s": seconds, "cpu_s": cpu_seconds, "load_average": os.getloadavg()[0],
        "unconverged": table.meta["unconverged"], "evaluations": table.meta["evaluations"],
        "working_bits_max": table.meta["certified"]["working_bits_max"],
        "max_relative_radius": float(relative.max()), "auto_inside_widened_enclosures": int(inside.sum()),
        "cells": int(inside.size), "met": bool(seconds <= GOAL_S and table.meta["unconverged"] == 0
                                               and inside.all()),
    }


if __name__ == "__main__":
    quick = "--quick" in sys.argv[1:]
    print(w_certified(size=8 if quick else 32))
