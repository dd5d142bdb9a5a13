"""The E_avg probe (benchmarks/probe_certified_average.py, issue 33): its fixed-endpoint inner integral against the
shipped certified E route, its continuation to a complex ball, and (slow) its E_avg against the float64 table."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from helpers.paths import REPO

flint = pytest.importorskip("flint")
sys.path.insert(0, str(REPO / "benchmarks"))

import probe_certified_average as probe  # noqa: E402

import brdfnorm as bn  # noqa: E402
from brdfnorm import lut  # noqa: E402
from brdfnorm.engine.routes import certified  # noqa: E402


@pytest.fixture
def prec():
    old, flint.ctx.prec = flint.ctx.prec, 100
    yield 100
    flint.ctx.prec = old


@pytest.mark.parametrize("alpha", [1.0, 0.3, 1e-4])
@pytest.mark.parametrize("shadowing", ["height-correlated", "separable"])
def test_inner_is_mu_times_certified_e(prec, alpha, shadowing):
    theta = 0.7
    inner = probe.inner(flint.acb(theta), flint.arb(alpha), shadowing == "height-correlated", prec, [0], 200_000)
    (e,) = certified.enclose(bn.load("ggx", shadowing=shadowing), theta, {"alpha": alpha, "shadowing": shadowing},
                             digits=15)
    mu_e = flint.arb(theta).cos() * e.ball
    assert inner.real.overlaps(mu_e) and inner.imag.contains(0)
    assert float(inner.real.rad()) < 1e-15 and float(mu_e.rad()) < 1e-14


def test_inner_on_a_complex_ball_encloses_its_centre(prec):
    alpha = flint.arb(1.0)
    centre = probe.inner(flint.acb(0.7), alpha, True, prec, [0], 200_000)
    ball = probe.inner(flint.acb(flint.arb(0.7, 1e-4), flint.arb(0, 1e-4)), alpha, True, prec, [0], 20_000)
    assert ball.is_finite() and ball.contains(centre)
    wide = probe.inner(flint.acb(flint.arb(0.7, 1e-2), flint.arb(0, 1e-2)), alpha, True, prec, [0], 2_000)
    assert not wide.is_finite()  # the blow-up the probe measures: such a ball gives no bound


@pytest.mark.slow
def test_probe_average_contains_the_float64_table():
    ball, _, _ = probe.average(1.0, 3, 4e-3)
    table = lut.compute(bn.load("ggx"), {"mu": np.linspace(0, 1, 4), "alpha": [1.0]}, clamp={"mu": 1e-4},
                           rtol=1e-10)
    value, error = float(table["E_avg"][0]), float(table["E_avg_error"][0])
    assert ball.lower() - error <= value <= ball.upper() + error
    assert float(ball.rad()) < 1e-6
