#!/usr/bin/env python
"""Time ``brdfnorm audit`` (issues 29 and 42) on the issues' workloads: a 64×64 E table (inference + dense
interpolation error + resolution sweep; goal ≤ 3 s with the compiled engine), a 32×32 float32 split-sum C header
with local defects (a 3×3 block 4 % too bright, one cell's channels swapped; goal ≤ 5 s, and every damaged cell
must be listed), 32³ uint16 E(f0) tables (goal ≤ 60 s) with Schlick's factor and with the exact dielectric one,
and 16×16 and 64×64 half-float split-sum tables (the latter goal ≤ 10 s); issue 41's legal large inputs (goal
≤ 10 s: 64² and 1024² tables no convention fits, a raw 8×8×1000 grid, and with ``BRDFNORM_BENCH_E1024=1`` a 1024²
E table with a defect). The tables are made by ``brdfnorm.lut`` (or the audit's exact reference) first, untimed;
each audit must reach the verdict its table was made for (the convention it was made in, every damaged cell
listed, or no convention for the tables made to fit none), or the script says so and exits 1. Wall and CPU
seconds of this process are both reported (the development machine is shared: CPU time is what the goals mean).

Usage: ``python benchmarks/bench_audit.py [--out FILE.md]``; ``benchmarks/run.py`` runs it as the ``audit``
workload (``--only audit``) and puts the two goals in its targets table.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))

import brdfnorm as bn  # noqa: E402
from brdfnorm import lut  # noqa: E402
from brdfnorm.audit import audit  # noqa: E402
from brdfnorm.audit.reference import Reference  # noqa: E402


def w_audit(cfg=None, refs=None) -> dict:
    """The workload as benchmarks/run.py reports it: one entry per audited table (seconds, CPU seconds, goal,
    named, errors)."""
    ggx = bn.load("ggx")
    cases = {}

    t = (np.arange(64) + 0.5) / 64
    e64 = lut.compute(ggx, {"mu": t, "alpha": t * t}, rtol=1e-9, average=False)["E"].astype(np.float32)
    r, seconds, cpu = _timed(lambda: audit(e64, "ggx", read={"dtype": "float32"}))
    cases["64x64"] = _case("64×64 float32 E (mu-texel, r2-texel), inference + interpolation + sweep",
                           seconds, 3.0,
                           r.fits and (r.best.convention.direction, r.best.convention.roughness) == ("mu-texel",
                                                                                                   "r2-texel"), r, cpu)
    cases.update(_large())

    cases["32x32-dfg-defects"] = _defects(ggx)

    t = (np.arange(32) + 0.5) / 32
    dfg = lut.compute(ggx, {"alpha": t, "mu": t}, channels=["dfg"], rtol=1e-7, average=False)
    e32 = np.rint((t[:, None, None] * dfg["DFG_f0"][None] + dfg["DFG_f90"][None]) * 65535) / 65535
    r, seconds, cpu = _timed(lambda: audit(e32, "ggx", read={"dtype": "uint16"}))
    cases["32x32x32"] = _case("32³ uint16 E(f0, α, μ), inference + interpolation + sweep",
                              seconds, 60.0, r.fits and r.best.convention.meanings == ("E_f0",), r, cpu)

    t = (np.arange(16) + 0.5) / 16
    dfg = lut.compute(ggx, {"alpha": t * t, "mu": t}, channels=["dfg"], rtol=1e-8, average=False)
    half = np.stack([dfg["DFG_f0"], dfg["DFG_f90"]], -1).astype(np.float16).astype(float)
    r, seconds, cpu = _timed(lambda: audit(half, "ggx", read={"dtype": "float16"}))
    cases["16x16-dfg"] = _case("16×16 half split-sum (DFG_f0, DFG_f90), inference + interpolation + sweep",
                               seconds, None, r.fits and r.best.convention.meanings == ("DFG_f0", "DFG_f90"), r, cpu)

    t = (np.arange(64) + 0.5) / 64
    dfg = lut.compute(ggx, {"alpha": t * t, "mu": t}, channels=["dfg"], rtol=1e-7, average=False)
    half = np.stack([dfg["DFG_f0"], dfg["DFG_f90"]], -1).astype(np.float16).astype(float)
    r, seconds, cpu = _timed(lambda: audit(half, "ggx", read={"dtype": "float16"}))
    cases["64x64-dfg"] = _case("64×64 half split-sum (DFG_f0, DFG_f90), inference + interpolation + sweep",
                               seconds, 10.0, r.fits and r.best.convention.meanings == ("DFG_f0", "DFG_f90"), r, cpu)
    cases["64x64-dfg"]["f90_cells"] = r.inference.reference_cells.get("F90", 0)
    # the exact dielectric Fresnel over an f0 axis: reached only after Schlick's E_f0 fits nothing, and every
    # cell of the best convention is a quadrature
    t = np.linspace(0.0, 1.0, 32)
    f0, alpha, mu = np.meshgrid(t, np.maximum(t, 1e-8), (np.arange(32) + 0.5) / 32, indexing="ij")
    exact, _ = Reference(ggx).meaning("E_f0_dielectric", "height-correlated", mu, alpha, f0)
    codes = np.rint(exact * 65535) / 65535
    r, seconds, cpu = _timed(lambda: audit(codes, "ggx", read={"dtype": "uint16"}))
    cases["32x32x32-dielectric"] = _case("32³ uint16 E(f0, α, μ) with the exact dielectric Fresnel, inference + "
                                         "interpolation + sweep", seconds, 60.0,
                                         r.fits and r.best.convention.meanings == ("E_f0_dielectric",), r, cpu)
    if os.environ.get("BRDFNORM_BENCH_GLASS33", "1") != "0":  # ~6 min of one core on the 2-core machine
        cases["33x33x33-glass"] = _glass33()
    named = all(c["named"] for c in cases.values())
    return {"title": "brdfnorm audit of tables made in known conventions (issue 29)",
            "status": "ok" if named else "a convention was not named", "cases": cases,
            "load_average": os.getloadavg()[0]}


def _defects(ggx) -> dict:
    """Issue 42's case: a 32×32 float2 split-sum C header of brdfnorm's own lut output (α = r², texel centres),
    a 3×3 block 4 % too bright and one cell's two channels swapped, audited from the file (reading included)."""
    import tempfile

    t = (np.arange(32) + 0.5) / 32
    dfg = lut.compute(ggx, {"alpha": t * t, "mu": t}, channels=["dfg"], rtol=1e-8, average=False)
    table = np.stack([dfg["DFG_f0"], dfg["DFG_f90"]], -1).astype(np.float32)
    table[10:13, 20:23, 0] *= np.float32(1.04)
    table[5, 7] = table[5, 7, ::-1].copy()
    damaged = {(i, j, 0) for i in range(10, 13) for j in range(20, 23)} | {(5, 7, 0), (5, 7, 1)}
    body = ",\n".join(f"  float2({a:.9g}f, {b:.9g}f)" for a, b in table.reshape(-1, 2))
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / "dfg.h"
        path.write_text(f"static const float2 g_dfg[32 * 32] = {{\n{body}\n}};\n")
        r, seconds, cpu = _timed(lambda: audit(str(path), "ggx", read={"shape": (32, 32, 2)}))
    listed = {tuple(c["index"]) + (int(k),) for k, v in r.wrong_cells.items() for c in v["cells"]}
    named = (r.fits and not r.passes and r.best.convention.meanings == ("DFG_f0", "DFG_f90")
             and (r.best.convention.direction, r.best.convention.roughness) == ("mu-texel", "r2-texel")
             and listed == damaged)
    case = _case("32×32 float32 split-sum C header with a 4 % block and a swapped cell, every bad cell listed, "
                 "inference + interpolation + sweep", seconds, 5.0, named, r, cpu)
    case["f90_cells"] = r.inference.reference_cells.get("F90", 0)
    return case


def _glass33() -> dict:
    """Issue 42's 33³ η table: R + T of GGX glass over (η, roughness, μ) in Cycles' layout (η from F0 = t⁴, nodes),
    Cycles' refraction shadowing, float32, a 3×3×3 block 3 % too bright; the other axes pinned (as docs/audit.md
    says a glass table is audited), the refraction's shadowing and the η layout searched. The table is made with
    every core, untimed."""
    n = 33
    t = np.linspace(0.0, 1.0, n)
    f0 = np.clip(t, 1e-4, 0.99) ** 4
    eta = np.maximum((1 + np.sqrt(f0)) / (1 - np.sqrt(f0)), 1 + 2e-6)
    glass = bn.load("ggx-dielectric", refraction_shadowing="reflection-form")
    table = lut.compute(glass, {"eta": eta, "alpha": np.maximum(t * t, 1e-8), "mu": np.maximum(t, 1e-4)},
                        rtol=1e-7, average=False, workers=None)["E"].astype(np.float32)
    table[20:23, 10:13, 5:8] *= np.float32(1.03)
    damaged = {(i, j, k) for i in range(20, 23) for j in range(10, 13) for k in range(5, 8)}
    r, seconds, cpu = _timed(lambda: audit(
        table.astype(float), bn.load("ggx-dielectric"), read={"dtype": "float32"}, sweep=False,
        pins={"axes": "eta,alpha,mu", "direction": "mu-node", "roughness": "r2-node", "mu_floor": "1e-4",
              "alpha_floor": "1e-8"}))
    c = r.best.convention
    listed = {tuple(x["index"]) for v in r.wrong_cells.values() for x in v["cells"]}
    named = (r.fits and c.f0 == "eta-cycles" and c.shadowing == "height-correlated/refraction=reflection-form"
             and listed == damaged)
    case = _case("33³ float32 GGX glass R + T over (η, α, μ) with a 3 % block, axes pinned, inference + "
                 "interpolation", seconds, 60.0, named, r, cpu)
    case["f90_cells"] = r.inference.reference_cells.get("E_glass", 0)
    return case


def _large() -> dict:
    """Issue 41's legal large inputs, whose inference is bounded by a fixed subgrid (goal: a verdict within 10 s):
    64² and 1024² E tables that fit no convention (0.5 + 0.1 μ), a raw 8×8×1000 float32 file of 0.5 read as three
    axes (from the file, reading included), and (``BRDFNORM_BENCH_E1024=1``: the table costs ~30 s of CPU to make)
    a 1024² float32 E table in brdfnorm's convention with a 3×3 block 1 % too bright, every damaged cell listed."""
    import tempfile

    cases = {}
    for n in (64, 1024):
        mu = (np.arange(n) + 0.5) / n
        table = np.tile(0.5 + 0.1 * mu[:, None], (1, n))
        r, seconds, cpu = _timed(lambda table=table: audit(table, "ggx"))
        cases[f"{n}x{n}-nofit"] = _case(f"{n}×{n} float64 table no convention fits (exit 1), inference + "
                                        "interpolation + sweep", seconds, 10.0, not r.fits and not r.passes, r, cpu)
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / "t.bin"
        path.write_bytes(np.full(8 * 8 * 1000, 0.5, dtype=np.float32).tobytes())
        r, seconds, cpu = _timed(lambda: audit(str(path), "ggx", read={"shape": (8, 8, 1000), "dtype": "float32"}))
    cases["8x8x1000-raw"] = _case("raw 8×8×1000 float32 as a 3-D grid, no convention fits (exit 1), reading + "
                                  "inference + interpolation + sweep", seconds, 10.0, not r.fits, r, cpu)
    if os.environ.get("BRDFNORM_BENCH_E1024", "0") != "0":
        t = (np.arange(1024) + 0.5) / 1024
        exact = lut.compute(bn.load("ggx"), {"mu": t, "alpha": t * t}, rtol=1e-9, average=False)["E"]
        table = exact.astype(np.float32).astype(float)
        table[500:503, 200:203] *= 1.01
        r, seconds, cpu = _timed(lambda: audit(table, "ggx", read={"dtype": "float32"}))
        listed = {tuple(x["index"]) for v in r.wrong_cells.values() for x in v["cells"]}
        cases["1024x1024"] = _case("1024×1024 float32 E with a 1 % 3×3 block, every bad cell listed, inference + "
                                   "interpolation + sweep", seconds, 10.0, r.fits and listed == {
                                       (i, j) for i in range(500, 503) for j in range(200, 203)}, r, cpu)
    return cases


def _timed(run):
    """(result, wall seconds, CPU seconds of this process) of ``run()``."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = run()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def _case(title: str, seconds: float, goal: float | None, named: bool, r, cpu: float | None = None) -> dict:
    return {"title": title, "seconds": seconds, "goal_s": goal, "named": bool(named), "cpu_seconds": cpu,
            "max_residual": max(c.max for c in r.best.channels),
            "interpolation_max": max((v["max"] for v in r.interpolation.values()), default=float("nan")),
            "reference_cells": sum(r.inference.reference_cells.values())}


def audit_targets(results: dict) -> list[dict]:
    """The issue's speed goals, for benchmarks/run.py's targets table."""
    out = []
    for case in results.get("audit", {}).get("cases", {}).values():
        if case["goal_s"] is not None:
            out.append({"target": f"audit of a {case['title']} ≤ {case['goal_s']:g} s",
                        "measured": f"{case['seconds']:.3g} s ({case['cpu_seconds']:.3g} s CPU); verdict as made: "
                                    f"{case['named']}",
                        "met": bool(case["seconds"] <= case["goal_s"] and case["named"])})
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    result = w_audit()
    lines = ["| audit | seconds (wall) | CPU seconds | goal | verdict as made | reference cells | max residual | "
             "GPU interpolation max error |", "|---|---|---|---|---|---|---|---|"]
    for case in result["cases"].values():
        goal_text = f"≤ {case['goal_s']:g} s" if case["goal_s"] else "—"
        lines.append(f"| {case['title']} | {case['seconds']:.2f} | {case['cpu_seconds']:.2f} | {goal_text} | "
                     f"{case['named']} | {case['reference_cells']} | {case['max_residual']:.3g} | "
                     f"{case['interpolation_max']:.3g} |")
    for case in result["cases"].values():
        if "f90_cells" in case:
            lines.append(f"\n{case['title']}: {case['f90_cells']} quadrature reference cells")
    lines.append(f"\nload average {result['load_average']:.1f}")
    text = "\n".join(lines)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")
    return 0 if result["status"] == "ok" else 1


if __name__ == "__main__":
    raise SystemExit(main())
