#!/usr/bin/env python
"""Time ``brdfnorm check`` on every example file at the default budget, with its verdicts (the audit of issue 15).

Usage: ``python benchmarks/bench_check.py [--budget SECONDS] [--out FILE.md] [FILE.brdf ...]`` (default: every
file in examples/). Prints a markdown table — seconds per file, verdict, the largest albedo found with its error
bar and where, what the search covered — to stdout, and writes it to ``--out`` when given.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))

from brdfnorm.check import Budget, check  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--budget", type=float, default=20.0, help="seconds per file (the command's default)")
    parser.add_argument("--out", type=Path, help="also write the markdown table here")
    args = parser.parse_args(argv)
    files = args.files or sorted((ROOT / "examples").glob("*.brdf"))
    lines = ["| file | verdict | failed | largest albedo ± error | where | parameter points × directions | "
             "refinement | evaluations | seconds |", "|---|---|---|---|---|---|---|---|---|"]
    for path in files:
        start = time.perf_counter()
        report = check(path, budget=Budget(seconds=args.budget))
        seconds = time.perf_counter() - start
        energy, covered = report.results["energy"], report.coverage["energy"]
        where = ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in energy.params.items())
        lines.append(
            f"| {path.name} | {report.status} | {', '.join(report.failed) or '—'} | {energy.value:.10g} ± "
            f"{energy.error:.1e} | {where}; θ={energy.theta_deg:.4g}° φ={energy.phi_deg:.4g}° | "
            f"{covered['parameter_points']}/{covered['parameter_points_planned']} × {covered['directions']} | "
            f"{'finished' if covered['refinement_finished'] else 'stopped by budget'} | "
            f"{report.coverage['evaluations']:.3g} | {seconds:.1f} |")
        print(lines[-1], file=sys.stderr, flush=True)
    table = "\n".join(lines) + "\n"
    print(table)
    if args.out:
        args.out.write_text(table, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
