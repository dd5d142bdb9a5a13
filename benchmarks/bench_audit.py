#!/usr/bin/env python
"""Time ``brdfnorm audit`` (issue 29) on the issue's workloads: a 64×64 E table (inference + dense interpolation
error + resolution sweep; goal ≤ 10 s on the 2-core machine), a 32³ uint16 E(f0) table (goal ≤ 60 s), and a 16×16
half-float split-sum table. The tables are made by ``brdfnorm.lut`` first (not timed); each audit must name the
convention it was made in, or the script says so and exits 1.

Usage: ``python benchmarks/bench_audit.py [--out FILE.md]``.
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
from brdfnorm.audit import audit  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    ggx = bn.load("ggx")
    rows, ok = [], True

    t = (np.arange(64) + 0.5) / 64
    e64 = lut.compute(ggx, {"mu": t, "alpha": t * t}, rtol=1e-9, average=False)["E"].astype(np.float32)
    wall = time.perf_counter()
    r = audit(e64, "ggx", read={"dtype": "float32"})
    seconds = time.perf_counter() - wall
    named = r.fits and (r.best.convention.direction, r.best.convention.roughness) == ("mu-texel", "r2-texel")
    ok &= named
    rows.append(("64×64 float32 E (mu-texel, r2-texel)", seconds, 10.0, named, r.best.channels[0].max,
                 r.interpolation["0"]["max"]))

    t = (np.arange(32) + 0.5) / 32
    dfg = lut.compute(ggx, {"alpha": t, "mu": t}, channels=["dfg"], rtol=1e-7, average=False)
    e32 = np.rint((t[:, None, None] * dfg["DFG_f0"][None] + dfg["DFG_f90"][None]) * 65535) / 65535
    wall = time.perf_counter()
    r = audit(e32, "ggx", read={"dtype": "uint16"})
    seconds = time.perf_counter() - wall
    named = r.fits and r.best.convention.meanings == ("E_f0",)
    ok &= named
    rows.append(("32³ uint16 E(f0, α, μ)", seconds, 60.0, named, r.best.channels[0].max,
                 r.interpolation["0"]["max"]))

    t = (np.arange(16) + 0.5) / 16
    dfg = lut.compute(ggx, {"alpha": t * t, "mu": t}, channels=["dfg"], rtol=1e-8, average=False)
    half = np.stack([dfg["DFG_f0"], dfg["DFG_f90"]], -1).astype(np.float16).astype(float)
    wall = time.perf_counter()
    r = audit(half, "ggx", read={"dtype": "float16"})
    seconds = time.perf_counter() - wall
    named = r.fits and r.best.convention.meanings == ("DFG_f0", "DFG_f90")
    ok &= named
    rows.append(("16×16 half split-sum (DFG_f0, DFG_f90)", seconds, None, named,
                 max(c.max for c in r.best.channels), max(v["max"] for v in r.interpolation.values())))

    lines = ["| audit | seconds | goal | convention named | max residual | GPU interpolation max error |",
             "|---|---|---|---|---|---|"]
    for name, seconds, goal, named, residual, interp in rows:
        goal_text = f"≤ {goal:g} s" if goal else "—"
        lines.append(f"| {name} | {seconds:.2f} | {goal_text} | {named} | {residual:.3g} "
                     f"| {interp:.3g} |")
    text = "\n".join(lines)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
