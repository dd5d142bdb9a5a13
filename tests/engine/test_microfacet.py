"""The ggx and beckmann lobes and their half-vector albedo (brdfnorm.engine.routes.halfvector), against independent
routes:
a fixed Gauss–Legendre reference in CDF coordinates (tests/helpers/microfacet_reference.py), closed forms (1 − ln 2,
the mirror limit with mpmath), the generic hemisphere engine, the `.brdf` files of the same lobes, and a
complex-number Fresnel."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
from helpers.microfacet_reference import reference_albedo
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.engine.routes import azimuthal
from brdfnorm.errors import BrdfnormError, ParameterError
from brdfnorm.models.microfacet import fresnel_conductor, fresnel_dielectric

MUS = np.array([1e-4, 0.03, 0.5, 1.0])
ALPHAS = np.array([1e-8, 1e-4, 0.02, 0.3, 1.0])


def _view(mu: float) -> np.ndarray:
    return np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])


def _random_directions(rng, n: int) -> np.ndarray:
    z = rng.uniform(0.01, 1.0, n)
    phi = rng.uniform(0.0, 2 * np.pi, n)
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


@pytest.mark.parametrize("method", ["microfacet", "azimuthal"])
@pytest.mark.parametrize("shadowing", ["height-correlated", "separable"])
def test_ggx_normal_incidence_alpha_one_is_one_minus_ln2(shadowing, method):
    # At μ = 1, Λ(V) = 0, so both G2 forms reduce to G1(L); with α = 1 the GGX slope density is
    # 1/(π(1+r²)²) and the integral is elementary: E = 1 − ln 2. Both routes: the half-vector cubature and
    # the 1-D azimuthal reduction ("auto" picks the latter).
    result = bn.albedo(bn.load("ggx", alpha=1.0, shadowing=shadowing), 0.0, rtol=1e-12, method=method)
    true_error = abs(result.value[0] - (1.0 - np.log(2.0)))
    assert result.method == method
    assert true_error <= 1e-13
    assert result.error[0] >= true_error


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ggx", "beckmann"])
@pytest.mark.parametrize("method", ["microfacet", "azimuthal"])
def test_grid_agrees_with_gauss_legendre_reference(name, method):
    model = bn.load(name, alpha=ALPHAS[:, None])
    result = bn.albedo(model, np.arccos(MUS)[None, :], method=method)  # one vectorized call, rtol 1e-10
    assert result.converged.all()
    for i, alpha in enumerate(ALPHAS):
        for j, mu in enumerate(MUS):
            # At the μ = cos θ the albedo is asked at (θ = arccos μ in float64: 1e-12 relative off μ at grazing,
            # which moves E by ~1e-14 — not the integrator's error).
            reference = reference_albedo(name, np.cos(np.arccos(mu)), alpha, order=20)
            check = reference_albedo(name, np.cos(np.arccos(mu)), alpha, order=14)
            assert abs(reference - check) <= 1e-11, "the reference itself is not converged"
            true_error = abs(result.value[i, j, 0] - reference)
            assert true_error <= 1e-9 * reference, (mu, alpha)
            assert result.error[i, j, 0] + abs(reference - check) >= true_error, (mu, alpha)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ggx", "beckmann"])
def test_separable_shadowing_agrees_with_reference(name):
    cases = [(1e-4, 0.3), (0.03, 0.02), (0.5, 1.0), (1e-4, 1e-4)]
    for mu, alpha in cases:
        result = bn.albedo(bn.load(name, alpha=alpha, shadowing="separable"), np.arccos(mu))
        reference = reference_albedo(name, mu, alpha, "separable", order=20)
        assert abs(result.value[0] - reference) <= max(result.error[0], 1e-12), (mu, alpha)
        assert abs(result.value[0] - reference) <= 1e-9


def _mirror_limit(name: str, mu: float, alpha: float, shadowing: str) -> float:
    """α → 0: H = N, L = mirror(V), E = G2(mirror V, V) with Λ(V) at the given α (mpmath, 30 digits)."""
    mpmath.mp.dps = 30
    mu = mpmath.mpf(mu)
    a = mpmath.mpf(alpha) * mpmath.sqrt(1 - mu * mu) / mu
    if name == "ggx":
        lam = (mpmath.sqrt(1 + a * a) - 1) / 2
    elif a == 0:
        lam = mpmath.mpf(0)
    else:
        b = 1 / a
        lam = (mpmath.erf(b) - 1) / 2 + mpmath.exp(-b * b) / (2 * b * mpmath.sqrt(mpmath.pi))
    return float(1 / (1 + 2 * lam) if shadowing == "height-correlated" else 1 / (1 + lam) ** 2)


@pytest.mark.parametrize("name", ["ggx", "beckmann"])
@pytest.mark.parametrize("shadowing", ["height-correlated", "separable"])
def test_mirror_limit_with_mpmath(name, shadowing):
    # At α = 1e-8 the lobe's width changes E by O(α²)-relative terms only: E = G2(mirror V, V) to ~1e-12.
    for mu in (0.01, 0.2, 0.7, 1.0):
        result = bn.albedo(bn.load(name, alpha=1e-8, shadowing=shadowing), np.arccos(mu))
        assert abs(result.value[0] - _mirror_limit(name, mu, 1e-8, shadowing)) <= 1e-12


def test_anisotropic_mirror_limit():
    # α_x ≠ α_y → 0: E = 1/(1 + 2Λ(V)) with Λ from a² = (α_x² V_x² + α_y² V_y²)/V_z² (GGX), V at azimuth 0.5.
    theta, phi, ax, ay = 1.4, 0.5, 1e-8, 4e-8
    V = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    mpmath.mp.dps = 30
    a2 = (mpmath.mpf(ax) * V[0]) ** 2 + (mpmath.mpf(ay) * V[1]) ** 2
    lam = (mpmath.sqrt(1 + a2 / mpmath.mpf(V[2]) ** 2) - 1) / 2
    result = bn.albedo(bn.load("ggx", alpha_x=ax, alpha_y=ay), theta, phi)
    assert abs(result.value[0] - float(1 / (1 + 2 * lam))) <= 1e-12


def _complex_fresnel(cos: float, n: complex) -> float:
    """Unpolarized reflectance from the complex Fresnel amplitudes (numpy complex arithmetic)."""
    sin2 = 1 - cos * cos
    root = np.sqrt(n * n - sin2 + 0j)
    rs = (cos - root) / (cos + root)
    rp = (n * n * cos - root) / (n * n * cos + root)
    return float((abs(rs) ** 2 + abs(rp) ** 2) / 2)


def test_fresnel_against_complex_amplitudes():
    for cos in (1e-6, 0.1, 0.5, 0.9, 1.0):
        for eta, k in ((1.5, 0.0), (0.2, 3.0), (2.5, 0.4), (1.1, 8.0)):
            assert abs(fresnel_conductor(np.array(cos), eta, k) - _complex_fresnel(cos, complex(eta, k))) <= 1e-14
        assert abs(fresnel_dielectric(np.array(cos), 1.5) - _complex_fresnel(cos, 1.5)) <= 1e-14
    # Total internal reflection seen from inside (η < 1): F = 1 past the critical angle.
    assert fresnel_dielectric(np.array(0.1), 1 / 1.5) == 1.0
    assert abs(fresnel_dielectric(np.array(0.9), 1 / 1.5) - _complex_fresnel(0.9, 1 / 1.5)) <= 1e-14


def test_dielectric_mirror_limit_is_fresnel_times_shadowing():
    mu = 0.4
    model = bn.load("ggx", alpha=1e-8, fresnel="dielectric", eta=1.5)
    result = bn.albedo(model, np.arccos(mu))
    expected = _complex_fresnel(mu, 1.5) * _mirror_limit("ggx", mu, 1e-8, "height-correlated")
    assert model.channels == 3
    np.testing.assert_allclose(result.value, expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("params", [
    {"alpha": 0.3},
    {"alpha": 0.5, "shadowing": "separable", "fresnel": "schlick", "f0": (0.9, 0.6, 0.5)},
    {"alpha_x": 0.2, "alpha_y": 0.6, "fresnel": "conductor", "eta": (0.2, 0.9, 1.1), "k": (3.0, 2.5, 2.2)},
])
@pytest.mark.parametrize("name", ["ggx", "beckmann"])
def test_generic_engine_agrees_at_moderate_roughness(name, params):
    model = bn.load(name, **params)
    theta, phi = np.radians([10.0, 60.0]), 0.7
    generic = bn.albedo(model, theta, phi, rtol=1e-9, method="quadrature")
    for method in ["microfacet"] + (["azimuthal"] if azimuthal.applies(model, "light") else []):
        fast = bn.albedo(model, theta, phi, rtol=1e-10, method=method)
        difference = np.abs(fast.value - generic.value)
        assert np.all(difference <= fast.error + generic.error + 1e-12)
        assert np.all(difference <= 3e-9)


def test_anisotropic_equal_roughness_is_isotropic():
    iso = bn.albedo(bn.load("ggx", alpha=0.4), np.radians(50.0), 1.1)
    aniso = bn.load("ggx", alpha_x=0.4, alpha_y=0.4)
    assert not aniso.isotropic
    np.testing.assert_allclose(bn.albedo(aniso, np.radians(50.0), 1.1).value, iso.value, rtol=0, atol=3e-10)
    # Swapping α_x and α_y is a rotation by 90° of the view azimuth.
    a = bn.albedo(bn.load("beckmann", alpha_x=0.1, alpha_y=0.5), np.radians(70.0), 0.3)
    b = bn.albedo(bn.load("beckmann", alpha_x=0.5, alpha_y=0.1), np.radians(70.0), 0.3 + np.pi / 2)
    np.testing.assert_allclose(a.value, b.value, rtol=0, atol=3e-10)


@pytest.mark.parametrize("params", [
    {"alpha": 0.3},
    {"alpha": 0.05, "shadowing": "separable", "fresnel": "dielectric", "eta": 1.33},
    {"alpha_x": 0.1, "alpha_y": 0.7, "fresnel": "conductor", "eta": (0.2, 0.9, 1.1), "k": (3.0, 2.5, 2.2)},
    {"alpha": 0.6, "fresnel": "schlick", "f0": 0.2, "f90": 0.8},
])
@pytest.mark.parametrize("name", ["ggx", "beckmann"])
def test_reciprocity_on_random_pairs(name, params, rng):
    model = bn.load(name, **params)
    L, V = _random_directions(rng, 2000), _random_directions(rng, 2000)
    np.testing.assert_allclose(model.eval(L, V), model.eval(V, L), rtol=1e-12, atol=1e-290)
    assert bn.albedo(model, 0.6, over="view").value == pytest.approx(bn.albedo(model, 0.6).value, abs=1e-15)


def test_ggx_brdf_file_agrees_with_builtin(rng):
    # examples/ggx.brdf: α = roughness², separable Smith G1 for GGX, Schlick F with f90 = 1.
    L, V = _random_directions(rng, 3000), _random_directions(rng, 3000)
    for roughness in (np.sqrt(1e-3), 0.3, 1.0):
        file_model = bn.load(EXAMPLES / "ggx.brdf", roughness=roughness, f0=0.04)
        builtin = bn.load("ggx", alpha=roughness**2, shadowing="separable", fresnel="schlick", f0=0.04, f90=1.0)
        expected = builtin.eval(L, V)
        np.testing.assert_allclose(file_model.eval(L, V), expected, rtol=1e-9, atol=0)
    file_albedo = bn.albedo(bn.load(EXAMPLES / "ggx.brdf", roughness=0.6, f0=0.04), np.radians(40.0), rtol=1e-10)
    builtin_albedo = bn.albedo(builtin.with_params(alpha=0.36), np.radians(40.0))
    assert np.all(np.abs(file_albedo.value - builtin_albedo.value) <= 1e-9)


def test_anisotropic_ggx_brdf_file_agrees_with_builtin(rng):
    # examples/anisotropic_ggx.brdf: height-correlated Smith, α_x along X, α_y along Y, Schlick with f90 = 1.
    L, V = _random_directions(rng, 3000), _random_directions(rng, 3000)
    F0 = (0.95, 0.64, 0.54)
    file_model = bn.load(EXAMPLES / "anisotropic_ggx.brdf", alpha_x=0.05, alpha_y=0.4, F0=F0)
    builtin = bn.load("ggx", alpha_x=0.05, alpha_y=0.4, fresnel="schlick", f0=F0, f90=1.0)
    np.testing.assert_allclose(file_model.eval(L, V), builtin.eval(L, V), rtol=1e-9, atol=0)


def test_beckmann_brdf_file_agrees_with_builtin(rng):
    # examples/beckmann.brdf: exact Beckmann Λ with erf written in GLSL (series and continued fraction).
    L, V = _random_directions(rng, 3000), _random_directions(rng, 3000)
    for alpha in (1e-3, 0.05, 0.4, 1.0):
        for shadowing in (0, 1):
            file_model = bn.load(EXAMPLES / "beckmann.brdf", alpha=alpha, height_correlated=shadowing)
            kind = "height-correlated" if shadowing else "separable"
            builtin = bn.load("beckmann", alpha=alpha, shadowing=kind)
            np.testing.assert_allclose(file_model.eval(L, V)[..., :1], builtin.eval(L, V), rtol=1e-9, atol=1e-280)


def test_choice_parameters():
    model = bn.load("ggx", shadowing="separable")
    assert model.params["shadowing"] == "separable"
    with pytest.raises(ParameterError, match="height-correlated, separable"):
        bn.load("ggx", shadowing="smith")
    with pytest.raises(ParameterError, match="alpha ≤ 1"):  # the compensation tables' range (F ≠ 1 is allowed)
        bn.load("ggx", fresnel="schlick", ms="kulla-conty", alpha=1.5)
    with pytest.raises(BrdfnormError, match="alpha_x"):
        bn.load("ggx", alpha_x=1e-20)


def test_cli_lists_and_sets_choices(run_cli):
    code, out, err = run_cli("models")
    assert code == 0 and "ggx" in out and "beckmann" in out and "height-correlated|separable" in out
    code, out, err = run_cli("albedo", "ggx", "-p", "alpha=1", "-p", "shadowing=separable", "--theta", "0",
                             "--json")
    assert code == 0, err
    assert '"albedo": 0.3068528194' in out
    code, out, err = run_cli("albedo", "ggx", "-p", "shadowing=smith", "--theta", "0")
    assert code == 2 and err.count("\n") == 1
    assert "shadowing" in err and "height-correlated, separable" in err
    code, out, err = run_cli("info", "beckmann", "--json")
    assert code == 0 and '"choice"' in out


def test_kulla_conty_furnace_with_exact_tables():
    # ms_table=0: E and E_avg exact (integrals). The compensated lobe's albedo, E + ∫ f_ms (N·L) dL with the
    # light integral done HERE by a fixed composite Gauss–Legendre rule in ln μ_L (f_ms does not depend on the
    # light azimuth), must be 1 — a check of f_ms and of E_avg against an independent quadrature of E.
    alpha = 0.5
    model = bn.load("ggx", alpha=alpha, ms="kulla-conty", ms_table=0)
    single = bn.load("ggx", alpha=alpha)
    x, w = np.polynomial.legendre.leggauss(20)
    edges = np.log([1e-7, 1e-2, 0.2, 1.0])
    nodes = np.concatenate([(a + b) / 2 + (b - a) / 2 * x for a, b in zip(edges[:-1], edges[1:], strict=True)])
    weights = np.concatenate([(b - a) / 2 * w for a, b in zip(edges[:-1], edges[1:], strict=True)])
    mu_l = np.exp(nodes)
    L = np.stack([np.sqrt(1 - mu_l**2), np.zeros_like(mu_l), mu_l], axis=-1)
    for mu_v in (0.1, 0.7):
        f_ms = model.multiple_scattering(L, _view(mu_v)[None, :], model.params)[:, 0]
        compensation = 2 * np.pi * np.sum(weights * f_ms * mu_l * mu_l)  # dμ = μ d(ln μ)
        total = bn.albedo(single, np.arccos(mu_v), rtol=1e-11).value[0] + compensation
        assert abs(1.0 - total) <= 1e-9


@pytest.mark.slow
def test_kulla_conty_interpolated_tables(run_cli):
    # Renderer-style tables: the furnace residual shrinks as the table grows, and the albedo method's closed
    # form for ∫ f_ms (N·L) dL agrees with the generic hemisphere engine on the compensated lobe.
    alphas, mus = np.array([0.15, 0.55, 0.95]), np.array([0.05, 0.4, 1.0])
    residuals = []
    for size in (4, 8):
        model = bn.load("ggx", alpha=alphas[:, None], ms="kulla-conty", ms_table=size)
        result = bn.albedo(model, np.arccos(mus)[None, :])
        residuals.append(np.max(np.abs(1.0 - result.value)))
        assert result.method == "azimuthal"
    assert residuals[1] < residuals[0] < 0.2
    model = bn.load("ggx", alpha=0.55, ms="kulla-conty", ms_table=4)
    fast = bn.albedo(model, np.arccos(0.4))
    generic = bn.albedo(model, np.arccos(0.4), method="quadrature", rtol=1e-9)
    assert abs(fast.value[0] - generic.value[0]) <= fast.error[0] + generic.error[0]
    code, out, err = run_cli("albedo", "ggx", "-p", "ms=kulla-conty", "-p", "ms_table=4", "--theta", "0,60",
                             "--json")
    assert code == 0, err


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ggx", "beckmann"])
def test_normal_incidence_agrees_with_certified_enclosures(name):
    # brdfnorm.engine.routes.certified encloses E(V = N) by Arb ball arithmetic in a 1-D reduction (another engineer's
    # route).
    pytest.importorskip("flint", reason="python-flint (the certified extra) is not installed")
    for params in ({"alpha": 1e-8}, {"alpha": 0.02}, {"alpha": 0.7, "shadowing": "separable"},
                   {"alpha": 0.3, "fresnel": "schlick", "f0": (0.9, 0.5, 0.1)},
                   {"alpha": 0.5, "fresnel": "dielectric", "eta": 1 / 1.5}):
        model = bn.load(name, **params)
        fast = bn.albedo(model, 0.0)
        certified = bn.albedo(model, 0.0, method="certified")
        true_error = np.abs(fast.value - certified.value)
        assert np.all(true_error <= fast.error + certified.error), params
        assert np.all(true_error <= 1e-10 * certified.value), params


def test_too_close_to_the_horizon_is_refused(run_cli):
    with pytest.raises(BrdfnormError, match="cos θ"):
        bn.albedo(bn.load("ggx", alpha=0.5), np.arccos(1e-12))
    code, out, err = run_cli("albedo", "ggx", "--theta", "89.9999999999")
    assert code == 2 and "--theta" in err and err.count("\n") == 1
