"""The generic engine's interactive case (issue #13): a 90-angle albedo curve of examples/ggx.brdf at rtol 1e-6,
what a live plot redraws while a slider moves. Goal: ≤ 100 ms.

Times are the best of ``cfg.repeats`` calls (the first, which warms caches, is not timed); the machine's load
average is recorded with them, since on a shared machine they scale with it. The reference is brdfnorm's own
quadrature at rtol 1e-11 (cross-checked against dblquad in the ``ggx-table`` workload); the line reports the
largest relative error and whether every error estimate covers the true error.
Run alone: ``.venv/bin/python benchmarks/bench_engine.py [--quick]``.
"""

from __future__ import annotations

import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import brdfnorm as bn

ROOT = Path(__file__).resolve().parents[1]
RTOL = 1e-6
GOAL_S = 0.1


def w_engine(cfg, refs=None) -> dict:
    """The workload as benchmarks/run.py reports it (``cfg.table_angles`` are the curve's angles)."""
    model = bn.load(str(ROOT / "examples" / "ggx.brdf"))
    theta = np.radians(cfg.table_angles)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bn.albedo(model, theta, rtol=RTOL)
        times = []
        for _ in range(max(cfg.repeats, 1)):
            start = time.perf_counter()
            result = bn.albedo(model, theta, rtol=RTOL)
            times.append(time.perf_counter() - start)
        reference = bn.albedo(model, theta, rtol=1e-11, method="quadrature").value[:, 0]
    value, error = result.value[:, 0], result.error[:, 0]
    true_error = np.abs(value - reference)
    best = min(times)
    return {
        "title": f"examples/ggx.brdf albedo curve: {theta.size} angles, rtol {RTOL:g} (goal ≤ {GOAL_S * 1e3:g} ms)",
        "status": "ok", "time_s": best, "runs": len(times), "load_average": os.getloadavg()[0],
        "method": result.method, "evaluations_per_albedo": float(result.evaluations.mean()),
        "max_rel_error": float((true_error / reference).max()),
        "estimates_cover_errors": bool(np.all(error >= true_error)),
        "converged": bool(result.converged.all()),
    }


if __name__ == "__main__":
    from types import SimpleNamespace

    quick = "--quick" in sys.argv[1:]
    angles = np.array([0.0, 30.0, 60.0, 89.0]) if quick else np.arange(90.0)
    print(w_engine(SimpleNamespace(table_angles=angles, repeats=2 if quick else 5)))
