"""One compile of the shaders' fused global rule (brdfnorm.engine.compiled.global_rule.shader_global) for one, two
and three channels, and the mark its compile is held under: a shader of fewer than global_rule.PADDED channels is
called through its kernels' copy's ``padded_shader`` (its outputs, then zeros), so that a scalar built-in lobe and a
three-channel one take the same kernel signature (a fresh machine's report needs both: one compile, not two), and
the padded lobe's values equal the numpy backend's within the estimates; a process compiling the kernel holds a mark
beside Numba's cache of it, and a second process waits for it rather than compiling the same signature beside it;
likewise the microfacet route's fused_global at its first call in a process (global_rule.route_mark); within
global_rule.shader_rule_left_to_others (brdfnorm.parallel.warm's child) the kernel is loaded where cached, never
compiled."""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.compiled import drivers, global_rule, marks

pytest.importorskip("numba")


@pytest.fixture
def signatures(monkeypatch):
    """The argument types of every shader_kernel call (the kernel's signature) while the fixture is live."""
    kernel, seen = global_rule.shader_kernel, []

    def spy(arguments, shader, outputs):
        import numba

        seen.append(tuple(numba.typeof(a) for i, a in enumerate(arguments) if i != shader) + (outputs,))
        return kernel(arguments, shader, outputs)

    monkeypatch.setattr(global_rule, "shader_kernel", spy)
    return seen


def test_one_and_three_channel_lobes_take_one_kernel_signature(signatures):
    theta = np.arccos([0.02, 0.3, 0.9])
    results = {}
    for name in ("phong", "charlie"):  # one channel (padded), three channels (the shader itself)
        model = bn.load(name)
        assert model.native_kernel().channels == {"phong": 1, "charlie": 3}[name]
        before = len(signatures)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            results[name] = [bn.albedo(model, theta, method="quadrature", rtol=1e-9, backend=backend)
                             for backend in ("compiled", "numpy")]
        assert len(signatures) > before  # the half-vector route's fused rule ran
    assert len(set(signatures)) == 1 and signatures[0][-1] == global_rule.PADDED
    for compiled, numpy in results.values():
        assert compiled.value.shape == numpy.value.shape  # (the padding's channels dropped)
        assert np.all(np.abs(compiled.value - numpy.value) <= compiled.error + numpy.error)


def test_the_padded_shader_is_the_shaders_outputs_then_zeros():
    point = (0.3, -0.2, 0.93, -0.1, 0.4, 0.91)
    for name in ("phong", "charlie"):
        model = bn.load(name)
        kernel = model.native_kernel()
        module = drivers.kernels_for(kernel)
        u = np.ascontiguousarray(kernel.pack(model.params), dtype=float).ravel()
        own, padded = module.shader(*point, u), module.padded_shader(*point, u)
        assert len(padded) == global_rule.PADDED
        assert padded[:len(own)] == tuple(own) and all(x == 0.0 for x in padded[len(own):])


class _Kernel:
    """A stand-in for shader_global: its overloads, a compile that records who holds the mark, a cache path."""

    def __init__(self, directory, cached=None):
        self.overloads, self.compiled, self.targetctx = {}, [], None
        self._cache = type("Cache", (), {"_cache_path": str(directory),
                                         "load_overload": lambda self, argtypes, context: cached})()

    def compile(self, argtypes):
        mark = global_rule.compile_mark(argtypes)
        self.compiled.append(mark.read_text())
        self.overloads[argtypes] = type("Result", (), {"entry_point": "entry"})()


def test_the_compile_is_held_under_a_mark_another_process_waits_on(monkeypatch, tmp_path):
    stand_in, waited = _Kernel(tmp_path), []
    monkeypatch.setattr(global_rule, "shader_global", stand_in)
    monkeypatch.setattr(marks, "await_other", lambda mark: waited.append(mark) or 0.0)
    arguments = [np.zeros(2), np.zeros(2, dtype=np.int64), None]
    assert global_rule.shader_kernel(arguments, 2, 3) == "entry"
    one = global_rule.compile_mark(next(iter(stand_in.overloads)))
    assert one.parent == tmp_path and waited == [one]  # waited for another holder before compiling
    assert stand_in.compiled == [str(os.getpid())] and not one.exists()  # held while compiling, then let go
    assert global_rule.shader_kernel(arguments, 2, 3) == "entry"  # compiled: neither waits nor compiles
    assert waited == [one] and len(stand_in.compiled) == 1
    global_rule.shader_kernel(arguments, 2, 1)  # another signature, another mark
    assert len(set(waited)) == 2


def test_no_mark_where_numba_caches_nothing(monkeypatch, tmp_path):
    stand_in = _Kernel(tmp_path)
    del stand_in._cache
    stand_in._cache = object()
    monkeypatch.setattr(global_rule, "shader_global", stand_in)
    assert global_rule.compile_mark((1,)) is None


class _Route:
    """A stand-in for fused_global: no overloads until called, a call that records the route mark's holder."""

    def __init__(self, directory):
        self.overloads, self.held = {}, []
        self._cache = type("Cache", (), {"_cache_path": str(directory)})()

    def __call__(self, *every):
        mark = global_rule.route_mark()
        self.held.append(mark.read_text() if mark.exists() else None)
        self.overloads["compiled"] = True


def test_the_first_microfacet_call_waits_for_and_holds_the_route_mark(monkeypatch, tmp_path):
    stand_in, waited = _Route(tmp_path), []
    monkeypatch.setattr(global_rule, "fused_global", stand_in)
    monkeypatch.setattr(global_rule, "await_other", lambda mark: waited.append(mark) or 0.0)
    one = np.zeros(1, dtype=np.int64)
    call = (one, np.ones(1), np.zeros(1), np.zeros(1, dtype=bool), np.ones(1), np.ones(1), np.ones(1), 120, 0,
            ("microfacet", 1, ()))
    global_rule.integrate(*call)
    mark = global_rule.route_mark()
    assert mark.parent == tmp_path and waited == [mark] and stand_in.held == [str(os.getpid())]
    assert not mark.exists()
    global_rule.integrate(*call)  # compiled in this process: neither waits nor marks
    assert waited == [mark] and stand_in.held == [str(os.getpid()), None]


def test_the_child_loads_the_shaders_rule_but_leaves_its_compile_to_the_command(monkeypatch, tmp_path):
    from numba.core.errors import NumbaError

    arguments = [np.zeros(2), np.zeros(2, dtype=np.int64), None]
    for cached, compiles in ((None, 0), ("a cached result", 1)):
        stand_in = _Kernel(tmp_path, cached)
        monkeypatch.setattr(global_rule, "shader_global", stand_in)
        with global_rule.shader_rule_left_to_others():
            if compiles:
                assert global_rule.shader_kernel(arguments, 2, 3) == "entry"
            else:
                with pytest.raises(NumbaError):
                    global_rule.shader_kernel(arguments, 2, 3)
        assert len(stand_in.compiled) == compiles
    assert global_rule.shader_kernel(arguments, 2, 1) == "entry"  # outside the block: compiled as ever
