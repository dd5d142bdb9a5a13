"""Fixtures of the table tests."""

from __future__ import annotations

import pytest

import brdfnorm as bn
from brdfnorm import lut

#: The Blinn-Phong table's axes: μ from grazing to normal, exponents from broad to sharp.
BLINN_PHONG_MU = [0.05, 0.3, 0.7, 1.0]
BLINN_PHONG_N = [2.0, 30.0, 400.0]


@pytest.fixture(scope="session")
def bp_table() -> lut.Lut:
    """One small table with every channel kind (E, E_avg, the split-sum pair) over (μ, n), rtol 1e-9, shared by the
    layout and reader tests (computed once per process)."""
    return lut.compute(bn.load("blinn-phong"), {"mu": BLINN_PHONG_MU, "n": BLINN_PHONG_N}, rtol=1e-9,
                       channels=["dfg"])


@pytest.fixture(scope="module")
def ggx_shader():
    """examples/ggx.brdf at f0 = 1 (the E_avg tests' shader)."""
    from helpers.paths import EXAMPLES

    return bn.load(str(EXAMPLES / "ggx.brdf"), f0=1.0)
