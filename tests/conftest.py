"""Fixtures every test folder shares (the kernel cache, the hypothesis profile, ``run_cli``, ``rng``, ...). Plain
reference mathematics lives in the ``helpers`` package (``from helpers.references import ...``)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

# Compiled kernels (brdfnorm.engine.compiled, brdfnorm.glsl.native) are cached on disk: tests and the commands they
# run use a directory of the checkout's own (.test-cache/, ignored by git), never the user's ~/.cache/brdfnorm. It
# is shared by the xdist workers and kept between runs, so each lobe's kernels are compiled once per checkout, not
# once per worker and run (the cache keys cover the generated source and brdfnorm's and Numba's versions).
_CACHE = Path(__file__).resolve().parent.parent / ".test-cache"
os.environ["BRDFNORM_CACHE_DIR"] = str(_CACHE)

# CI runs the property tests on a fixed example sequence, so a verdict there is reproducible; locally they
# keep exploring new inputs on every run.
settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI"):
    settings.load_profile("ci")


@pytest.fixture
def run_cli(capsys):
    """``run_cli(*argv)``: the brdfnorm command line run in-process, as (exit code, stdout, stderr)."""
    from brdfnorm.cli import main

    def run(*argv: str) -> tuple[int, str, str]:
        try:
            main(list(argv))
            code = 0
        except SystemExit as done:
            code = done.code or 0
        out, err = capsys.readouterr()
        return code, out, err

    return run


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


@pytest.fixture
def lobe_aligned_only(monkeypatch):
    """The generic engine without its half-vector route (brdfnorm.engine.routes.halfvector_generic), for tests of the
    lobe-aligned routes behind it."""
    from brdfnorm.engine.machinery.result import RouteResult
    from brdfnorm.engine.routes import halfvector_generic

    def nothing_kept(fixed, *args, **kwargs):
        K = fixed.shape[0]
        return RouteResult(np.zeros((K, 1)), np.zeros((K, 1)), np.zeros(K, dtype=np.int64), np.zeros(K, dtype=bool))

    monkeypatch.setattr(halfvector_generic, "route", nothing_kept)
