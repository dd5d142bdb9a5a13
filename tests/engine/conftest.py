"""Fixtures the engine's route tests share: the half-vector global rule alone, and a spy on the generic
half-vector route."""

import numpy as np
import pytest

from brdfnorm.engine.machinery.result import RouteResult
from brdfnorm.engine.routes import halfvector, halfvector_generic


@pytest.fixture
def global_only(monkeypatch):
    """Replace the adaptive panels by a stand-in that leaves every case it gets unconverged (NaN)."""
    def no_panels(integrand, initial, K, **_):
        return RouteResult(np.full((K, 1), np.nan), np.full((K, 1), np.inf), np.zeros(K, dtype=np.int64),
                           np.zeros(K, dtype=bool))

    monkeypatch.setattr(halfvector, "adaptive_rectangles", no_panels)


@pytest.fixture
def kept(monkeypatch):
    """The cases the route kept, per call of the engine."""
    calls = []
    original = halfvector_generic.route

    def spy(*args, **kwargs):
        out = original(*args, **kwargs)
        calls.append(out.converged)
        return out

    monkeypatch.setattr(halfvector_generic, "route", spy)
    return calls
