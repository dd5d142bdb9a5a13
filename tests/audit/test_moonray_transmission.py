"""MoonRay's ``TransmissionAlbedo.h`` (the R + T of its Cook–Torrance glass over η, roughness, cos θ), a 5×5×5 excerpt
of each of ``mE`` (entering) and ``mEExit`` (exiting) in ``tests/fixtures/engines/`` (see the README there), audited
end to end from the file in the layout MoonRay's accessor reads (η = 1.05 + 2t: ``--as f0=eta-moonray``).

The findings, each checked against the independent facet-normal quadrature of ``tests/helpers/dielectric_reference.py``:
the closest convention is Beckmann with separable Smith shadowing (what the lobe's code evaluates), but no
convention fits: where every shadowing form, η layout and μ layout gives R + T = 1 to 1e-5 (α = 1/16, μ = 1/2) the
table is low by the same amount at every η, entering and exiting (0.026 at μ = 1/2; 0.016 at μ = 3/4), and its
μ = 0 column is 0 where R + T is above 0.95."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.dielectric_reference import albedo_part
from helpers.paths import FIXTURES

from brdfnorm.audit import audit

FIXTURE = FIXTURES / "engines" / "moonray_transmission_albedo_excerpt.h"
#: η of the excerpt's slices z = 0, 8, …, 32 of 33 as the accessor's netaRange reads them.
ETA = 1.05 + 2.0 * np.arange(5) / 4


def _exact(mu: float, alpha: float, eta: float) -> float:
    return albedo_part("beckmann", mu, alpha, eta, "R") + albedo_part("beckmann", mu, alpha, eta, "T", "separable")


@pytest.mark.slow
@pytest.mark.parametrize("array, layout", [("mE", "eta-moonray"), ("mEExit", "eta-moonray-exiting")])
def test_moonray_transmission_albedo_excerpt(array, layout):
    result = audit(str(FIXTURE), "beckmann-dielectric", read={"array": array, "shape": (5, 5, 5)}, dense=False,
                   sweep=False, pins={"axes": "eta,alpha,mu", "direction": "mu-node", "roughness": "r2-node",
                                      "f0": layout, "alpha_floor": "0.001"})
    best = result.best
    assert not result.fits and not result.passes
    assert best.convention.shadowing == "separable"  # Walter's G1·G1, as BsdfTransmissionCookTorrance.cc
    assert 0.015 < best.median < 0.03
    fit = best.channels[0]
    table = result.source.values[..., 0]
    eta = ETA if layout == "eta-moonray" else 1.0 / ETA
    assert np.allclose(fit.exact[:, 2, 2] + fit.residual[:, 2, 2], table[:, 2, 2])
    for z in range(5):
        for j, deficit in ((2, 0.026), (3, 0.0162)):  # μ = 1/2, 3/4 at roughness 1/4 (α = 1/16)
            exact = _exact(j / 4, 1 / 16, eta[z])
            # no shadowing form or layout makes μ = 1/2 other than 1 (at μ = 3/4, η = 1/1.55 is near the critical
            # angle, 0.9989)
            assert exact > (1 - 1e-5 if j == 2 else 0.998)
            assert fit.exact[z, 1, j] == pytest.approx(exact, abs=1e-6)
            assert exact - table[z, 1, j] == pytest.approx(deficit, abs=1.5e-3)
    # the cos θ = 0 column is zero (the accessor's ceil reads it only at cos θ = 0); R + T at μ = 1e-3 is not
    assert np.all(table[:, :, 0] == 0.0)
    assert _exact(1e-3, 1 / 16, eta[2]) > 0.95
