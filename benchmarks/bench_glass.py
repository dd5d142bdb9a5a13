#!/usr/bin/env python
"""Time the rough-glass table of issue 18: ggx-dielectric E, E_R, E_T over N μ × N α × N η (η and 1/η, from F0)
at rtol 1e-9, and its E_avg, against the μ-average of albedos (the generic E_avg route) measured in the same run.

Usage: ``python benchmarks/bench_glass.py [--size 16] [--workers N] [--peer 2] [--out FILE.md]``. The cells run as
``brdfnorm lut`` runs them (a local process pool, all cores by default), and so does E_avg, the 3-D route of
:mod:`brdfnorm.engine.routes.dielectric_average` over every (α, η). The peer computes E_avg for ``--peer``
(α, η) combinations from each side by :func:`brdfnorm.lut.table.average_over_mu` and is extrapolated to all of
them (labelled so); the two agree within their estimates or the script says otherwise. Goal (this 2-core machine):
the whole 16³ table within 60 s.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))

import brdfnorm as bn  # noqa: E402
from brdfnorm import lut  # noqa: E402
from brdfnorm.lut import glass  # noqa: E402
from brdfnorm.lut.table import average_over_mu  # noqa: E402


def _axes(n: int) -> dict[str, np.ndarray]:
    f0 = np.linspace(0.02, 0.2, n // 2)
    outside = (1 + np.sqrt(f0)) / (1 - np.sqrt(f0))
    return {"mu": lut.grid_values(0.0, 1.0, n, "texel"), "alpha": lut.grid_values(0.0, 1.0, n, "texel"),
            "eta": np.concatenate([1 / outside[::-1], outside])}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=16)
    parser.add_argument("--workers", type=int, default=None, help="local processes for the cells (default: all)")
    parser.add_argument("--peer", type=int, default=2, help="(α, η) combinations per side for the peer")
    parser.add_argument("--rtol", type=float, default=1e-9)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    model, axes = bn.load("ggx-dielectric"), _axes(args.size)
    warnings.simplefilter("ignore")

    wall = time.perf_counter()
    cells = lut.compute(model, axes, rtol=args.rtol, average=False, workers=args.workers)
    cells_s = time.perf_counter() - wall
    alpha, eta = (g.ravel() for g in np.meshgrid(axes["alpha"], axes["eta"], indexing="ij"))
    wall = time.perf_counter()
    ours = glass.average(model, {"alpha": alpha, "eta": eta}, rtol=args.rtol, spread={"workers": args.workers})
    average_s = time.perf_counter() - wall

    rng = np.random.default_rng(0)
    picks = np.concatenate([rng.choice(np.flatnonzero(side), args.peer, replace=False)
                            for side in (eta > 1, eta < 1)])
    wall = time.perf_counter()
    peer = average_over_mu(model, {"alpha": alpha[picks], "eta": eta[picks]}, rtol=args.rtol)
    peer_s = (time.perf_counter() - wall) / picks.size * alpha.size
    difference = np.abs(ours[0][picks] - peer[0])
    honest = difference <= ours[1][picks] + peer[1]

    n = args.size
    shape = f"{n} μ × {n} α × {len(axes['eta'])} η"
    lines = [
        f"# Rough glass table ({shape}, rtol {args.rtol:g})", "",
        "| part | time | timing | note |", "|---|---|---|---|",
        f"| E, E_R, E_T cells | {cells_s:.1f} s | measured | {cells['E'].size} cells, "
        f"{int(np.sum(cells['E_error'] > args.rtol * cells['E']))} above rtol·E, "
        f"max E_error {np.max(cells['E_error']):.2g}, local processes |",
        f"| E_avg, 3-D route | {average_s:.1f} s | measured | {alpha.size} (α, η), local processes, "
        f"{int(np.sum(~ours[2]))} unconverged, max error {np.max(ours[1]):.2g}, {ours[3]} albedos (fallback) |",
        f"| **whole table** | **{cells_s + average_s:.1f} s** | measured | goal ≤ 60 s |",
        f"| E_avg, μ-average of albedos (peer) | {peer_s:.0f} s | extrapolated from {picks.size} (α, η) | "
        f"agrees within both estimates on {int(honest.sum())}/{picks.size}, max difference "
        f"{np.max(difference):.2g} |",
    ]
    text = "\n".join(lines)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")
    return 0 if honest.all() else 1


if __name__ == "__main__":
    raise SystemExit(main())
