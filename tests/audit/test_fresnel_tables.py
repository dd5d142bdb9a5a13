"""brdfnorm audit (issue 29): tables carrying the exact dielectric Fresnel factor — E_dielectric over (μ, α) at an
index of refraction η the audit finds, and E_f0_dielectric over an f0 axis (η = (1 + √f0)/(1 − √f0)).

Independent routes: the reference values are checked against composite Gauss-Legendre over the half vector
(helpers/references.py) of the Fresnel-free lobe times the dielectric reflectance written out here (Walter et al. 2007
eq. 22), which shares no code with brdfnorm's Fresnel or integrators; the tables are made by ``lut.compute``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers.references import half_vector_gauss_legendre

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.audit import audit
from brdfnorm.audit.reference import Reference

GGX = bn.load("ggx")
N = 8
T_TEXEL = (np.arange(N) + 0.5) / N


def _reflectance(cos: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarized reflectance of a dielectric interface, as the textbook writes it: (R_s + R_p)/2 from Snell's
    law (total internal reflection cannot happen for η > 1 seen from outside)."""
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos * cos)) / eta
    cos_t = np.sqrt(1.0 - sin_t * sin_t)
    rs = (cos - eta * cos_t) / (cos + eta * cos_t)
    rp = (eta * cos - cos_t) / (eta * cos + cos_t)
    return 0.5 * (rs * rs + rp * rp)


class _WithReflectance:
    """The Fresnel-free GGX lobe times _reflectance(V·H, η): the model the Gauss-Legendre route integrates."""

    def __init__(self, alpha: float, eta: float, shadowing: str = "height-correlated") -> None:
        self.lobe = GGX.with_params(alpha=alpha, shadowing=shadowing)
        self.eta = eta

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        H = L + V
        H = H / np.linalg.norm(H, axis=-1, keepdims=True)
        return self.lobe.eval(L, V) * _reflectance(np.sum(H * V, axis=-1), self.eta)[:, None]


def _gauss_legendre(mu: float, alpha: float, eta: float) -> float:
    V = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
    return float(half_vector_gauss_legendre(_WithReflectance(alpha, eta), V, 48, 128))


def _table(eta: float, n: int = N) -> np.ndarray:
    t = (np.arange(n) + 0.5) / n
    model = GGX.with_params(fresnel="dielectric", eta=eta)
    return lut.compute(model, {"mu": t, "alpha": t * t}, rtol=1e-10, average=False)["E"]


@pytest.mark.parametrize("mu, alpha, eta", [(0.9, 0.3, 1.5), (0.2, 0.6, 1.33), (0.05, 0.1, 2.4)])
def test_reference_equals_gauss_legendre_with_the_textbook_reflectance(mu, alpha, eta):
    value, error = Reference(GGX).meaning("E_dielectric", "height-correlated", np.array(mu), np.array(alpha),
                                          eta=eta)
    assert abs(float(value) - _gauss_legendre(mu, alpha, eta)) <= max(float(error), 0.0) + 1e-9


def test_f0_axis_ends_and_the_bracket_beyond_the_largest_index():
    """f0 = 0 reflects nothing (η = 1), f0 = 1 is E (F = 1); between the largest η the lobe takes (1000) and
    f0 = 1 the value is a bracket whose error estimate covers the truth (η ≈ 4000 integrated here)."""
    ref = Reference(GGX)
    mu, alpha = np.full(3, 0.4), np.full(3, 0.5)
    value, error = ref.meaning("E_f0_dielectric", "height-correlated", mu, alpha, np.array([0.0, 0.999, 1.0]))
    E, _ = ref.meaning("E", "height-correlated", mu[:1], alpha[:1])
    assert value[0] == 0.0 and value[2] == E[0]
    eta = (1 + np.sqrt(0.999)) / (1 - np.sqrt(0.999))
    truth = _gauss_legendre(0.4, 0.5, eta)
    assert abs(value[1] - truth) <= error[1] and error[1] < 2e-3


@pytest.mark.parametrize("eta", [1.5, 1.33])
def test_exact_fresnel_table_is_named_with_its_index(eta):
    """A 2-D table of ∫ f cos F(η, V·H): the exact-Fresnel round runs because nothing else fits, ranks geometries
    at η = 1.5 and finds η by root-finding; the fit is at the reference's precision."""
    r = audit(_table(eta), "ggx", dense=False, sweep=False)
    c = r.best.convention
    assert r.fits and c.meanings == ("E_dielectric",) and (c.direction, c.roughness) == ("mu-texel", "r2-texel")
    assert abs(c.eta - eta) < 1e-5 and r.best.channels[0].max < 1e-7


def test_pinned_index_is_used_and_a_wrong_one_does_not_fit(capsys):
    table = _table(1.33)
    assert audit(table, "ggx", dense=False, sweep=False, eta="1.33").best.convention.eta == 1.33
    wrong = audit(table, "ggx", dense=False, sweep=False, eta="1.5")
    assert not wrong.fits and wrong.best.channels[0].max > 1e-2


def test_cli_reports_eta_and_refuses_bad_pins(tmp_path, run_cli):
    path = tmp_path / "fresnel.npz"
    np.savez(path, E=_table(1.5).astype(np.float32))
    code, stdout, _ = run_cli("audit", str(path), "--model", "ggx", "--json", "--no-sweep",
                              "--no-interpolation", "--as", "channels=E_dielectric")
    out = json.loads(stdout)
    assert code == 0 and out["best"]["convention"]["channels"] == ["E_dielectric"]
    assert abs(out["best"]["convention"]["eta"] - 1.5) < 1e-5
    for pin, message in (("eta=0.5", "eta must lie in (1, 1000]"), ("eta=x", "eta must be a number")):
        code, _, err = run_cli("audit", str(path), "--model", "ggx", "--as", pin)
        assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    # a lobe without a dielectric Fresnel factor cannot carry the meaning
    code, _, err = run_cli("audit", str(path), "--model", "beckmann-dielectric", "--as",
                           "channels=E_dielectric")
    assert code == 2 and "fresnel" in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_three_axes_with_the_exact_factor_over_f0_and_its_fix(tmp_path):
    """A uint16 E(f0, α, μ) table with the exact dielectric factor: Schlick's E_f0 misses it (by more than its
    storage step), E_f0_dielectric is named, and the fix reproduces the reference."""
    n = 8
    f0, alpha, mu = np.linspace(0.0, 1.0, n), np.linspace(0.0, 1.0, n), (np.arange(n) + 0.5) / n
    F, A, M = np.meshgrid(f0, np.maximum(alpha, 1e-8), mu, indexing="ij")
    root = np.sqrt(np.minimum(F, 0.99))
    values = np.empty(F.shape)
    inside = F < 1.0
    cells = lut.compute_cells(GGX.with_params(fresnel="dielectric"), np.arccos(M[inside]),
                                    {"alpha": A[inside], "eta": ((1 + root) / (1 - root))[inside]}, rtol=1e-10)
    values[inside] = cells.value[:, 0]
    values[~inside] = lut.compute_cells(GGX, np.arccos(M[~inside]), {"alpha": A[~inside]},
                                              rtol=1e-10).value[:, 0]
    codes = np.rint(values * 65535) / 65535
    r = audit(codes, "ggx", read={"dtype": "uint16"}, sweep=False)
    c = r.best.convention
    assert r.fits and c.meanings == ("E_f0_dielectric",) and c.f0_axis == 0 and c.direction == "mu-texel"
    assert r.best.channels[0].max <= 0.5 / 65535 + 1e-6
    schlick = audit(codes, "ggx", read={"dtype": "uint16"}, sweep=False, dense=False, channels="E_f0")
    assert not schlick.fits and schlick.best.channels[0].max > 1e-3
    # the fix changes only the cells outside the tolerance: every cell ends within it of the exact table
    assert np.max(np.abs(r.fixed[..., 0] - values)) <= r.best.channels[0].tolerance


def _schlick_reflectance(cos: np.ndarray, f0: float) -> np.ndarray:
    return f0 + (1.0 - f0) * (1.0 - cos) ** 5


@pytest.mark.parametrize("f0", [0.04, 0.5])
def test_schlick_table_at_one_f0_is_named_with_its_f0(f0):
    """A 2-D table of ∫ f cos F_Schlick(f0, f90 = 1), made by the lobe's own fresnel=schlick: the audit names
    E_schlick and finds f0 by least squares (f0·(E − F90) + F90 is linear in it); a wrong pinned f0 does not fit.
    The worst cell is checked against Gauss-Legendre of the Fresnel-free lobe times Schlick's factor."""
    t = (np.arange(N) + 0.5) / N
    model = GGX.with_params(fresnel="schlick", f0=f0, f90=1.0)
    table = lut.compute(model, {"mu": t, "alpha": t * t}, rtol=1e-10, average=False)["E"]
    r = audit(table, "ggx", dense=False, sweep=False)
    c, fit = r.best.convention, r.best.channels[0]
    assert r.fits and c.meanings == ("E_schlick",) and abs(c.schlick_f0 - f0) < 1e-6 and fit.max < 1e-7
    mu = fit.worst_at["mu"]
    alpha = fit.worst_at["alpha"] if "alpha" in fit.worst_at else fit.worst_at["r"] ** 2  # as the table stores it

    class Schlick(_WithReflectance):
        def eval(self, L, V):
            H = (L + V) / np.linalg.norm(L + V, axis=-1, keepdims=True)
            return self.lobe.eval(L, V) * _schlick_reflectance(np.sum(H * V, axis=-1), f0)[:, None]

    V = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
    exact = float(half_vector_gauss_legendre(Schlick(alpha, 1.5), V, 48, 128))
    assert abs(table[fit.worst] - exact) < 1e-7
    wrong = audit(table, "ggx", dense=False, sweep=False, channels="E_schlick", schlick_f0=str(f0 + 0.02))
    assert not wrong.fits and wrong.best.convention.schlick_f0 == pytest.approx(f0 + 0.02)
