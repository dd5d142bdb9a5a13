"""A model that evaluates in float32 declares ``epsilon`` and the hemisphere quadrature stays honest (issue 34).

The model here is Blinn-Phong computed in float32 by numpy — the worst case for rounding, a lobe written in the
cosine of the half vector, whose float32 staircase near the peak is as wide as the lobe at n ≳ 1e5 — checked
against the float64 built-in (seed 002's series route) at rtol below float32's reach. Independent of Mitsuba.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.check import default_tolerance
from brdfnorm.models.blinn_phong import BlinnPhong


class BlinnPhong32(BlinnPhong):
    name = "blinn-phong-float32"
    epsilon = 2.0**-24

    def evaluate(self, L, V, params):
        S = L.astype(np.float32) + V.astype(np.float32)
        cosine = np.clip(S[..., 2] / np.sqrt(np.einsum("...i,...i->...", S, S)), 0, 1).astype(np.float32)
        return np.power(cosine, np.asarray(params["n"], dtype=np.float32)).astype(np.float64)[..., None]

    def closed_form_albedo(self, fixed, params, over):
        return np.full(np.shape(fixed)[:-1] + (1,), np.nan)


@pytest.mark.parametrize("n", [10.0, 100.0, 1e3, 1e5])
def test_float32_estimates_cover_the_error(n):
    """estimate ≥ |value − exact| (measured ratio ≥ 2.4, at n = 100, normal incidence), and an rtol below float32's
    reach ends 'rounding-limited' rather than a false 'converged'."""
    theta = np.arccos([0.02, 0.5, 1.0])
    exact = bn.albedo(bn.load("blinn-phong", n=n), theta, rtol=1e-12).value[:, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = bn.albedo(BlinnPhong32(n=n), theta, rtol=1e-8, method="quadrature")
    assert np.all(r.error[:, 0] >= np.abs(r.value[:, 0] - exact))
    assert not r.converged.any() and set(r.reason) == {"rounding-limited"}


def test_float64_models_keep_their_floor():
    """Models without ``epsilon`` are integrated as before (the float64 floor), and checked at 1e-6."""
    r = bn.albedo(bn.load("blinn-phong", n=100.0), np.arccos([0.5]), rtol=1e-10, method="quadrature")
    assert r.converged.all()
    assert default_tolerance(bn.load("blinn-phong")) == 1e-6
    assert default_tolerance(BlinnPhong32()) == 256 * 2.0**-24
