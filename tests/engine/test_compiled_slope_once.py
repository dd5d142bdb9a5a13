"""One compile of the ``.brdf`` shaders' half-vector rectangle integrand (brdfnorm.engine.compiled.slopes.shader_grid)
for every shader: the shader is a first-class function argument (padded to global_rule.PADDED outputs, as for the
fused global rule), so two different shaders, of one and of three channels, run the same compiled entry point (one
signature, one cache entry) and the kernels' per-shader copies hold no rectangle kernel; the values equal the numpy
backend's within the estimates; the compile is held under a mark beside Numba's cache of the kernel, which a second
process waits on rather than compiling the same signature beside it."""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.compiled import drivers, global_rule, marks, slopes

pytest.importorskip("numba")


@pytest.fixture
def entries(monkeypatch):
    """(shader outputs, the argument types other than the shader's, the compiled entry point) of every
    shader_grid_kernel call while the fixture is live."""
    kernel, seen = slopes.shader_grid_kernel, []

    def spy(arguments, shader, outputs):
        import numba

        entry = kernel(arguments, shader, outputs)
        seen.append((outputs, tuple(numba.typeof(a) for i, a in enumerate(arguments) if i != shader), entry))
        return entry

    monkeypatch.setattr(slopes, "shader_grid_kernel", spy)
    return seen


def test_two_shaders_share_one_compiled_rectangle_kernel(entries):
    theta = np.arccos([0.02, 0.3, 0.9])
    results, first = {}, {}
    for name in ("phong", "charlie"):  # one channel (padded), three channels (the shader itself)
        model = bn.load(name)
        kernel = model.native_kernel()
        assert kernel.channels == {"phong": 1, "charlie": 3}[name]
        assert not hasattr(drivers.kernels_for(kernel), "slope_grid")  # no per-shader copy of the rectangle
        before = len(entries)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            results[name] = [bn.albedo(model, theta, method="quadrature", rtol=1e-9, backend=backend)
                             for backend in ("compiled", "numpy")]
        assert len(entries) > before  # the half-vector route's rectangles ran through the package kernel
        first[name] = entries[before]
    assert {outputs for outputs, _, _ in entries} == {global_rule.PADDED}
    assert len({types for _, types, _ in entries}) == 1
    assert first["phong"][2] is first["charlie"][2]  # the same machine code for both shaders
    assert first["phong"][1] + (global_rule.PADDED,) in {
        tuple(t for i, t in enumerate(argtypes) if i != len(argtypes) - 3) + (global_rule.PADDED,)
        for argtypes in slopes.shader_grid.overloads}
    for compiled, numpy in results.values():
        assert compiled.value.shape == numpy.value.shape  # (the padding's channels dropped)
        assert np.all(compiled.converged) and np.all(numpy.converged)
        assert np.all(np.abs(compiled.value - numpy.value) <= compiled.error + numpy.error)


class _Kernel:
    """A stand-in for shader_grid: its overloads, a compile that records who holds the marks, a cache path."""

    def __init__(self, directory):
        self.directory, self.overloads, self.compiled = directory, {}, []
        self._cache = type("Cache", (), {"_cache_path": str(directory)})()

    def compile(self, argtypes):
        self.compiled.append([mark.read_text() for mark in self.directory.glob("shader_grid-*.compiling")])
        self.overloads[argtypes] = type("Result", (), {"entry_point": "entry"})()


def test_the_compile_is_held_under_a_mark_another_process_waits_on(monkeypatch, tmp_path):
    stand_in, waited = _Kernel(tmp_path), []
    monkeypatch.setattr(slopes, "shader_grid", stand_in)
    monkeypatch.setattr(marks, "await_other", lambda mark: waited.append(mark) or 0.0)
    arguments = [np.zeros(2), np.zeros(2, dtype=np.int64), None]
    assert slopes.shader_grid_kernel(arguments, 2, 3) == "entry"
    assert len(waited) == 1 and waited[0].parent == tmp_path  # waited for another holder before compiling
    assert stand_in.compiled == [[str(os.getpid())]] and not waited[0].exists()  # held while compiling, let go
    assert slopes.shader_grid_kernel(arguments, 2, 3) == "entry"  # compiled: neither waits nor compiles
    assert len(waited) == 1 and len(stand_in.compiled) == 1
    slopes.shader_grid_kernel(arguments, 2, 4)  # another signature, another mark
    assert len(set(waited)) == 2 and len(stand_in.compiled) == 2


def test_no_mark_where_numba_caches_nothing(monkeypatch, tmp_path):
    stand_in = _Kernel(tmp_path)
    stand_in._cache = object()
    monkeypatch.setattr(slopes, "shader_grid", stand_in)
    monkeypatch.setattr(marks, "await_other", lambda mark: pytest.fail("no mark to wait on"))
    assert slopes.shader_grid_kernel([np.zeros(2), None], 1, 3) == "entry"
    assert stand_in.compiled == [[]]
