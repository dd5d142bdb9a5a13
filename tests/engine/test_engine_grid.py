"""The engine's results are those recorded before it moved into :mod:`brdfnorm.engine` (issue 32), bit for bit: values,
error estimates, evaluation counts, convergence, reasons and methods over every route (tests/helpers/engine_grid.py says
which cases and how the fixture was made) — under the numpy backend, the reference. Under the compiled backend (issue
39) the sums run in another order: every value must then lie within the recorded and the new error estimates of the
recorded one, with the same methods and convergence."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers.engine_grid import FIXTURE, compute


def _recorded() -> dict:
    pytest.importorskip("flint", reason="python-flint (the certified extra) is not installed")
    return json.loads(FIXTURE.read_text(encoding="utf-8"))


def test_every_route_reproduces_the_recorded_grid_bit_for_bit(monkeypatch):
    recorded = _recorded()
    monkeypatch.setenv("BRDFNORM_BACKEND", "numpy")
    computed = json.loads(json.dumps(compute()))  # the same JSON normalization the recording went through
    assert computed.keys() == recorded.keys()
    for label, record in recorded.items():
        assert computed[label] == record, label


def _floats(values: list) -> np.ndarray:
    return np.array([float.fromhex(v) for v in values])


def test_the_compiled_backend_agrees_with_the_recorded_grid_within_the_estimates(monkeypatch):
    pytest.importorskip("numba")
    recorded = _recorded()
    monkeypatch.setenv("BRDFNORM_BACKEND", "compiled")
    computed = json.loads(json.dumps(compute()))
    assert computed.keys() == recorded.keys()
    pairs = (("value", "error"), ("reflected", None), ("transmitted", None), ("E", "E_error"),
             ("E_avg", "E_avg_error"), ("1-E", "E_error"))
    for label, record in recorded.items():
        new = computed[label]
        assert new.keys() == record.keys(), label
        for key in ("method", "converged", "reason", "lower", "upper", "E_avg_converged", "converged_mask"):
            assert new.get(key) == record.get(key), (label, key)
        for key, error in pairs:
            if key not in record:
                continue
            # a part of a BSDF's albedo shares its total's estimate
            bound = _floats(record[error or "error"]) + _floats(new[error or "error"])
            difference = np.abs(_floats(new[key]) - _floats(record[key]))
            assert np.all(difference <= bound), (label, key, difference.max(), bound.min())
