"""brdfnorm.parallel.warm's child (warm._compile) skips a lobe whose mark another live process holds (the command
compiling it now: brdfnorm.engine.compiled.drivers.native_integrand), and compiles one nobody holds; likewise a
route's kernels (the microfacet route's mark: brdfnorm.engine.compiled.global_rule.route_mark), which it compiles
under that mark where nobody holds it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import brdfnorm as bn
from brdfnorm.engine import methods
from brdfnorm.engine.compiled import drivers
from brdfnorm.parallel import warm
from brdfnorm.parallel.job import ModelSource

pytest.importorskip("numba")


@pytest.fixture
def albedos(monkeypatch, tmp_path):
    """The models the child computes its one albedo of (the compile stood in for), with an empty kernel cache."""
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("BRDFNORM_BACKEND", "compiled")
    seen = []
    monkeypatch.setattr(methods, "albedo", lambda model, *args, **kwargs: seen.append(model.name))
    return seen


def _job(name: str, method: str = "quadrature") -> dict:
    return warm.Job(ModelSource("builtin", name), method).to_json()


def _held(mark: Path) -> subprocess.Popen:
    """A live process holding ``mark`` (kill it after)."""
    script = (f"import time; from pathlib import Path; from brdfnorm.engine.compiled import marks\n"
              f"with marks.holding(Path({str(mark)!r})):\n    print('held', flush=True); time.sleep(60)")
    holder = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "held"
    return holder


def test_the_child_skips_a_lobe_another_process_is_compiling(albedos):
    mark = drivers.compiling_mark(bn.load("phong").native_kernel().key)
    holder = _held(mark)
    try:
        warm._compile([_job("phong"), _job("blinn-phong")])
    finally:
        holder.kill()
        holder.wait(timeout=60)
    assert albedos == ["blinn-phong"]
    assert Path(mark).read_text() == str(holder.pid)  # (not the child's to remove)


@pytest.fixture
def route(monkeypatch, tmp_path):
    """The microfacet route's run stood in for (records the route mark's holder), its mark in ``tmp_path``."""
    mark, runs = tmp_path / "microfacet-route.compiling", []
    monkeypatch.setattr(warm, "_ROUTE_MARKS", {"microfacet": lambda: mark})
    monkeypatch.setattr(warm, "_ROUTE_RUNS", {"microfacet": lambda model: runs.append(mark.read_text())})
    monkeypatch.setattr(warm, "route_compiled", lambda method: False)
    return mark, runs


def test_the_child_compiles_a_route_under_its_mark_and_skips_it_where_held(route):
    mark, runs = route
    warm._compile([_job("ggx", "microfacet")])
    assert runs == [str(__import__("os").getpid())] and not mark.exists()
    holder = _held(mark)
    try:
        warm._compile([_job("ggx", "microfacet")])
    finally:
        holder.kill()
        holder.wait(timeout=60)
    assert len(runs) == 1
