"""The engine's results are those recorded before it moved into :mod:`brdfnorm.engine` (issue 32), bit for bit:
values, error estimates, evaluation counts, convergence, reasons and methods over every route (tests/engine_grid.py
says which cases and how the fixture was made)."""

from __future__ import annotations

import json

import pytest
from engine_grid import FIXTURE, compute


def test_every_route_reproduces_the_recorded_grid_bit_for_bit():
    pytest.importorskip("flint", reason="python-flint (the certified extra) is not installed")
    recorded = json.loads(FIXTURE.read_text(encoding="utf-8"))
    computed = json.loads(json.dumps(compute()))  # the same JSON normalization the recording went through
    assert computed.keys() == recorded.keys()
    for label, record in recorded.items():
        assert computed[label] == record, label
