"""Kernels compiled ahead on a second core (:mod:`brdfnorm.parallel.warm`): the child compiles the models' kernels
into the disk cache, last-needed first, with nothing computed by the caller; nothing is started where there is
nothing to gain; and the report declares every lobe it compiles."""

from __future__ import annotations

import time

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.compiled import drivers
from brdfnorm.parallel import warm
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
    sources = warm.pending([phong, bn.load("phong", n=50.0), ggx])
    assert [s.name for s in sources] == ["phong", "ggx"]  # one per kernel key, in the order given
    drivers.kernels_file(_key(phong), __import__("numba").__version__).with_suffix(".compiled").touch()
    assert [s.name for s in warm.pending([phong, ggx])] == ["ggx"]
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
    monkeypatch.setattr(drivers, "_WARM", set())  # every key the report uses is warmed (loaded) again: recorded
    build_report(tmp_path / "report", config=config)
    return set(drivers._WARM)


def test_the_quick_report_declares_every_lobe_it_compiles(compiled, monkeypatch, tmp_path):
    declared = {_key(m) for m in plan(config=StudyConfig.quick())[2] if m.native_kernel() is not None}
    used = _compiled_during(monkeypatch, tmp_path, StudyConfig.quick())
    assert used and used <= declared


@pytest.mark.slow
def test_the_default_report_declares_every_lobe_it_compiles(compiled, monkeypatch, tmp_path):
    declared = {_key(m) for m in plan()[2] if m.native_kernel() is not None}
    used = _compiled_during(monkeypatch, tmp_path, StudyConfig())
    assert used <= declared and {"builtin:fon", "builtin:charlie"} <= used
