"""Kernels compiled ahead on a second core (:mod:`brdfnorm.parallel.warm`): the child compiles the models' kernels
into the disk cache, the microfacet route's first, then the lobes after it, then the earlier ones last-needed first,
with nothing computed by the caller; nothing is started where there is nothing to gain; and the report declares
every lobe and route it compiles."""

from __future__ import annotations

import time

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.compiled import drivers
from brdfnorm.parallel import warm
from brdfnorm.parallel.job import ModelSource
from brdfnorm.report import StudyConfig, build_report, plan


def _key(model) -> str:
    return model.native_kernel().key


@pytest.fixture
def compiled(monkeypatch):
    """The compiled backend, whatever $BRDFNORM_BACKEND the suite runs under."""
    monkeypatch.setenv("BRDFNORM_BACKEND", "compiled")


def test_nothing_pending_on_the_numpy_backend(monkeypatch):
    monkeypatch.setenv("BRDFNORM_BACKEND", "numpy")
    assert warm.pending([bn.load("phong"), bn.load("ggx")]) == []


def test_pending_skips_compiled_kernels_and_repeats(compiled, monkeypatch, tmp_path):
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path))
    phong, ggx = bn.load("phong", n=10.0), bn.load("ggx", alpha=0.3)
    jobs = warm.pending([phong, bn.load("phong", n=50.0), ggx])
    assert [(j.source.name, j.method) for j in jobs] == [("phong", "quadrature"), ("ggx", "quadrature")]  # one per key
    drivers.kernels_file(_key(phong), __import__("numba").__version__).with_suffix(".compiled").touch()
    assert [j.source.name for j in warm.pending([phong, ggx])] == ["ggx"]
    with warm.ahead([phong, ggx]) as given:  # one left: the caller needs it at once, no child
        assert given == 0


@pytest.mark.slow
def test_the_child_compiles_the_last_needed_kernels_first(compiled, monkeypatch, tmp_path):
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path))
    first, last = bn.load("phong"), bn.load("blinn-phong")
    with warm.ahead([first, last]) as given:
        assert given == 2
        deadline = time.monotonic() + 600
        while not drivers.kernels_compiled(_key(last)) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert drivers.kernels_compiled(_key(last))  # compiled by the child alone: nothing ran here
    # the caller then loads what the child wrote, and computes as ever
    result = bn.albedo(last, np.radians(30.0), method="quadrature", rtol=1e-9, backend="compiled")
    numpy = bn.albedo(last, np.radians(30.0), method="quadrature", rtol=1e-9, backend="numpy")
    assert abs(result.value[0] - numpy.value[0]) <= result.error[0] + numpy.error[0]


def _compiled_during(monkeypatch, tmp_path, config: StudyConfig) -> set[str]:
    """The shader keys whose kernels the report uses, and "microfacet" where it runs the microfacet route's."""
    from brdfnorm.engine.compiled import slopes

    monkeypatch.setattr(drivers, "_WARM", set())  # every key the report uses is warmed (loaded) again: recorded
    used = set()
    rectangle = slopes.microfacet_rectangle

    def recorded(*args, **kwargs):
        used.add("microfacet")
        return rectangle(*args, **kwargs)

    monkeypatch.setattr(slopes, "microfacet_rectangle", recorded)
    build_report(tmp_path / "report", config=config)
    return used | drivers._WARM


def _declared(needs) -> set[str]:
    out = set()
    for method, model in needs:
        if method in warm.ROUTE_KERNELS:
            out.add(method)
        elif model.native_kernel() is not None:
            out.add(_key(model))
    return out


def test_the_quick_report_declares_every_lobe_it_compiles(compiled, monkeypatch, tmp_path):
    declared = _declared(plan(config=StudyConfig.quick())[2])
    used = _compiled_during(monkeypatch, tmp_path, StudyConfig.quick())
    assert "microfacet" in used and len(used) > 1 and used <= declared


@pytest.mark.slow
def test_the_default_report_declares_every_lobe_it_compiles(compiled, monkeypatch, tmp_path):
    declared = _declared(plan()[2])
    used = _compiled_during(monkeypatch, tmp_path, StudyConfig())
    assert used <= declared and {"builtin:fon", "builtin:charlie", "microfacet"} <= used


def _job(name: str, method: str = "quadrature") -> warm.Job:
    return warm.Job(ModelSource("builtin", name), method)


def test_the_child_takes_the_route_first_then_the_lobes_in_order_from_the_second():
    a, b, c, d, e = (_job(n) for n in ("phong", "blinn-phong", "charlie", "fon", "ggx"))
    route = _job("ggx", "microfacet")
    assert warm.order([a, b, route, c, d, e]) == [route, b, c, d, e, a]
    assert warm.order([a, b, c]) == [c, b, a]  # no route: last-needed first


def test_a_route_is_pending_until_numba_caches_its_kernels(compiled, monkeypatch, tmp_path):
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path))
    needs = [("microfacet", bn.load("ggx")), ("microfacet", bn.load("beckmann")), ("quadrature", bn.load("phong"))]
    monkeypatch.setattr(warm, "route_compiled", lambda method: False)
    assert [(j.source.name, j.method) for j in warm.pending(needs)] == [("ggx", "microfacet"),
                                                                         ("phong", "quadrature")]
    monkeypatch.setattr(warm, "route_compiled", lambda method: True)
    assert [j.method for j in warm.pending(needs)] == ["quadrature"]


def test_a_lone_route_starts_the_child_with_it(compiled, monkeypatch, tmp_path):
    """The route is not needed at once, unlike a lone lobe: the child gets it (stdin: the jobs, in its order)."""
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(warm, "route_compiled", lambda method: False)
    monkeypatch.setattr(warm, "local_cores", lambda: 2)
    written = []

    class Child:
        def __init__(self, argv, **kwargs):
            self.stdin, self.pid = self, -1
            assert argv[1:] == ["-m", "brdfnorm.parallel.warm"]

        def write(self, data):
            written.append(__import__("json").loads(data))

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def poll(self):
            return 0

        def wait(self):
            return 0

    monkeypatch.setattr(warm.subprocess, "Popen", Child)
    with warm.ahead([("microfacet", bn.load("ggx"))]) as given:
        assert given == 1
    assert [(job["source"]["name"], job["method"]) for job in written[0]] == [("ggx", "microfacet")]


def test_every_route_has_its_kernels_and_its_run():
    import importlib

    assert warm.ROUTE_KERNELS.keys() == warm._ROUTE_RUNS.keys() == warm._ROUTE_MARKS.keys()
    for kernels in warm.ROUTE_KERNELS.values():
        for module, name in kernels:  # a renamed kernel fails here, not silently as "never cached"
            assert hasattr(getattr(importlib.import_module(f"brdfnorm.engine.compiled.{module}"), name), "_cache")


_ROUTE_CHECK = """
import sys, numpy as np, brdfnorm as bn
from brdfnorm.parallel import warm
from brdfnorm.parallel.job import ModelSource
from brdfnorm.engine.compiled import global_rule, slopes
from brdfnorm.lut import compute, grid_values
from brdfnorm.report import microfacet
if sys.argv[1] == "run":
    assert not warm.route_compiled("microfacet")
    warm._microfacet_route(bn.load("ggx"))
else:
    assert warm.route_compiled("microfacet")
    mu = grid_values(0.0, 1.0, microfacet.GRID, "texel")  # the report's table: loads, compiles nothing
    compute(bn.load("ggx"), {"mu": mu, "alpha": mu}, clamp={"mu": 1e-4, "alpha": 1e-8}, rtol=microfacet.RTOL,
            channels=["dfg"], grid="texel", backend="compiled")
    for kernel in (global_rule.fused_global, slopes.microfacet_grid):
        assert len(kernel.signatures) == 1 and not kernel.stats.cache_misses, kernel
"""


@pytest.mark.slow
def test_the_route_run_compiles_what_the_reports_tables_use(tmp_path):
    """On empty caches the child's run of the microfacet route compiles its kernels with the signatures the report's
    GGX table calls them with: that table, in a new process, then loads them and compiles nothing."""
    import os
    import subprocess
    import sys

    from helpers.paths import SRC

    env = dict(os.environ, BRDFNORM_CACHE_DIR=str(tmp_path / "kernels"), NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               BRDFNORM_BACKEND="compiled", PYTHONPATH=str(SRC))
    for stage in ("run", "check"):
        subprocess.run([sys.executable, "-c", _ROUTE_CHECK, stage], env=env, check=True, timeout=900)
