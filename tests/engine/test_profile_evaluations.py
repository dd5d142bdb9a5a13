"""benchmarks/profile_evaluations.py: the per-view profile of the global rule adds up to what the call reports.

The profile observes the driver through three patched internals; if any moved, or the driver's levels stopped
being nested, these checks fail: the final grids plus one probe cost per view are the reported evaluations, the
last level's estimate is the reported error, each level follows from the one before by the recorded doubling,
and the oracle (estimates replaced by true errors) reaches the tolerance with no more evaluations.
"""

from __future__ import annotations

import importlib.util
import math
import sys

import numpy as np
import pytest
from helpers.paths import REPO

BENCH = REPO / "benchmarks"


def _load(name: str):
    """A module of benchmarks/ by its file (registered under a private name: its dataclasses look it up)."""
    spec = importlib.util.spec_from_file_location(f"_bench_{name}", BENCH / f"{name}.py")
    loaded = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = loaded
    spec.loader.exec_module(loaded)
    return loaded


@pytest.fixture(scope="module")
def module():
    return _load("profile_evaluations")


@pytest.fixture(scope="module")
def peers():
    return _load("peers")


N, RTOL = 100.0, 1e-9
THETA = np.radians([10.0, 40.0, 55.0, 85.0])


def test_profile_adds_up(module, peers):
    truth = np.array([peers.blinn_phong_reference(N, t) for t in THETA])
    p = module.profile(N, THETA, RTOL, truth=truth)
    fixed = set()
    for k, levels in enumerate(p["levels"]):
        assert levels, k
        for before, after in zip(levels, levels[1:], strict=False):
            doubled_b, doubled_u = "β" in before["next"], "u" in before["next"]
            assert after["M"] == before["M"] * (2 if doubled_b else 1)
            assert after["N"] == (2 * before["N"] + 1 if doubled_u else before["N"])
        last = levels[-1]
        fixed.add(int(p["evaluations"][k]) - last["M"] * last["N"] - last["check"])
        assert math.isclose(last["estimate"], p["error"][k], rel_tol=1e-12)
        assert math.isclose(last["true"], abs(p["value"][k] - truth[k]), rel_tol=1e-9, abs_tol=1e-18)
        assert last["true"] <= last["estimate"]
    assert len(fixed) == 1 and fixed.pop() > 0  # the same per-call probes for every view


def test_oracle_reaches_the_tolerance_with_fewer(module, peers):
    truth = np.array([peers.blinn_phong_reference(N, t) for t in THETA])
    real = module.profile(N, THETA, RTOL, truth=truth)
    oracle = module.profile(N, THETA, RTOL, truth=truth, oracle=True)
    assert np.all(np.abs(oracle["value"] - truth) <= RTOL * truth)
    assert np.all(oracle["evaluations"] <= real["evaluations"])
    assert oracle["evaluations"].sum() < real["evaluations"].sum()
    with pytest.raises(ValueError, match="truth"):
        module.profile(N, THETA, RTOL, oracle=True)
