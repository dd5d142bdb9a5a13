"""The compiled backend against the numpy backend and scipy's dblquad (issue 39), side by side in one process.

Rows (each the best of ``repeats`` timed runs after one untimed warm-up, both backends in the same run; wall and
CPU seconds, ratios of CPU seconds):

* ``generic-vs-dblquad``: one Blinn-Phong (n = 100) albedo at θ_o = 60° by the generic engine (method
  "quadrature") at rtol 1e-9, and by ``scipy.integrate.dblquad`` at the same rtol; errors against mpmath;
* ``generic-batch-vs-dblquad``: the same lobe and rtol over a curve of 18 views θ_o = 0, 5, …, 85° in ONE call of
  the generic engine (the per-call set-up — lobe search, isotropy test, rounding-noise probe, global-rule set-up —
  paid once for the batch), CPU per albedo, against dblquad's mean CPU per albedo over the same views (one call
  each: dblquad has no batch); ``per_call_overhead_ms`` is the single-call CPU less the batch's per-albedo CPU;
  the largest error against mpmath and the smallest estimate/error ratio of both;
* ``dblquad-matched``: the batch row's views with dblquad at the epsrel that reaches the error brdfnorm achieves
  (against mpmath; 8 ulp of the albedo where both are at float64's rounding), or its best reachable: its largest
  error, CPU ms and evaluations per albedo (a counting lobe) beside brdfnorm's, both backends;
* ``evaluations``: integrand evaluations per generic Blinn-Phong albedo over θ_o = 0…89° (rtol 1e-9);
* ``generic-table``: a 32 × 32 E(μ, α) table and E_avg of built-in GGX through the generic engine (method
  "quadrature": the route a ``.brdf`` GGX takes, with the compiled lobe as its shader), rtol 1e-10;
* ``brdf-table``: the same table of ``examples/ggx.brdf`` (its GLSL shader compiled where the GLSL native backend
  is present, else through numpy closures); compiled also on every core (``workers=None``: one thread per core,
  :mod:`brdfnorm.parallel.threads`), with whether its tables equal the one-thread tables bit for bit;
* ``ggx-table`` and ``dfg-table``: ``lut ggx`` 32 × 32 E + E_avg, and its split-sum channels, in-process (the DFG
  table also on every core);
* ``brdf-table-cli``: the ``brdf-table`` row as a user runs it, ``brdfnorm lut examples/ggx.brdf … --clamp mu=1e-4
  -p f0=1 --rtol 1e-10`` in a new process (kernel cache warm), with ``--workers 1`` and with the default workers
  (a thread per core under the compiled backend); CPU of the process (all its threads) and its wall time;
* ``cold-start``: a new process importing brdfnorm and computing one built-in albedo, and one generic albedo with
  the kernel cache warm and with an empty cache (compiling the lobe's kernels).

Run alone: ``.venv/bin/python benchmarks/bench_backends.py [--quick]``; in ``make bench`` as workload ``backends``.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.parallel import local_cores

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
BACKENDS = ("numpy", "compiled")


#: CPU seconds of the best run, beside its wall time (``_best``): on a shared machine the wall time scales with the
#: load, the CPU time far less.
CPU: dict[int, float] = {}


def _best(call, repeats: int) -> tuple[float, object]:
    """The best wall time of ``repeats`` runs after a warm-up (its CPU time in CPU[id(result)])."""
    call()  # warm-up: kernel loading, caches
    times, result = [], None
    for _ in range(max(repeats, 1)):
        start, cpu = time.perf_counter(), time.process_time()
        result = call()
        times.append((time.perf_counter() - start, time.process_time() - cpu))
    wall, cpu = min(times)
    CPU[id(result)] = cpu
    return wall, result


def _generic_vs_dblquad(repeats: int) -> dict:
    sys.path.insert(0, str(HERE))
    import peers

    n, theta, rtol = 100.0, 60.0, 1e-9
    model = bn.load("blinn-phong", n=n)
    truth = peers.blinn_phong_reference(n, np.radians(theta))
    row = {"title": f"Blinn-Phong n={n:g} albedo at {theta:g}°, rtol {rtol:g}"}
    for backend in BACKENDS:
        seconds, result = _best(lambda b=backend: bn.albedo(model, np.radians(theta), method="quadrature",
                                                            rtol=rtol, backend=b), repeats)
        row[backend] = {"time_s": seconds, "cpu_s": CPU[id(result)], "error": abs(float(result.value[0]) - truth),
                        "estimate": float(result.error[0]), "evaluations": int(result.evaluations)}
    seconds, peer = _best(lambda: peers.dblquad_albedo(peers.blinn_phong(n), np.radians(theta), rtol), 1)
    row["dblquad"] = {"time_s": seconds, "cpu_s": CPU[id(peer)], "error": abs(peer.value - truth)}
    for backend in BACKENDS:
        row[f"dblquad_over_{backend}"] = row["dblquad"]["cpu_s"] / row[backend]["cpu_s"]
    return row


def _generic_batch_vs_dblquad(repeats: int) -> dict:
    sys.path.insert(0, str(HERE))
    import peers

    n, rtol = 100.0, 1e-9
    theta = np.radians(np.arange(0.0, 90.0, 5.0))
    model = bn.load("blinn-phong", n=n)
    truth = np.array([peers.blinn_phong_reference(n, t) for t in theta])
    row = {"title": f"Blinn-Phong n={n:g}, {theta.size} views 0…85° in one call, rtol {rtol:g}: CPU per albedo"}
    for backend in BACKENDS:
        seconds, result = _best(lambda b=backend: bn.albedo(model, theta, method="quadrature", rtol=rtol, backend=b),
                                repeats)
        error = np.abs(result.value[:, 0] - truth)
        single = _best(lambda b=backend: bn.albedo(model, theta[12], method="quadrature", rtol=rtol, backend=b),
                       repeats)[1]
        per_albedo = CPU[id(result)] / theta.size
        row[backend] = {"cpu_ms_per_albedo": 1e3 * per_albedo, "wall_ms_per_albedo": 1e3 * seconds / theta.size,
                        "single_call_cpu_ms": 1e3 * CPU[id(single)],
                        "per_call_overhead_ms": 1e3 * (CPU[id(single)] - per_albedo),
                        "max_error": float(error.max()),
                        "all_within_estimates": bool(np.all(error <= result.error[:, 0])),
                        "evaluations_mean": float(np.mean(result.evaluations))}
    start = time.process_time()
    peer = [peers.dblquad_albedo(peers.blinn_phong(n), t, rtol) for t in theta]
    cpu = (time.process_time() - start) / theta.size
    row["dblquad"] = {"cpu_ms_per_albedo": 1e3 * cpu,
                      "max_error": float(np.max(np.abs([p.value for p in peer] - truth)))}
    for backend in BACKENDS:
        row[f"dblquad_over_{backend}"] = cpu / (row[backend]["cpu_ms_per_albedo"] / 1e3)
    return row


#: dblquad's epsrel ladder for the accuracy-matched row (scipy refuses epsrel below 50 ε with epsabs = 0).
MATCH_EPSREL = (1e-9, 1e-10, 1e-11, 1e-12, 1e-13)


def _dblquad_matched() -> dict:
    """dblquad at the epsrel that reaches brdfnorm's achieved accuracy, over the batch row's 18 views.

    The same-rtol rows compare costs at the same *requested* tolerance; this one at the same *achieved* error
    (against mpmath): for each epsrel of :data:`MATCH_EPSREL`, dblquad's largest error over the views, its mean CPU
    ms and evaluations per albedo (a counting lobe, as benchmarks/run.py's w_profile counts them); the row matched
    is the first whose largest error is within brdfnorm's largest error, or 8 ulp of the albedo where both are at
    float64's rounding (an error below that is the last bits of a sum, not accuracy); the best reachable where
    none is."""
    sys.path.insert(0, str(HERE))
    import peers

    n, rtol = 100.0, 1e-9
    theta = np.radians(np.arange(0.0, 90.0, 5.0))
    model = bn.load("blinn-phong", n=n)
    truth = np.array([peers.blinn_phong_reference(n, t) for t in theta])
    row = {"title": f"Blinn-Phong n={n:g}, {theta.size} views 0…85°: dblquad at the accuracy brdfnorm reaches at "
                    f"rtol {rtol:g}"}
    floor = 8.0 * np.spacing(truth).max()
    for backend in BACKENDS:
        result = bn.albedo(model, theta, method="quadrature", rtol=rtol, backend=backend)  # warm-up: kernels
        start = time.process_time()
        result = bn.albedo(model, theta, method="quadrature", rtol=rtol, backend=backend)
        row[backend] = {"cpu_ms_per_albedo": 1e3 * (time.process_time() - start) / theta.size,
                        "max_error": float(np.max(np.abs(result.value[:, 0] - truth))),
                        "evaluations_mean": float(np.mean(result.evaluations))}
    target = max(max(row[b]["max_error"] for b in BACKENDS), floor)
    lobe = peers.blinn_phong(n)
    ladder = []
    for epsrel in MATCH_EPSREL:
        count = [0]
        counting = peers.PeerLobe(lobe.name, lambda *a, c=count: (c.__setitem__(0, c[0] + 1), lobe.scalar(*a))[1],
                                  lobe.vector)
        start = time.process_time()
        values = [peers.dblquad_albedo(counting, t, epsrel).value for t in theta]
        ladder.append({"epsrel": epsrel, "cpu_ms_per_albedo": 1e3 * (time.process_time() - start) / theta.size,
                       "evaluations_mean": count[0] / theta.size,
                       "max_error": float(np.max(np.abs(np.array(values) - truth)))})
    reached = [line for line in ladder if line["max_error"] <= target]
    matched = reached[0] if reached else min(ladder, key=lambda line: line["max_error"])
    row.update({"target_error": target, "dblquad_ladder": ladder, "dblquad": {**matched, "reached": bool(reached)}})
    for backend in BACKENDS:
        row[f"dblquad_over_{backend}"] = matched["cpu_ms_per_albedo"] / row[backend]["cpu_ms_per_albedo"]
    return row


def _evaluations() -> dict:
    theta = np.radians(np.arange(90.0))
    result = bn.albedo(bn.load("blinn-phong", n=100.0), theta, method="quadrature", rtol=1e-9, backend="numpy")
    return {"title": "evaluations per generic Blinn-Phong (n=100) albedo, θ_o = 0…89°, rtol 1e-9",
            "mean": float(result.evaluations.mean()), "max": int(result.evaluations.max())}


def _table(model, size: int, repeats: int, *, method: str = "auto", channels=(), backends=BACKENDS,
           roughness: str = "alpha", all_cores: bool = False) -> dict:
    axes = {"mu": np.linspace(0.0, 1.0, size), roughness: np.linspace(0.05, 1.0, size)}
    row = {}
    values = {}
    for backend in backends:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            seconds, table = _best(lambda b=backend: lut.compute(model, axes, clamp={"mu": 1e-4}, rtol=1e-10,
                                                                  method=method, channels=channels, backend=b),
                                   repeats)
        values[backend] = table
        row[backend] = {"time_s": seconds, "cpu_s": CPU[id(table)], "unconverged": table.meta["unconverged"],
                        "evaluations": table.meta["evaluations"]}
    if all_cores:  # the compiled backend on a thread per core (the default workers), against its one-thread tables
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            seconds, table = _best(lambda: lut.compute(model, axes, clamp={"mu": 1e-4}, rtol=1e-10, method=method,
                                                       channels=channels, backend="compiled", workers=None), repeats)
        one = values["compiled"]
        row["compiled_all_cores"] = {"time_s": seconds, "cpu_s": CPU[id(table)], "threads": local_cores(),
                                     "identical": all(np.array_equal(table[n], one[n]) for n in one)}
    if len(values) == 2:
        a, b = values["numpy"], values["compiled"]
        row["compiled_within_estimates"] = bool(np.all(np.abs(a["E"] - b["E"]) <= a["E_error"] + b["E_error"]))
        row["numpy_over_compiled"] = row["numpy"]["cpu_s"] / row["compiled"]["cpu_s"]
    return row


def _seconds_in_new_process(code: str, env: dict) -> dict:
    """Wall and CPU seconds (user + system, from the child's rusage) of a new process running ``code``: on a loaded
    machine the wall time of a compile scales with the load, its CPU time hardly."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env, capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu}


def _cli_table(size: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    row = {}
    with tempfile.TemporaryDirectory() as out:
        for name, extra in (("workers_1", ["--workers", "1"]), ("default_workers", [])):
            argv = ["brdfnorm", "lut", str(ROOT / "examples" / "ggx.brdf"), "--axis", f"mu=0:1:n={size}", "--axis",
                    f"roughness=0.05:1:n={size}", "--clamp", "mu=1e-4", "-p", "f0=1", "--rtol", "1e-10", "-o",
                    str(Path(out) / "table.json"), *extra]
            code = f"import sys; sys.argv = {argv!r}; from brdfnorm.cli import main; main()"
            row[name] = _seconds_in_new_process(code, env)
    return row


def _cold_start() -> dict:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    builtin = "import brdfnorm as bn; bn.albedo(bn.load('ggx', alpha=0.3), 0.5)"
    generic = "import brdfnorm as bn; bn.albedo(bn.load('oren-nayar'), 0.5, method='quadrature')"
    row = {"builtin_albedo": _seconds_in_new_process(builtin, env)}
    with tempfile.TemporaryDirectory() as empty:  # a cache of its own: empty, then warmed by that first run
        row["generic_albedo_empty_cache"] = _seconds_in_new_process(generic, {**env, "BRDFNORM_CACHE_DIR": empty})
        row["generic_albedo_warm_cache"] = _seconds_in_new_process(generic, {**env, "BRDFNORM_CACHE_DIR": empty})
    row["import"] = _seconds_in_new_process("import brdfnorm", env)
    return row


def _cpu(line: dict) -> str:
    return f"{line['cpu_s']:.3g} CPU s ({line['time_s']:.3g} s wall)"


def rows(w: dict) -> list[tuple[str, str, str, str, str]]:
    """(workload, numpy, compiled, against, goal) per issue-39 workload of ``w_backends``'s result, for the
    side-by-side table of ``make bench`` (benchmarks/run.py)."""
    out = []
    single = w["generic_vs_dblquad"]
    out.append((f"one generic albedo vs dblquad ({single['title']})", _cpu(single["numpy"]), _cpu(single["compiled"]),
                f"dblquad {single['dblquad']['cpu_s'] * 1e3:.3g} CPU ms: {single['dblquad_over_numpy']:.3g}× / "
                f"{single['dblquad_over_compiled']:.3g}× faster", "≥ 500×"))
    batch = w["generic_batch_vs_dblquad"]

    def per_albedo(line: dict) -> str:
        return (f"{line['cpu_ms_per_albedo']:.3g} CPU ms per albedo, one call {line['single_call_cpu_ms']:.3g} ms "
                f"(set-up {line['per_call_overhead_ms']:.3g} ms)")

    out.append((f"generic albedos in a batch vs dblquad ({batch['title']})", per_albedo(batch["numpy"]),
                per_albedo(batch["compiled"]),
                f"dblquad {batch['dblquad']['cpu_ms_per_albedo']:.3g} CPU ms per albedo: "
                f"{batch['dblquad_over_numpy']:.3g}× / {batch['dblquad_over_compiled']:.3g}× faster", "≥ 500×"))
    matched = w["dblquad_matched"]

    def achieved(line: dict) -> str:
        return (f"{line['cpu_ms_per_albedo']:.3g} CPU ms per albedo, {line['evaluations_mean']:.0f} evaluations, "
                f"largest error {line['max_error']:.2g}")

    peer = matched["dblquad"]
    out.append((f"generic albedos vs dblquad at the same achieved error ({matched['title']})",
                achieved(matched["numpy"]), achieved(matched["compiled"]),
                f"dblquad at epsrel {peer['epsrel']:g} ({'reaches' if peer['reached'] else 'best reachable, misses'} "
                f"{matched['target_error']:.2g}): {achieved(peer)}; {matched['dblquad_over_numpy']:.3g}× / "
                f"{matched['dblquad_over_compiled']:.3g}× faster", "≥ 500×"))
    evaluations = w["evaluations"]
    out.append((evaluations["title"], f"{evaluations['mean']:.0f} mean, {evaluations['max']} max", "same", "",
                "≤ 5 000"))
    for key, title, goal in (("generic_table", "32×32 E + E_avg, built-in GGX through the generic engine", "—"),
                             ("brdf_table", "lut examples/ggx.brdf 32×32 E + E_avg", "≤ 2 s"),
                             ("ggx_table", "lut ggx 32×32 E + E_avg", "≤ 0.1 s"),
                             ("dfg_table", "lut ggx --channels dfg 32×32", "≤ 3 s")):
        table = w[key]
        ratio = f"numpy/compiled {table['numpy_over_compiled']:.3g}×" if "numpy_over_compiled" in table else ""
        if "compiled_within_estimates" in table:
            ratio += f"; equal within estimates: {table['compiled_within_estimates']}"
        cells = [f"{_cpu(table[b])}, {table[b]['evaluations']} evaluations, {table[b]['unconverged']} unconverged"
                 for b in BACKENDS]
        if "compiled_all_cores" in table:
            every = table["compiled_all_cores"]
            cells[1] += (f"; on {every['threads']} threads {_cpu(every)}, tables "
                         f"{'identical' if every['identical'] else 'DIFFERENT'}")
        out.append((title, *cells, ratio, goal))
    cli = w["brdf_table_cli"]
    out.append(("the same .brdf table through the CLI, new process, warm kernel cache", "",
                "; ".join(f"{label} {cli[key]['wall_s']:.3g} s wall ({cli[key]['cpu_s']:.3g} CPU s)"
                          for key, label in (("workers_1", "--workers 1"),
                                             ("default_workers", f"default workers ({local_cores()} threads)"))),
                "", "≤ 2 s"))
    cold = w["cold_start"]
    for key, title, goal in (("builtin_albedo", "new process: import + one built-in GGX albedo", "≤ 0.5 s"),
                             ("generic_albedo_empty_cache", "new process, empty kernel cache: import + compile + "
                              "first generic albedo (oren-nayar)", "≤ 5 s"),
                             ("generic_albedo_warm_cache", "the same with the kernel cache warm", "—")):
        out.append((title, "", f"{cold[key]['cpu_s']:.3g} CPU s ({cold[key]['wall_s']:.3g} s wall)",
                    f"import alone {cold['import']['cpu_s']:.3g} CPU s", goal))
    return out


def w_backends(cfg, refs=None) -> dict:
    """The workload as benchmarks/run.py reports it."""
    quick = cfg.quick
    size, repeats = (8, 1) if quick else (32, 2)
    ggx = bn.load("ggx")
    return {
        "title": "compiled backend (issue 39): numpy vs compiled vs dblquad",
        "status": "ok", "load_average": os.getloadavg()[0],
        # The new processes' imports compile every module of the package from source where bytecode is not written
        # (PYTHONDONTWRITEBYTECODE, set on some machines: ~0.13 s more of a CLI start, docs/performance.md).
        "bytecode_cache": not sys.dont_write_bytecode,
        "generic_vs_dblquad": _generic_vs_dblquad(repeats),
        "generic_batch_vs_dblquad": _generic_batch_vs_dblquad(repeats),
        "dblquad_matched": _dblquad_matched(),
        "evaluations": _evaluations(),
        "generic_table": _table(ggx, size, repeats, method="quadrature"),
        "brdf_table": _table(bn.load(str(ROOT / "examples" / "ggx.brdf"), f0=1.0), size, 1, roughness="roughness",
                             all_cores=True),
        "ggx_table": _table(ggx, size, repeats),
        "dfg_table": _table(ggx, size, 1, channels=("dfg",), all_cores=True),
        "brdf_table_cli": _cli_table(size),
        "cold_start": _cold_start(),
    }


if __name__ == "__main__":
    import json
    from types import SimpleNamespace

    print(json.dumps(w_backends(SimpleNamespace(quick="--quick" in sys.argv[1:])), indent=1))
