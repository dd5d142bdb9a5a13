"""The global driver's half-azimuth check of u (brdfnorm.engine.machinery.global_driver._refine_half; issue 39,
item 5: evaluations per generic albedo): where both directions would be doubled at (M, N), β is doubled to
(2M, N) and u measured on the M azimuths already there, (M, 2N); the value reported is Q(2M, N).

Checked here: the bookkeeping on a synthetic grid (every node evaluated once, the value the tensor rule's on the
final grid), the evaluations it saves and its honesty on Blinn-Phong against seed 002's series, both backends
evaluating the same nodes, the deviations computed once at 16 azimuths, a fall below the rounding in
``grid_estimate.sudden``, and (slow) randomized sweeps of the cases the check could miss: a second, narrow lobe off
the plane of incidence (a feature along β that only the finer azimuths resolve) and anisotropic lobes at random view
azimuths, each against an independent reference and against the same engine with the check switched off."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers.global_grid import SmoothGrid, assert_settled_with_check
from helpers.paths import EXAMPLES, FIXTURES
from helpers.references import phong_like_reference

import brdfnorm as bn
from brdfnorm.engine.machinery import global_driver, grid_estimate
from brdfnorm.engine.machinery.tensor_rule import LobeAlignedGrid, fejer

BACKENDS = pytest.mark.parametrize("backend", ["numpy", "compiled"])


def _albedo(model, theta, phi=0.0, backend="numpy", **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bn.albedo(model, np.atleast_1d(theta), phi, method="quadrature", backend=backend, **kwargs)


def _ratio(result, exact, allowance=0.0) -> np.ndarray:
    value, error = result.value[:, 0], result.error[:, 0]
    return np.maximum(np.abs(value - exact) - allowance, 0.0) / error



def test_the_check_evaluates_each_node_once_and_reports_its_grid(monkeypatch):
    halves = []
    decide = global_driver._halves

    def observed(grid, group, more_b, more_u, short, needed_u):
        half = decide(grid, group, more_b, more_u, short, needed_u)
        halves.append(0 if half is None else int(half.sum()))
        return half

    monkeypatch.setattr(global_driver, "_halves", observed)
    monkeypatch.setattr(global_driver, "HALF_AZIMUTH_DEPTH", 1)  # (the quarter: test_quarter_azimuth_check.py)
    monkeypatch.setattr(global_driver, "HALF_AZIMUTH_NEEDED", 1)
    grid = SmoothGrid()
    # (its path: 32 × 63 → β doubled, u checked on the 32 azimuths → β again, the check taken along to 64 of the
    # 128 → settled on 128 × 63, u checked on 64 azimuths × 127 radial nodes)
    result = global_driver.integrate_global(grid, 1, np.arange(1), rtol=1e-6, atol=0.0, max_nodes=65_536)
    assert result.converged[0] and sum(halves) == 2
    assert_settled_with_check(grid, result, M=128, level_u=6, check_step=2)


@pytest.mark.parametrize("theta_deg", [55.0, 75.0])
def test_fewer_evaluations_for_blinn_phong(theta_deg, monkeypatch):
    # Blinn-Phong n = 100, rtol 1e-9: at 50–81° the driver doubled both directions at 32 × 63 (64 × 127, 8 872
    # evaluations); now 64 × 63 with u checked on 32 azimuths × 127 radial nodes (6 824), within its estimate.
    # (Both 480 fewer since the rounding-noise survey, machinery/rounding.surveyed_noise.)
    monkeypatch.setattr(global_driver, "HALF_AZIMUTH_DEPTH", 1)  # (the quarter: test_quarter_azimuth_check.py)
    model = bn.load("blinn-phong", n=100.0)
    theta = np.radians(theta_deg)
    exact = bn.albedo(model, np.atleast_1d(theta), method="series", rtol=1e-13)
    result = _albedo(model, theta, rtol=1e-9)
    assert _ratio(result, exact.value[:, 0], exact.error[:, 0])[0] <= 1.0
    assert result.evaluations.tolist() == [6_344]
    monkeypatch.setattr(LobeAlignedGrid, "half_azimuth", False)
    assert _albedo(model, theta, rtol=1e-9).evaluations.tolist() == [8_392]


def test_both_backends_evaluate_the_same_nodes():
    model = bn.load("blinn-phong", n=100.0)
    theta = np.radians([20.0, 55.0, 75.0, 84.0])
    numpy, compiled = _albedo(model, theta, rtol=1e-9), _albedo(model, theta, rtol=1e-9, backend="compiled")
    assert numpy.evaluations.tolist() == compiled.evaluations.tolist()
    assert np.all(np.abs(numpy.value - compiled.value) <= np.minimum(numpy.error, compiled.error))


def test_deviations_are_computed_once_per_grid(monkeypatch):
    # At 16 azimuths both the extrapolation (grid_estimate.own_error) and grid_estimate.sudden read them.
    seen = []
    deviations = grid_estimate.deviations

    def counted(F, weights):
        seen.append((id(F), F.shape))
        return deviations(F, weights)

    monkeypatch.setattr(grid_estimate, "deviations", counted)
    _albedo(bn.load("blinn-phong", n=100.0), np.radians([1.0, 10.0, 40.0]), rtol=1e-9)
    assert any(shape[1] == 16 for _, shape in seen)
    assert len(seen) == len(set(seen))


def test_a_fall_below_the_rounding_is_one_to_the_rounding():
    # d₁ = 0 or 1e-17 (the rounding of either backend) after d₂ = 2.5e-9 and d₃ = 1e-2, magnitude 0.24: the
    # same decision — not sudden: geometric convergence predicts a next difference far below the rounding.
    F = np.zeros((1, 16, 7, 1))
    weights = [fejer(3 - k)[1] for k in range(3)] + [np.zeros(0)]
    plain = np.full((1, 1), 1e-20)
    magnitude = np.full((1, 1), 0.24)
    decided = []
    for d1 in (0.0, 1e-17):
        d_b = np.array([d1, 2.5e-9, 1e-2]).reshape(3, 1, 1)
        decided.append(grid_estimate.sudden(F, weights, plain, plain, magnitude, (d_b, d_b))[0][0, 0])
    assert decided == [1e-20, 1e-20]
    # ... while a resolved sudden agreement still keeps the coarser difference
    d_b = np.array([3.5e-8, 1e-2, 1e-4]).reshape(3, 1, 1)
    raised = grid_estimate.sudden(F, weights, plain, plain, magnitude, (d_b, d_b))[0][0, 0]
    assert raised == pytest.approx(1e-2 + 3.5e-8)


def _off_plane(rng, count):
    """Random cases of tests/fixtures/off_plane_lobes.brdf near enough the plane of incidence for the lobe-aligned
    coordinates about the main peak to see the second lobe, with their albedos (seed 002's series plus modified
    Phong's 1-D reference) and the reference's allowance."""
    theta = np.radians(rng.uniform(0.0, 89.5, count))
    n = np.exp(rng.uniform(0.0, np.log(2e4), count))
    m = n * np.exp(rng.uniform(np.log(1.5), np.log(30.0), count))
    weight = np.exp(rng.uniform(np.log(0.01), np.log(10.0), count))
    azimuth = rng.uniform(0.02, 1.0, count) * rng.choice([-1, 1], count) / np.sqrt(np.sin(theta) + 0.05)
    series = bn.albedo(bn.load("blinn-phong").with_params(n=n), theta, method="series", rtol=1e-13)
    exact = series.value[:, 0] + weight * np.array([phong_like_reference(a, t, original=False)
                                                     for a, t in zip(m, theta, strict=True)])
    model = bn.load(str(FIXTURES / "off_plane_lobes.brdf")).with_params(n=n, m=m, weight=weight, azimuth=azimuth)
    return model, theta, exact, series.error[:, 0] + 1e-13 * exact


def _worse_than_without(model, theta, exact, allowance, rtol, backend, monkeypatch, phi=0.0) -> float:
    """max(true error / estimate) over the cases the engine without the check keeps within their estimates."""
    with_check = _ratio(_albedo(model, theta, phi, backend, rtol=rtol), exact, allowance)
    with monkeypatch.context() as patch:
        patch.setattr(LobeAlignedGrid, "half_azimuth", False)
        without = _ratio(_albedo(model, theta, phi, backend, rtol=rtol), exact, allowance)
    return float(np.where(without <= 1.0, with_check, 0.0).max())


@BACKENDS
def test_a_narrow_lobe_off_the_plane_quick(backend, rng, monkeypatch):
    model, theta, exact, allowance = _off_plane(rng, 6)
    assert _worse_than_without(model, theta, exact, allowance, 1e-9, backend, monkeypatch) <= 1.0


@pytest.mark.slow
@BACKENDS
def test_a_narrow_lobe_off_the_plane_sweep(backend, rng, monkeypatch):
    """~240 random two-lobe cases per backend, rtol 1e-4…1e-11 (cases the engine misses without the check too —
    the second lobe beyond what the coordinates about the main peak resolve — are not the check's)."""
    worst = 0.0
    for rtol in (1e-4, 1e-6, 1e-8, 1e-9, 1e-10, 1e-11):
        model, theta, exact, allowance = _off_plane(rng, 40)
        worst = max(worst, _worse_than_without(model, theta, exact, allowance, rtol, backend, monkeypatch))
    assert worst <= 1.0, worst


@pytest.mark.slow
@BACKENDS
@pytest.mark.parametrize("shader", ["ashikhmin_shirley.brdf", "ward_anisotropic.brdf"])
def test_anisotropic_lobes_sweep(shader, backend, rng, monkeypatch):
    """Anisotropic (stretched) lobes at random view azimuths, rtol 1e-4…1e-9, against the engine without the
    check at rtol 1e-12 (converged cases only)."""
    worst = 0.0
    for rtol in (1e-4, 1e-6, 1e-9):
        count = 12
        theta, phi = np.radians(rng.uniform(0.0, 88.0, count)), rng.uniform(0.0, 2 * np.pi, count)
        if shader == "ward_anisotropic.brdf":
            params = {k: np.exp(rng.uniform(np.log(0.02), 0.0, count)) for k in ("alpha_x", "alpha_y")}
        else:
            params = {k: np.exp(rng.uniform(0.0, np.log(1e4), count)) for k in ("nu", "nv")}
        model = bn.load(str(EXAMPLES / shader)).with_params(**params)
        with monkeypatch.context() as patch:
            patch.setattr(LobeAlignedGrid, "half_azimuth", False)
            reference = _albedo(model, theta, phi, "numpy", rtol=1e-12)
        keep = np.asarray(reference.converged)
        ratio = _ratio(_albedo(model, theta, phi, backend, rtol=rtol), reference.value[:, 0], reference.error[:, 0])
        worst = max(worst, float(ratio[keep].max(initial=0.0)))
    assert worst <= 1.0, worst
