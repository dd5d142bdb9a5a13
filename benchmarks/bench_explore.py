"""How live ``brdfnorm explore`` feels (issue 16, item 4): first page load and the update after a slider move.

Run: ``.venv/bin/python benchmarks/bench_explore.py [moves] [loads]`` (needs the ``explore`` extra, Playwright
and Debian's /usr/bin/chromium). For each model — the built-ins and examples/ggx.brdf — ``loads`` fresh browser
contexts load the page cold (empty cache: plotly.js is transferred and compiled from scratch); the last one then
moves the model's first slider ``moves`` times across its range, waiting for each update. A cold load is split
into where its time goes (the Resource Timing and Navigation Timing APIs): the plotly bundle's transfer
(bytes on the wire, ms), the scripts compiled and run (DOMContentLoaded: the deferred plotly.js is the bulk),
the first numbers shown, all three plots drawn, and the refined pass with brdfnorm check's energy verdict. The
page itself records, per update, the time from the ``input`` event to the moment the coarse plots (lobe, albedo
curve, 3-D surface) and numbers are drawn, the server's compute time, and the same for the refined pass (whose
energy verdict comes from ``brdfnorm.check``: its server time is reported apart); a *drag* (ten moves 30 ms
apart, as a mouse drag sends them) measures the last move's latency, which includes cancelling the stale work.
Targets: first load ≤ 2 s, update ≤ 300 ms. Writes ``benchmarks/results/explore.md`` and ``explore.json``;
prints the tables. The machine's load average is recorded with the numbers: on a shared machine they scale
with it.

``bench_explore.py --against OLD_SRC [rounds]`` compares cold first loads of another source tree (e.g. an earlier
commit's ``src/``, from ``git archive``) with this one: both served at once (``brdfnorm explore`` run with each
tree on PYTHONPATH), loads alternating between them in one browser so that both see the same machine load.
Writes ``benchmarks/results/explore.before-after.md``.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from playwright.sync_api import sync_playwright

from brdfnorm.explore import Catalog, background

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--disable-sync", "--no-first-run"]
#: (catalog id, label, the slider moved); the slider runs over 10 %…90 % of its range.
MODELS = [("arg0", "examples/ggx.brdf", "roughness"), ("builtin:lambert", "lambert", "reflectance"),
          ("builtin:phong", "phong", "n"), ("builtin:modified-phong", "modified-phong", "n"),
          ("builtin:blinn-phong", "blinn-phong", "n"), ("builtin:blinn-phong-gaussian", "blinn-phong-gaussian", "n")]
TIMING = "document.body.dataset.{}Timing ? JSON.parse(document.body.dataset.{}Timing) : null"
#: Where a cold load's time went, from the browser's own timing APIs (ms from navigation start).
LOAD_BREAKDOWN = """() => {
  const navigation = performance.getEntriesByType("navigation")[0];
  const bundle = performance.getEntriesByType("resource").find((r) => r.name.includes("/static/plotly"));
  return { bundle_bytes: bundle.transferSize, bundle_body_bytes: bundle.decodedBodySize,
           bundle_transfer_ms: bundle.responseEnd - bundle.startTime, bundle_done_ms: bundle.responseEnd,
           scripts_ready_ms: navigation.domContentLoadedEventEnd };
}"""


def wait_timing(page, quality: str, generation: int | None = None, timeout: float = 120.0) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        timing = page.evaluate(TIMING.format(quality, quality))
        if timing and (generation is None or timing["generation"] == generation):
            return timing
        time.sleep(0.01)
    raise TimeoutError(f"no {quality} update for generation {generation}")


def generation(page) -> int:
    return int(page.evaluate("document.body.dataset.generation"))


def cold_load(browser, url: str, model_id: str) -> tuple[dict, object, object]:
    """One cold load in a fresh context: its breakdown, and the context and page (still open)."""
    context = browser.new_context(viewport={"width": 1440, "height": 1200})
    page = context.new_page()
    page.goto(f"{url}?model={model_id}")
    first = wait_timing(page, "coarse")
    first_fine = wait_timing(page, "fine", first["generation"])
    load = page.evaluate(LOAD_BREAKDOWN)
    load.update(numbers_ms=first["page_numbers_ms"], plots_ms=first["page_ms"], refined_ms=first_fine["page_ms"],
                check_ms=first_fine["check_ms"])
    return load, context, page


def measure(browser, url: str, model_id: str, name: str, moves: int, loads: int, watched: Path | None) -> dict:
    cold = []
    for _ in range(loads):
        load, context, page = cold_load(browser, url, model_id)
        cold.append(load)
        if len(cold) < loads:
            context.close()
    slider = page.get_by_test_id(f"param-{name}")
    low, high = float(slider.get_attribute("min")), float(slider.get_attribute("max"))
    coarse, fine = [], []
    for k in range(moves):
        position = low + (high - low) * (0.1 + 0.8 * k / max(moves - 1, 1))
        slider.fill(repr(position))
        g = generation(page)
        coarse.append(wait_timing(page, "coarse", g))
        fine.append(wait_timing(page, "fine", g))
    for k in range(10):  # a drag: moves 30 ms apart, the last one counts
        slider.fill(repr(low + (high - low) * (0.15 + 0.07 * k)))
        time.sleep(0.03)
    drag = wait_timing(page, "coarse", generation(page))
    drag_fine = wait_timing(page, "fine", generation(page))
    saved = None
    if watched is not None:  # save the watched file: time until the page shows the reloaded model's numbers
        before = generation(page)
        started = time.monotonic()
        watched.write_text(watched.read_text().replace("::end shader", "// saved by the benchmark\n::end shader"))
        wait_timing(page, "coarse", before + 1)
        saved = 1e3 * (time.monotonic() - started)
    page.reload()  # a second visit: the assets come from the browser's cache (content-hashed URLs)
    reload = wait_timing(page, "coarse")
    context.close()
    latencies = [t["latency_ms"] for t in coarse]
    plots = [c["plots_ms"] for c in cold]
    return {
        "cold_loads": cold, "first_load_ms_median": statistics.median(plots), "first_load_ms_max": max(plots),
        "first_numbers_ms_median": statistics.median(c["numbers_ms"] for c in cold),
        "scripts_ready_ms_median": statistics.median(c["scripts_ready_ms"] for c in cold),
        "bundle_transfer_ms_median": statistics.median(c["bundle_transfer_ms"] for c in cold),
        "bundle_bytes": cold[0]["bundle_bytes"], "bundle_body_bytes": cold[0]["bundle_body_bytes"],
        "first_refined_ms_median": statistics.median(c["refined_ms"] for c in cold),
        "reload_ms": reload["page_ms"], "reload_numbers_ms": reload["page_numbers_ms"],
        "update_2d_ms_median": statistics.median(t["latency_2d_ms"] for t in coarse),
        "update_ms_median": statistics.median(latencies), "update_ms_max": max(latencies),
        "server_ms_median": statistics.median(t["compute_ms"] for t in coarse),
        "draw_ms_median": statistics.median(sum(t["draw_ms"].values()) for t in coarse),
        "refined_ms_median": statistics.median(t["latency_ms"] for t in fine),
        "check_ms_median": statistics.median(t["check_ms"] for t in fine),
        "drag_last_ms": drag["latency_ms"], "drag_refined_ms": drag_fine["latency_ms"], "save_to_numbers_ms": saved,
        "moves": moves, "coarse": coarse, "fine": fine,
    }


def run_all(watched: Path, moves: int, loads: int, results: dict) -> None:
    with background(Catalog.build([str(watched)])) as url, sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
        for model_id, label, name in MODELS:
            results[label] = measure(browser, url, model_id, name, moves, loads,
                                     watched if model_id == "arg0" else None)
            r = results[label]
            print(f"{label:22s} first load {r['first_load_ms_median']:6.0f} ms (max {r['first_load_ms_max']:5.0f})  "
                  f"update median {r['update_ms_median']:5.0f} "
                  f"max {r['update_ms_max']:5.0f} ms (server {r['server_ms_median']:4.0f}, draw "
                  f"{r['draw_ms_median']:4.0f})  refined {r['refined_ms_median']:6.0f} ms  "
                  f"(check {r['check_ms_median']:5.0f})  drag {r['drag_last_ms']:5.0f} ms", file=sys.stderr)
        browser.close()


def main(moves: int = 8, loads: int = 3) -> None:
    load_before = os.getloadavg()
    results = {}
    with tempfile.TemporaryDirectory() as directory:
        watched = Path(directory) / "ggx.brdf"  # a copy: the benchmark saves it
        shutil.copy(ROOT / "examples" / "ggx.brdf", watched)
        run_all(watched, moves, loads, results)
    load_after = os.getloadavg()
    summary = {"load_average_before": load_before, "load_average_after": load_after, "cpus": os.cpu_count(),
               "targets": {"first_load_ms": 2000, "update_ms": 300}, "models": results}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "explore.json").write_text(json.dumps(summary, indent=1) + "\n")
    bundle = next(iter(results.values()))
    lines = ["# brdfnorm explore: page load and update latency", "",
             f"{os.cpu_count()} CPUs, load average {load_before[0]:.1f} before and {load_after[0]:.1f} after the run "
             "(other processes share the machine). Headless Chromium.", "",
             f"## First load (cold cache, median of {loads} per model; ms from navigation start)", "",
             f"plotly.js bundle: {bundle['bundle_body_bytes'] / 1e6:.2f} MB, {bundle['bundle_bytes'] / 1e6:.2f} MB "
             "on the wire.", "",
             "| model | bundle transfer | scripts ready (DOMContentLoaded) | numbers | all plots (median) "
             "| all plots (max) | refined + energy verdict | second visit: numbers / all plots |",
             "|---|---|---|---|---|---|---|---|"]
    for label, r in results.items():
        lines.append(f"| {label} | {r['bundle_transfer_ms_median']:.0f} ms | {r['scripts_ready_ms_median']:.0f} ms | "
                     f"{r['first_numbers_ms_median']:.0f} ms | {r['first_load_ms_median']:.0f} ms | "
                     f"{r['first_load_ms_max']:.0f} ms | {r['first_refined_ms_median']:.0f} ms | "
                     f"{r['reload_numbers_ms']:.0f} / {r['reload_ms']:.0f} ms |")
    lines += ["", f"## After a slider move ({moves} moves and a ten-move drag per model)", "",
              "| model | numbers + 2-D | + 3-D (median) | + 3-D (max) | server (coarse) | draw "
              "| refined + energy verdict (median) | of which brdfnorm check (server) | last move of a drag |",
              "|---|---|---|---|---|---|---|---|---|"]
    for label, r in results.items():
        lines.append(f"| {label} | {r['update_2d_ms_median']:.0f} ms | {r['update_ms_median']:.0f} ms | "
                     f"{r['update_ms_max']:.0f} ms | {r['server_ms_median']:.0f} ms | {r['draw_ms_median']:.0f} ms | "
                     f"{r['refined_ms_median']:.0f} ms | {r['check_ms_median']:.0f} ms | {r['drag_last_ms']:.0f} ms |")
    saved = results["examples/ggx.brdf"]["save_to_numbers_ms"]
    lines += ["", f"Saving the watched examples/ggx.brdf (a copy) to the page showing the reloaded model's numbers: "
              f"{saved:.0f} ms.", "",
              "Targets: first load ≤ 2000 ms (all plots drawn), update ≤ 300 ms (move → coarse numbers and all three "
              "plots drawn)."]
    (RESULTS / "explore.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def first_load(browser, url: str) -> dict:
    context = browser.new_context(viewport={"width": 1440, "height": 1200})
    try:
        page = context.new_page()
        page.goto(url)
        return wait_timing(page, "coarse")
    finally:
        context.close()


def compare(old_src: str, rounds: int = 4) -> None:
    """Cold first loads, alternating between the tree ``old_src`` and this one (see the module docstring)."""
    trees = {"before": str(Path(old_src).resolve()), "after": str(ROOT / "src")}
    servers, processes = {}, []
    try:
        for name, src in trees.items():
            port = free_port()
            processes.append(subprocess.Popen(
                [sys.executable, "-m", "brdfnorm", "explore", str(ROOT / "examples" / "ggx.brdf"), "--no-browser",
                 "--port", str(port)], env=dict(os.environ, PYTHONPATH=src), stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL))
            servers[name] = f"http://127.0.0.1:{port}/"
        loads = [os.getloadavg()[0]]
        results = {name: {model_id: [] for model_id, _, _ in MODELS} for name in servers}
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
            wait_until_serving(servers.values())
            for k in range(rounds):
                for model_id, _, _ in MODELS:
                    for name in (("before", "after") if k % 2 == 0 else ("after", "before")):
                        results[name][model_id].append(first_load(browser, f"{servers[name]}?model={model_id}"))
                loads.append(os.getloadavg()[0])
            browser.close()
    finally:
        for process in processes:
            process.terminate()
            process.wait()
    lines = ["# brdfnorm explore: cold first load, before and after", "",
             f"`bench_explore.py --against {old_src} {rounds}`: {rounds} cold loads per model and tree, alternating "
             f"between the trees; {os.cpu_count()} CPUs, load average {min(loads):.1f}–{max(loads):.1f} during the "
             "run. Milliseconds from navigation start to the first numbers / to all three plots drawn.", "",
             "| model | before: numbers | before: all plots, median (max) | after: numbers "
             "| after: all plots, median (max) |", "|---|---|---|---|---|"]
    for model_id, label, _ in MODELS:
        cells = []
        for name in servers:
            loads_of = results[name][model_id]
            plots = [t["page_ms"] for t in loads_of]
            cells += [f"{statistics.median(t['page_numbers_ms'] for t in loads_of):.0f}",
                      f"{statistics.median(plots):.0f} ({max(plots):.0f})"]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    every = {name: [t["page_ms"] for runs in results[name].values() for t in runs] for name in servers}
    lines += ["", "All models: " + "; ".join(f"{name} median {statistics.median(v):.0f} ms, max {max(v):.0f} ms"
                                             for name, v in every.items()) + f" (n = {len(every['after'])} each)."]
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "explore.before-after.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def wait_until_serving(urls, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    for url in urls:
        while True:
            try:
                with socket.create_connection(("127.0.0.1", int(url.rsplit(":", 1)[1].strip("/"))), timeout=1):
                    break
            except OSError:
                if time.monotonic() > deadline:
                    raise TimeoutError(f"{url} is not serving") from None
                time.sleep(0.2)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--against"]:
        compare(sys.argv[2], *(int(a) for a in sys.argv[3:4]))
    else:
        main(*(int(a) for a in sys.argv[1:3]))
