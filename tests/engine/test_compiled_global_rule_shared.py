"""The kernels both fused global rules call (brdfnorm.engine.compiled.global_rule: _begin, _grown, _row, _summed,
_settle), compiled once per machine and shared by fused_global and shader_global: global_rule.shared_kernels
compiles them under one mark that a second process waits on, for the very signatures the two callers give them (a
fresh process with an empty Numba cache ends with one overload of each), and marks.in_cache tells a cached
signature from one never compiled."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers.paths import EXAMPLES
from numba import types

from brdfnorm.engine.compiled import global_rule, marks

SHARED = ("_begin", "_grown", "_row", "_summed", "_settle")


class _Kernel:
    """A stand-in for one shared kernel: no overloads, a compile that records who holds the mark, a cache path."""

    def __init__(self, name, directory, log):
        self.name, self.overloads, self.log = name, {}, log
        self._cache = type("Cache", (), {"_cache_path": str(directory)})()

    def compile(self, argtypes):
        mark = next(Path(self._cache._cache_path).glob("global_rule_shared-*.compiling"), None)
        self.log.append((self.name, mark.read_text() if mark is not None else None))
        self.overloads[argtypes] = True


def test_the_shared_kernels_compile_under_one_mark_another_process_waits_on(monkeypatch, tmp_path):
    log, waited = [], []
    for name in SHARED:
        monkeypatch.setattr(global_rule, name, _Kernel(name, tmp_path, log))
    monkeypatch.setattr(global_rule, "await_other", lambda mark: waited.append(mark) or 0.0)
    global_rule.shared_kernels()
    assert len(waited) == 1 and waited[0].parent == tmp_path
    # each compiled once, _settle last (its overloads say "done" to the next caller), all under this process's mark
    assert log == [(name, str(os.getpid())) for name in ("_begin", "_grown", "_row", "_summed", "_settle")]
    assert not waited[0].exists()
    global_rule.shared_kernels()  # compiled in this process: neither waits nor compiles
    assert len(waited) == 1 and len(log) == len(SHARED)


def test_in_cache_tells_a_cached_signature_from_one_never_compiled():
    global_rule.shared_kernels()  # compiled, or loaded, into the tests' cache
    argtypes = next(iter(global_rule._settle.overloads))
    assert marks.in_cache(global_rule._settle, argtypes)
    assert not marks.in_cache(global_rule._begin, (types.float32,))
    assert not marks.in_cache(object(), argtypes)  # no Numba cache: "not cached"


@pytest.mark.slow
def test_both_global_rules_call_the_shared_kernels_as_compiled(tmp_path):
    # a new process, both caches empty: after the microfacet route's and a shader's fused rule, each shared kernel
    # has the one overload shared_kernels compiled (a caller typing it otherwise would have compiled a second)
    code = ("import numpy as np, brdfnorm as bn\n"
            "from brdfnorm.engine.compiled import global_rule\n"
            "from brdfnorm.parallel.warm import _microfacet_route\n"
            "_microfacet_route(bn.load('ggx'))\n"
            f"m = bn.load({str(EXAMPLES / 'ggx.brdf')!r}, roughness=np.array([0.2, 0.7]), f0=0.5)\n"
            "bn.albedo(m, np.arccos([0.05, 0.6])[:, None], method='quadrature', backend='compiled')\n"
            f"print(*(len(getattr(global_rule, n).overloads) for n in {SHARED!r}),\n"
            "      len(global_rule.fused_global.overloads), len(global_rule.shader_global.overloads))\n")
    env = {**os.environ, "BRDFNORM_CACHE_DIR": str(tmp_path / "kernels"), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["1"] * (len(SHARED) + 2), out


@pytest.mark.parametrize("kind, width, linear", [(0, 0.0, True), (1, 0.0, False), (2, 0.3, False)])
def test_the_azimuth_row_is_the_slope_maps_own_functions(kind, width, linear):
    # _row (a kernel of its own since the fused loop was split) against the functions it gathers, called one by one
    from brdfnorm.engine.compiled.slopes import SLOPE_MAP, azimuth_node, piece_extent

    geometry = tuple(np.array([0.0, value]) for value in (0.6, 0.9, 0.1, 0.2, 0.3, 0.35, 0.05, 0.4, 2.0, 1.0))
    assert len(geometry) == len(SLOPE_MAP)
    row = global_rule._row(3, 16, kind, 0.7, width, 2.0, linear, True, False, tuple(g[1] for g in geometry))
    phi, dphi = global_rule._azimuth(3 * (2 * np.pi / 16), 0.7, width)
    vz, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity = (g[1] for g in geometry)
    dx, dy, d2, p, q_minus_p, s_h, s_split, s_middle, s_end, azimuth = azimuth_node(
        phi, linear, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity, vz, False)
    extent = piece_extent(kind, s_middle, s_split, s_end, True, False)
    assert row == (dphi * 2.0, dx, dy, d2, p, q_minus_p, s_h, s_split, s_end, azimuth, *extent)
    assert all(np.isfinite(row)) and row[0] > 0
