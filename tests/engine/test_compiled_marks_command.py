"""The command's side of the compiling marks (brdfnorm.engine.compiled.drivers.native_integrand): where a lobe's
kernels are not compiled yet, the process compiling them holds the lobe's mark while it does (so that
brdfnorm.parallel.warm's child skips that lobe instead of compiling it beside it) and lets go after; where they are
compiled, no mark is written."""

from __future__ import annotations

import os

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.compiled import drivers

pytest.importorskip("numba")


@pytest.fixture
def recorded(monkeypatch, tmp_path):
    """native_integrand(kernel) with the kernels' compile stood in for: returns what the mark held during it."""
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(drivers, "_WARM", set())
    held = []

    class Native:
        def __init__(self, kernel, *args):
            self.kernel = kernel

        def __call__(self, *args):
            return None

    def warm(native, key):
        mark = drivers.compiling_mark(key)
        held.append(mark.read_text() if mark.exists() else None)

    monkeypatch.setattr(drivers, "NativeIntegrand", Native)
    monkeypatch.setattr(drivers, "_warm", warm)

    def run(kernel):
        drivers.native_integrand(kernel, np.zeros((1, 3)), [np.zeros(1)], True)
        return held[-1]

    return run


def test_the_command_holds_the_mark_while_it_compiles_a_lobe(recorded):
    kernel = bn.load("phong").native_kernel()
    assert recorded(kernel) == str(os.getpid())
    assert not drivers.compiling_mark(kernel.key).exists()


def test_no_mark_where_the_lobe_is_compiled(recorded):
    kernel = bn.load("blinn-phong").native_kernel()
    drivers.kernels_file(kernel.key, __import__("numba").__version__).with_suffix(".compiled").touch()
    assert recorded(kernel) is None
