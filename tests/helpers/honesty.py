"""What the honesty tests share: both backends as a parameter, and a case's true error over its estimate, the
generic engine's `.brdf` GGX against the one-dimensional integral of the built-in lobe (no code in common)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import brdfnorm as bn

from .paths import EXAMPLES

#: Both backends: each carries its own copy of the rules these tests guard.
BACKENDS = pytest.mark.parametrize("backend", ["numpy", "compiled"])


def honesty_ratio(model, theta: float, exact: float, rtol: float, backend: str = "numpy") -> float:
    """|E − exact| / the estimate of brdfnorm's quadrature albedo E of ``model`` at one view (≤ 1: honest)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(model, np.atleast_1d(theta), method="quadrature", backend=backend, rtol=rtol)
    return float(np.abs(result.value[0, 0] - exact) / result.error[0, 0])


def assert_generic_ggx_covers_azimuthal(roughness: np.ndarray, theta: np.ndarray, phi: np.ndarray,
                                        rtol: float) -> None:
    """examples/ggx.brdf with F = 1 (GGX with separable Smith shadowing) at the views (θ, φ): every estimate covers
    its error against the built-in lobe's azimuthal integral at rtol 1e-12, and is within ``rtol``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(bn.load(str(EXAMPLES / "ggx.brdf"), roughness=roughness, f0=1.0), theta, phi=phi,
                           rtol=rtol)
    reference = bn.albedo(bn.load("ggx", alpha=roughness**2, shadowing="separable"), theta, rtol=1e-12)
    assert reference.method == "azimuthal"
    error = np.abs(result.value[:, 0] - reference.value.ravel())
    assert np.all(error <= result.error[:, 0] + reference.error.ravel()), (error / result.error[:, 0]).max()
    assert np.all(result.error[:, 0] <= rtol * result.value[:, 0])
