"""Anisotropic energy tables (issue #45): the compiled anisotropic albedo against independent computations —
Gauss–Legendre over the half vector in polar coordinates (helpers.references.half_vector_gauss_legendre, which
shares no code with brdfnorm's integrators) at a view, a seeded Monte Carlo of the view-azimuth average with its
confidence interval — the isotropic limit against the 2-D table, the engines' parameterizations, the command line."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.references import half_vector_gauss_legendre

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.engine.routes import anisotropic as kernel
from brdfnorm.errors import ArgumentError
from brdfnorm.lut import anisotropy


def reference(model, mu: float, phi_v: float) -> tuple[float, float]:
    """Gauss–Legendre at 24 and 32 nodes a panel: the finer value and the change as its own error."""
    V = np.array([np.sqrt(1 - mu * mu) * np.cos(phi_v), np.sqrt(1 - mu * mu) * np.sin(phi_v), mu])
    coarse, fine = (half_vector_gauss_legendre(model, V, order, 48) for order in (24, 32))
    return fine, abs(fine - coarse) + 1e-12


@pytest.mark.parametrize(("name", "shadowing"), [("ggx", "height-correlated"),
                                               pytest.param("ggx", "separable", marks=pytest.mark.slow),
                                               pytest.param("beckmann", "height-correlated", marks=pytest.mark.slow),
                                               pytest.param("beckmann", "separable", marks=pytest.mark.slow)])
@pytest.mark.parametrize(("mu", "phi_v", "ax", "ay"), [(1.0, 0.0, 1.0, 0.1), (0.5, 0.7, 1.0, 0.1),
                                                       (0.2, 1.3, 0.2, 0.6), (0.05, 0.0, 0.5, 0.15)])
def test_view_albedo_matches_an_independent_quadrature(name, shadowing, mu, phi_v, ax, ay):
    model = bn.load(name).with_params(alpha_x=ax, alpha_y=ay, shadowing=shadowing)
    value, own = reference(model, mu, phi_v)
    E, error, _, converged = kernel.albedo(name, shadowing, mu, ax, ay, phi_v, rtol=1e-9)
    assert converged[0]
    assert abs(E[0] - value) <= error[0] + own, (E[0], value, error[0], own)
    assert error[0] <= 1e-9 * E[0]


def test_the_issues_value_at_normal_view():
    # brdfnorm's half-vector route gives 0.529432698036 ± 6e-12 at (α_x, α_y) = (1, 0.1), μ = 1; the isotropic
    # table at √(α_x α_y) = 0.316 says 0.864.
    E, error, _, _ = kernel.albedo("ggx", "height-correlated", 1.0, 1.0, 0.1, 0.0, rtol=1e-11)
    assert abs(E[0] - 0.529432698036) <= error[0] + 6e-12
    iso, iso_error, _, _ = kernel.albedo("ggx", "height-correlated", 1.0, np.sqrt(0.1), np.sqrt(0.1), rtol=1e-11)
    assert abs(iso[0] - 0.86368845) < 1e-8


@pytest.mark.parametrize("name", ["ggx", "beckmann"])
def test_azimuth_average_against_seeded_monte_carlo(name):
    """Ē(μ): φ_v ~ U[0, 2π), the slopes drawn from the distribution (D(H)(N·H) dω_H), the weight
    w = G2 (V·H)/(V_z H_z) where N·L > 0 (the half-vector estimator, no quadrature); a 5σ interval."""
    rng = np.random.default_rng(4521)
    mu, ax, ay, n = 0.3, 0.8, 0.15, 400_000
    phi_v = rng.uniform(0.0, 2 * np.pi, n)
    u, phi = rng.uniform(0.0, 1.0, n), rng.uniform(0.0, 2 * np.pi, n)
    s = np.sqrt(u / (1.0 - u)) if name == "ggx" else np.sqrt(-np.log1p(-u))
    H = np.stack([ax * s * np.cos(phi), ay * s * np.sin(phi), np.ones(n)], axis=-1)
    H /= np.linalg.norm(H, axis=-1, keepdims=True)
    V = np.stack([np.sqrt(1 - mu * mu) * np.cos(phi_v), np.sqrt(1 - mu * mu) * np.sin(phi_v), np.full(n, mu)], -1)
    vh = np.sum(V * H, axis=-1)
    L = 2 * vh[:, None] * H - V
    model = bn.load(name).with_params(alpha_x=ax, alpha_y=ay)
    from brdfnorm.models.microfacet import shadowing_masking, smith_a2

    lam = model.distribution.smith_lambda
    above = L[:, 2] > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        g2 = shadowing_masking("height-correlated", lam(smith_a2(L, ax, ay)), lam(smith_a2(V, ax, ay)))
        w = np.where(above, g2 * vh / (mu * H[:, 2]), 0.0)
    mean, sigma = w.mean(), w.std() / np.sqrt(n)
    E, error, _, converged = kernel.albedo(name, "height-correlated", mu, ax, ay, rtol=1e-7)
    assert converged[0] and abs(E[0] - mean) <= 5 * sigma + error[0], (E[0], mean, sigma)
    # and the average differs from the views' extremes: the test sees the azimuth
    views = kernel.albedo(name, "height-correlated", mu, ax, ay, [0.0, np.pi / 2], rtol=1e-7)[0]
    assert abs(views[0] - views[1]) > 20 * sigma


def test_error_estimates_are_not_smaller_than_the_error():
    cases = [(mu, ax, ay) for mu in (1e-4, 1e-3, 0.1, 0.6) for ax, ay in ((1.0, 0.1), (0.05, 0.5), (3.0, 0.9))]
    mu, ax, ay = (np.array(c) for c in zip(*cases, strict=True))
    for name in ("ggx", "beckmann"):
        exact = kernel.albedo(name, "height-correlated", mu, ax, ay, 0.4, rtol=1e-12)
        loose = kernel.albedo(name, "height-correlated", mu, ax, ay, 0.4, rtol=1e-5)
        assert np.all(np.abs(loose[0] - exact[0]) <= loose[1] + exact[1])


@pytest.mark.slow
def test_averages_error_estimates_are_not_smaller_than_the_error():
    for name in ("ggx", "beckmann"):
        mu, ax, ay = np.array([1e-3, 0.3]), np.array([1.0, 0.05]), np.array([0.1, 0.5])
        tight = kernel.albedo(name, "height-correlated", mu, ax, ay, rtol=1e-10)
        loose = kernel.albedo(name, "height-correlated", mu, ax, ay, rtol=1e-5)
        assert np.all(np.abs(loose[0] - tight[0]) <= loose[1] + tight[1])
        average = kernel.average_albedo(name, "height-correlated", ax, ay, rtol=1e-5)
        reference = kernel.average_albedo(name, "height-correlated", ax, ay, rtol=1e-9)
        assert np.all(np.abs(average[0] - reference[0]) <= average[1] + reference[1])


@pytest.mark.parametrize("name", ["ggx", pytest.param("beckmann", marks=pytest.mark.slow)])
def test_isotropic_limit_equals_the_2d_table(name):
    axes = {"mu": [1e-3, 0.3, 1.0], "alpha": [0.05, 0.4, 1.0]}
    flat = lut.compute(bn.load(name), axes, rtol=1e-9)
    table = anisotropy.compute(bn.load(name), {**axes, "aspect": [1.0]}, anisotropy="aspect", rtol=1e-7)
    assert table["E"].shape == (3, 3, 1) and table.meta["unconverged"] == 0
    assert np.all(np.abs(table["E"][..., 0] - flat["E"]) <= table["E_error"][..., 0] + flat["E_error"])
    assert np.all(np.abs(table["E_avg"][:, 0] - flat["E_avg"]) <= table["E_avg_error"][:, 0] + flat["E_avg_error"])
    burley = anisotropy.compute(bn.load(name), {**axes, "anisotropy": [0.0]}, rtol=1e-7)
    assert np.array_equal(burley["E"], table["E"])


def test_parameterizations():
    P = anisotropy.PARAMETERIZATIONS
    ax, ay = P["burley"](0.1, 1.0)
    assert np.isclose(ax, 0.1 / np.sqrt(0.1)) and np.isclose(ay, 0.1 * np.sqrt(0.1))
    ax, ay = P["materialx"](0.9, 1.0)  # aspect √0.02; α_x clamped at 1
    assert ax == 1.0 and np.isclose(ay, 0.9 * np.sqrt(0.02))
    ax, ay = P["openpbr"](0.25, 0.5)
    assert np.isclose(ax, 0.25 * np.sqrt(2 / 1.25)) and np.isclose(ay, 0.5 * ax)
    ax, ay = P["aspect"](0.3, 0.5)
    assert np.isclose(np.sqrt(ax * ay), 0.3) and np.isclose(ay / ax, 0.25)
    with pytest.raises(ArgumentError, match="anisotropy must lie"):
        P["burley"](0.3, 1.5)
    with pytest.raises(ArgumentError, match="anisotropy parameterization"):
        anisotropy.compute(bn.load("ggx"), {"mu": [1.0], "alpha": [0.3], "anisotropy": [0.5]}, anisotropy="disney")
    with pytest.raises(ArgumentError, match="white"):
        anisotropy.compute(bn.load("ggx").with_params(fresnel="schlick"), {"mu": [1.0], "alpha": [0.3],
                                                                           "anisotropy": [0.5]})


def test_view_azimuth_axis_and_average():
    axes = {"mu": [0.4], "alpha": [0.5], "anisotropy": [1.0]}
    averaged = anisotropy.compute(bn.load("ggx"), axes, rtol=1e-8, average=False)
    phi = np.linspace(0.0, np.pi / 2, 9)
    views = anisotropy.compute(bn.load("ggx"), {**axes, "phi_v": phi}, rtol=1e-8, average=False)
    E = views["E"][0, 0, 0]
    assert abs(E[0] - E[-1]) > 0.01  # the azimuth matters
    trapezoid = (E[0] / 2 + E[1:-1].sum() + E[-1] / 2) / 8
    assert abs(trapezoid - averaged["E"][0, 0, 0]) < 1e-3  # a coarse rule, a loose check of the same mean
    assert views.meta["anisotropy"]["view_azimuth"].startswith("phi_v axis")


def test_cli_writes_the_parameterization_and_degrees(tmp_path, run_cli):
    out = tmp_path / "aniso.npz"
    code, _, err = run_cli("lut", "beckmann", "--anisotropy", "materialx", "--axis", "mu=0.5,1",
                           "--axis", "roughness=0.5", "--axis", "anisotropy=0,0.9", "--axis", "phi_v=0,90",
                           "--rtol", "1e-6", "-o", str(out))
    assert code == 0, err
    table = lut.load(out)
    assert table.meta["anisotropy"]["parameterization"] == "materialx"
    assert table.meta["units"]["phi_v"] == "degrees" and list(table.axes["phi_v"]) == [0.0, 90.0]
    ax, ay = anisotropy.PARAMETERIZATIONS["materialx"](0.25, 0.9)
    direct = kernel.albedo("beckmann", "height-correlated", 0.5, ax, ay, np.pi / 2, rtol=1e-6)
    assert abs(table["E"][0, 0, 1, 1] - direct[0][0]) <= 2 * direct[1][0]
    code, _, err = run_cli("lut", "ggx", "--axis", "mu=1", "--axis", "alpha=0.5", "--axis", "phi_v=0",
                           "-o", str(out))
    assert code == 2 and "phi_v" in err and "Traceback" not in err
    code, _, err = run_cli("lut", "ggx", "--anisotropy", "burley", "--axis", "mu=1", "--axis",
                           "alpha=0.5", "--axis", "anisotropy=0.5", "--channels", "dfg", "-o", str(out))
    assert code == 2 and "--anisotropy" in err


@pytest.mark.slow
def test_workers_are_bit_identical():
    axes = {"mu": np.linspace(0.1, 1, 5), "alpha": [0.2, 0.7], "anisotropy": [0.0, 0.5, 1.0]}
    one = anisotropy.compute(bn.load("ggx"), axes, rtol=1e-6)
    two = anisotropy.compute(bn.load("ggx"), axes, rtol=1e-6, workers=2)
    for name in one:
        assert np.array_equal(one[name], two[name]), name
