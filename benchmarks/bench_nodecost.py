"""The fused global rule's cost per node (issue 39, item 2; docs/performance.md, "Seventh round: the fused loop's
cost per node"): CPU nanoseconds per evaluation of :func:`brdfnorm.engine.compiled.global_rule.integrate` inside
the tables that spend most of their time there, and of the same calls replayed on their recorded cells.

Workloads (compiled backend, one thread, ``--clamp mu=1e-4``, rtol 1e-10, 32 × 32 unless ``--size``):

* ``dfg``: ``lut ggx --channels dfg`` (the built-in microfacet weight, :func:`.global_rule.fused_global`);
* ``brdf``: ``lut examples/ggx.brdf -p f0=1`` over μ and roughness, E then E_avg (the shader's weight,
  :func:`.global_rule.shader_global`), split by stage.

Per workload and stage: the table's CPU seconds (``time.process_time``), the global rule's CPU seconds and
evaluations inside it, their ratio in ns per evaluation, and the calls replayed ``--replays`` times (best per call):
the kernel alone on fixed cells. ``--save FILE.npz`` keeps the tables and every call's (value, error) to compare two
checkouts (``--compare A.npz B.npz``: the largest |Δ| / estimate). CPU, not wall, seconds: the machine is shared.

Run: ``PYTHONPATH=src .venv/bin/python benchmarks/bench_nodecost.py [--size 32] [--save out.npz]``.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _record(stage: list, calls: list):
    """Wrap global_rule.integrate: per call its stage, CPU seconds, evaluations, a copy of its arguments, outputs."""
    from brdfnorm.engine.compiled import global_rule

    original = global_rule.integrate

    def integrate(cases, lam, width, symmetric, scale, rtol, atol, max_nodes, graded_predicts, lobe):
        arguments = [np.array(x, copy=True) for x in (cases, lam, width, symmetric, scale, rtol, atol)]
        start = time.process_time()
        out = original(cases, lam, width, symmetric, scale, rtol, atol, max_nodes, graded_predicts, lobe)
        seconds = time.process_time() - start
        calls.append({"stage": stage[0], "seconds": seconds, "evaluations": int(out[2].sum()),
                      "arguments": (*arguments, max_nodes, graded_predicts, lobe), "value": out[0].copy(),
                      "error": out[1].copy(), "settled": out[3].copy()})
        return out

    global_rule.integrate = integrate
    return original


def _staged(stage: list):
    """Mark E_avg's calls: lut.table's averages run under stage "E_avg"."""
    from brdfnorm.lut import table

    for name in ("average_over_mu", "_average_adaptive"):
        original = getattr(table, name)

        def wrapped(*args, _original=original, **kwargs):
            previous, stage[0] = stage[0], "E_avg"
            try:
                return _original(*args, **kwargs)
            finally:
                stage[0] = previous

        setattr(table, name, wrapped)


def _replay(original, calls: list, replays: int) -> dict:
    per_stage: dict[str, list[float]] = {}
    for call in calls:
        best = np.inf
        for _ in range(replays):
            start = time.process_time()
            out = original(*call["arguments"])
            best = min(best, time.process_time() - start)
        assert int(out[2].sum()) == call["evaluations"]
        entry = per_stage.setdefault(call["stage"], [0.0, 0])
        entry[0] += best
        entry[1] += call["evaluations"]
    return {stage: {"cpu_s": s, "evaluations": n, "ns_per_evaluation": 1e9 * s / max(n, 1)}
            for stage, (s, n) in per_stage.items()}


def run(size: int, replays: int, save: str | None) -> dict:
    import brdfnorm as bn
    from brdfnorm import lut

    stage, calls = ["E"], []
    original = _record(stage, calls)
    _staged(stage)
    axes_alpha = {"mu": np.linspace(0.0, 1.0, size), "alpha": np.linspace(0.05, 1.0, size)}
    axes_rough = {"mu": np.linspace(0.0, 1.0, size), "roughness": np.linspace(0.05, 1.0, size)}
    workloads = {"dfg": (bn.load("ggx"), axes_alpha, ("dfg",)),
                 "brdf": (bn.load(str(ROOT / "examples" / "ggx.brdf"), f0=1.0), axes_rough, ())}
    report, arrays = {}, {}
    for name, (model, axes, channels) in workloads.items():
        def compute(model=model, axes=axes, channels=channels):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return lut.compute(model, axes, clamp={"mu": 1e-4}, rtol=1e-10, channels=channels,
                                   backend="compiled", workers=1)

        compute()  # warm-up: kernels loaded
        calls.clear()
        stage[0] = "E"
        start = time.process_time()
        table = compute()
        table_cpu = time.process_time() - start
        line = {"table_cpu_s": table_cpu, "table_evaluations": table.meta["evaluations"],
                "unconverged": table.meta["unconverged"], "stages": {}}
        for key in sorted({c["stage"] for c in calls}):
            mine = [c for c in calls if c["stage"] == key]
            seconds, evaluations = sum(c["seconds"] for c in mine), sum(c["evaluations"] for c in mine)
            line["stages"][key] = {"global_rule_cpu_s": seconds, "evaluations": evaluations,
                                   "ns_per_evaluation": 1e9 * seconds / max(evaluations, 1), "calls": len(mine)}
        line["replayed"] = _replay(original, calls, replays)
        report[name] = line
        for column in table:
            arrays[f"{name}/table/{column}"] = np.asarray(table[column])
        for i, c in enumerate(calls):
            arrays[f"{name}/call{i}/value"], arrays[f"{name}/call{i}/error"] = c["value"], c["error"]
            arrays[f"{name}/call{i}/settled"] = c["settled"]
    if save:
        np.savez(save, **arrays)
    return report


def compare(a: str, b: str) -> dict:
    """Largest |Δ| / estimate of the tables' values (against their *_error columns) and of the calls' values."""
    x, y = np.load(a), np.load(b)
    out = {"keys_differ": sorted(set(x.files) ^ set(y.files))}
    for key in x.files:
        if key not in y.files:
            continue
        if key.endswith("_error") or key.endswith("/error") or key.endswith("/settled"):
            if not np.array_equal(x[key], y[key], equal_nan=True):
                out.setdefault("errors_differ", []).append(key)
            continue
        if key.endswith("/value"):
            estimate = np.maximum(x[key.replace("/value", "/error")], y[key.replace("/value", "/error")])
            settled = x[key.replace("/value", "/settled")] & y[key.replace("/value", "/settled")]
            if not np.array_equal(x[key.replace("/value", "/settled")], y[key.replace("/value", "/settled")]):
                out.setdefault("settled_differ", []).append(key)
            delta = np.abs(x[key] - y[key])[settled]
            estimate = estimate[settled]
        else:
            error_key = f"{key}_error"
            if error_key not in x.files:
                if not np.array_equal(x[key], y[key], equal_nan=True):
                    out.setdefault("other_differ", []).append(key)
                continue
            delta = np.abs(x[key] - y[key])
            estimate = np.maximum(x[error_key], y[error_key])
        group = key.split("/")[0] + ("/calls" if key.endswith("/value") else "/" + key.split("/")[-1])
        entry = out.setdefault(group, {"max_delta_over_estimate": 0.0, "max_abs_delta": 0.0, "identical": True})
        if delta.size:
            ratio = np.where(delta > 0, delta / np.where(estimate > 0, estimate, np.inf), 0.0)
            entry["max_delta_over_estimate"] = max(entry["max_delta_over_estimate"], float(ratio.max()))
            entry["max_abs_delta"] = max(entry["max_abs_delta"], float(delta.max()))
            entry["identical"] &= bool(np.all(delta == 0))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=int, default=32)
    parser.add_argument("--replays", type=int, default=3)
    parser.add_argument("--save")
    parser.add_argument("--compare", nargs=2)
    args = parser.parse_args()
    if args.compare:
        print(json.dumps(compare(*args.compare), indent=1))
        return
    print(json.dumps(run(args.size, args.replays, args.save), indent=1))


if __name__ == "__main__":
    main()
