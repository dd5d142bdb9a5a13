"""The ``zeltner`` LTC sheen (Zeltner et al. 2022) and the openpbr fuzz made of it.

Independent routes: the LTC written here from its definition (the 3×3 matrix M⁻¹ inverted by numpy, D_o of the
normalized direction times |M⁻¹|/|M⁻¹L|³), scipy's dblquad of the lobe over the hemisphere, and the fit R(μ, r)
whose integral the LTC is by construction.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers.paths import EXAMPLES
from scipy import integrate

import brdfnorm as bn
from brdfnorm.errors import ParameterError
from brdfnorm.models.zeltner import albedo_fit, ltc_a, ltc_b

MU = np.array([1.0, 0.8, 0.5, 0.2, 0.05, 0.01])


def _ltc_by_definition(L: np.ndarray, V: np.ndarray, r: float) -> float:
    """D(L) = D_o(M⁻¹L/|M⁻¹L|) |det M⁻¹| / |M⁻¹L|³, with M = the LTC matrix [[1/a, 0, −b/a], [0, 1/a, 0], [0, 0, 1]]
    in the frame whose X is V's tangent direction (the matrix inverted numerically, not the closed form)."""
    mu = V[2]
    a, b = 1.0 / float(ltc_a(mu, r)), float(ltc_b(mu, r))
    M = np.array([[a, 0.0, -b * a], [0.0, a, 0.0], [0.0, 0.0, 1.0]])
    Minv = np.linalg.inv(M)
    x = np.array([V[0], V[1], 0.0])
    x = x / np.linalg.norm(x) if np.linalg.norm(x) > 0 else np.array([1.0, 0.0, 0.0])
    frame = np.stack([x, np.cross([0.0, 0.0, 1.0], x), [0.0, 0.0, 1.0]])
    w = Minv @ (frame @ L)
    n = np.linalg.norm(w)
    return max(w[2] / n, 0.0) / np.pi * abs(np.linalg.det(Minv)) / n**3


@pytest.mark.parametrize("r", [0.05, 0.3, 0.7, 1.0])
def test_lobe_matches_the_ltc_definition(r):
    rng = np.random.default_rng(7)
    model = bn.load("zeltner", roughness=r, color=(1.0, 0.5, 0.25))
    for _ in range(20):
        L, V = rng.normal(size=3), rng.normal(size=3)
        L[2], V[2] = abs(L[2]), abs(V[2])
        L, V = L / np.linalg.norm(L), V / np.linalg.norm(V)
        expected = albedo_fit(V[2], r) * _ltc_by_definition(L, V, r) / L[2]
        got = model.eval(L, V)
        assert np.allclose(got, expected * np.array([1.0, 0.5, 0.25]), rtol=1e-12, atol=0)


@pytest.mark.parametrize("r", [0.1, 0.5, 1.0])
def test_ltc_integrates_to_one_by_dblquad(r):
    mu = 0.35
    V = np.array([np.sqrt(1 - mu * mu), 0.0, mu])

    def integrand(phi, theta):
        L = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
        return _ltc_by_definition(L, V, r) * np.sin(theta)

    value, error = integrate.dblquad(integrand, 0.0, np.pi / 2, 0.0, 2 * np.pi, epsabs=1e-11, epsrel=1e-11)
    assert abs(value - 1.0) <= max(error, 1e-10)


@pytest.mark.parametrize("r", [0.01, 0.1, 0.5, 1.0])
def test_engine_albedo_equals_the_fit(r):
    """brdfnorm's quadrature of the lobe against R(μ, r): the LTC is normalized, so they agree to the quadrature."""
    model = bn.load("zeltner", roughness=r)
    result = bn.albedo(model, np.arccos(MU), method="quadrature", rtol=1e-10, backend="numpy")
    fit = albedo_fit(MU, r)
    assert result.converged.all()
    assert np.all(np.abs(result.value[:, 0] - fit) <= result.error[:, 0])
    assert np.all(np.abs(result.value[:, 0] - fit) <= 1e-10 * np.abs(fit))
    closed = bn.albedo(model, np.arccos(MU), method="closed-form").value[:, 0]
    assert np.allclose(closed, albedo_fit(np.cos(np.arccos(MU)), r), rtol=1e-15, atol=0)  # θ → μ rounded


def test_fit_values_and_range():
    # The fit at a few points, written out from the coefficients (no shared code with albedo_fit).
    x, y = 0.5, 0.5
    s = y * (0.0206607 + 1.58491 * y) / (0.0379424 + y * (1.32227 + y))
    m = y * (-0.193854 + y * (-1.14885 + y * (1.7932 - 0.95943 * y * y))) / (0.046391 + y)
    o = y * (0.000654023 + (-0.0207818 + 0.119681 * y) * y) / (1.26264 + y * (-1.92021 + y))
    assert albedo_fit(x, y) == pytest.approx(np.exp(-0.5 * ((x - m) / s) ** 2) / (s * np.sqrt(2 * np.pi)) + o,
                                             rel=1e-14)
    # The fit dips below 0 (its offset o is negative) for r in about [0.04, 0.13]: at least −2.2e-5, never below.
    grid = albedo_fit(np.linspace(0, 1, 201)[:, None], np.linspace(0.01, 1, 199)[None, :])
    assert grid.max() < 0.75 and -2.2e-5 < grid.min() < 0
    assert albedo_fit(0.7745, 0.0985) == pytest.approx(-2.1079e-5, rel=1e-4)
    with pytest.raises(ParameterError, match="roughness"):
        bn.load("zeltner", roughness=0.005)


def test_openpbr_fuzz_is_the_ltc_sheen():
    """White fuzz over a white Lambert base passes the furnace (view rule); a grey fuzz c gives
    c R + (1 − R), R the fit; the material route and the generic quadrature of the composed BRDF agree."""
    theta = np.arccos(np.array([1.0, 0.5, 0.1]))
    common = dict(base_color=(1, 1, 1), specular_weight=0.0, fuzz_weight=1.0, fuzz_roughness=0.4)
    white = bn.albedo(bn.load("openpbr", **common), theta).value
    assert np.all(np.abs(white - 1.0) <= 1e-12)
    grey = bn.load("openpbr", **common, fuzz_color=(0.5, 0.5, 0.5))
    R = albedo_fit(np.cos(theta), 0.4)
    expected = 0.5 * R + (1.0 - R)
    by_material = bn.albedo(grey, theta, method="material").value[:, 0]
    by_quadrature = bn.albedo(grey, theta, method="quadrature", rtol=1e-9, backend="numpy").value[:, 0]
    assert np.all(np.abs(by_material - expected) <= 1e-13)
    assert np.all(np.abs(by_quadrature - expected) <= 1e-8)
    charlie = bn.albedo(bn.load("openpbr", **common, fuzz_color=(0.5, 0.5, 0.5), fuzz_lobe="charlie"), theta)
    assert np.max(np.abs(charlie.value[:, 0] - expected)) > 1e-2  # the other lobe is a different fuzz


def test_compiled_kernel_matches_numpy():
    pytest.importorskip("numba")
    model = bn.load("zeltner", roughness=0.35, color=(0.9, 0.5, 0.2))
    kernel = model.native_kernel()
    u = kernel.pack(model.params)
    rng = np.random.default_rng(11)
    L, V = rng.normal(size=(40, 3)), rng.normal(size=(40, 3))
    L, V = L / np.linalg.norm(L, axis=1, keepdims=True), V / np.linalg.norm(V, axis=1, keepdims=True)
    V[0] = [0.0, 0.0, 1.0]  # normal incidence: any frame
    expected = model.eval(L, V)
    got = np.array([kernel.function(*l_, *v_, u) for l_, v_ in zip(L, V, strict=True)])
    assert np.allclose(got, expected, rtol=1e-14, atol=0)
    theta = np.arccos([0.9, 0.3])
    compiled = bn.albedo(model, theta, method="quadrature", rtol=1e-10, backend="compiled")
    assert np.abs(compiled.value - albedo_fit(np.cos(theta), 0.35)[:, None] * [0.9, 0.5, 0.2]).max() <= 1e-10


def test_example_file_is_the_same_lobe():

    path = EXAMPLES / "zeltner.brdf"
    file = bn.load(path, roughness=0.3, sheenColor=(0.9, 0.5, 0.2))
    builtin = bn.load("zeltner", roughness=0.3, color=(0.9, 0.5, 0.2))
    rng = np.random.default_rng(5)
    L, V = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
    L, V = L / np.linalg.norm(L, axis=1, keepdims=True), V / np.linalg.norm(V, axis=1, keepdims=True)
    a, b = file.eval(L, V), builtin.eval(L, V)
    assert np.allclose(a, b, rtol=1e-12, atol=1e-300)
    theta = np.arccos([0.8, 0.2])
    e = bn.albedo(file, theta, rtol=1e-9, backend="numpy").value
    assert np.abs(e - albedo_fit(np.cos(theta), 0.3)[:, None] * [0.9, 0.5, 0.2]).max() <= 1e-9
