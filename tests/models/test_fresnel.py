"""The Fresnel family and its exact averages (brdfnorm.models.fresnel) against mpmath quadrature of independently
written formulas (complex Fresnel equations, Gulbrandsen's mapping restated)."""

import mpmath as mp
import numpy as np
import pytest

from brdfnorm.errors import ArgumentError
from brdfnorm.models.fresnel import (
    MU_BAR,
    Fresnel,
    artistic_to_complex,
    audit_artistic_fit,
    f82_tint,
    kulla_conty_artistic_fit,
    multiple_scattering_colour,
    schlick,
)

mp.mp.dps = 30


def mp_fresnel(mu, eta, k=0.0):
    """(|r_s|² + |r_p|²)/2 for the complex index n = η + ik, from Snell's law with complex cos θ_t."""
    n = mp.mpc(eta, k)
    cos_t = mp.sqrt(1 - (1 - mu * mu) / (n * n))
    rs = (mu - n * cos_t) / (mu + n * cos_t)
    rp = (n * mu - cos_t) / (n * mu + cos_t)
    return min(mp.mpf(1), (abs(rs) ** 2 + abs(rp) ** 2) / 2)


def mp_average(function, breaks=(0, 1)):
    return 2 * mp.quad(lambda mu: mu * function(mu), list(breaks))


@pytest.mark.parametrize("f0", [0.0, 0.02, 0.04, 0.5, 0.9, 1.0])
def test_schlick_average_is_f0_plus_one_21st(f0):
    value, error = Fresnel("schlick", f0=f0).average()
    assert abs(float(value) - (f0 + (1 - f0) / 21)) <= 1e-15
    reference = mp_average(lambda mu: f0 + (1 - f0) * (1 - mu) ** 5)
    assert abs(float(value) - float(reference)) <= max(float(error), 1e-15)


@pytest.mark.parametrize("p", [1.0, 2.5, 5.0, 7.3])
def test_generalized_schlick_average(p):
    value, _ = Fresnel("generalized-schlick", f0=0.2, f90=0.7, exponent=p).average()
    reference = mp_average(lambda mu: 0.2 + 0.5 * (1 - mu) ** p)
    assert abs(float(value) - float(reference)) <= 1e-15
    assert np.allclose(Fresnel("generalized-schlick", f0=0.2, f90=0.7, exponent=p)(0.3), 0.2 + 0.5 * 0.7**p)


@pytest.mark.parametrize("f0,tint", [(0.9, 1.0), (0.9, 0.6), (0.5, 0.2), (0.04, 0.0), (0.98, 0.9)])
def test_f82_tint_hits_its_edge_and_averages_exactly(f0, tint):
    s_bar = f0 + (1 - f0) * (1 - MU_BAR) ** 5
    assert abs(float(f82_tint(MU_BAR, f0, tint)) - tint * s_bar) <= 1e-15
    value, error = Fresnel("f82-tint", f0=f0, tint=tint).average()
    mf0, mt = mp.mpf(f0), mp.mpf(tint)
    bar = mp.mpf(1) / 7
    s = lambda mu: mf0 + (1 - mf0) * (1 - mu) ** 5  # noqa: E731
    reference = mp_average(lambda mu: s(mu) - mu * (1 - mu) ** 6 / (bar * (1 - bar) ** 6) * (s(bar) - mt * s(bar)))
    assert abs(float(value) - float(reference)) <= 1e-14
    assert abs(float(value) - float(reference)) <= float(error)


@pytest.mark.parametrize("eta,k", [(0.2, 3.0), (1.5, 1e-4), (0.5, 0.01), (2.0, 4.0), (0.05, 0.5), (1.1, 0.0)])
def test_conductor_average_against_mpmath(eta, k):
    value, error = Fresnel("conductor", eta=eta, k=k).average()
    breaks = (0, float(mp.sqrt(1 - eta * eta)), 1) if eta < 1 else (0, 1)
    reference = float(mp_average(lambda mu: mp_fresnel(mu, eta, k), breaks))
    assert abs(float(value) - reference) <= 1e-12
    assert abs(float(value) - reference) <= float(error)  # an honest estimate
    assert float(error) <= 1e-12


@pytest.mark.parametrize("r,g", [(0.9, 0.9), (0.56, 1.0), (0.3, 0.0), (0.99, 0.5), (0.05, 0.7)])
def test_artistic_average_against_mpmath(r, g):
    mr, mg = mp.mpf(r), mp.mpf(g)
    n = mg * (1 - mr) / (1 + mr) + (1 - mg) * (1 + mp.sqrt(mr)) / (1 - mp.sqrt(mr))
    k = mp.sqrt(max(0, (mr * (n + 1) ** 2 - (n - 1) ** 2) / (1 - mr)))
    eta, kk = artistic_to_complex(r, g)
    assert abs(float(eta) - float(n)) <= 1e-14 * float(n)
    assert abs(float(kk) ** 2 - float(k) ** 2) <= 1e-12 * float(n + 1) ** 2  # k² cancels (g = 0, r → 1)
    assert abs(float(mp_fresnel(1, n, k)) - r) <= 1e-14  # Gulbrandsen: r is the normal reflectivity
    value, error = Fresnel("artistic", r=r, g=g).average()
    reference = float(mp_average(lambda mu: mp_fresnel(mu, n, k)))
    assert abs(float(value) - reference) <= min(1e-12, float(error))


@pytest.mark.parametrize("eta", [1.5, 1 / 1.5, 1.01, 3.0])
def test_dielectric_average_against_mpmath(eta):
    value, error = Fresnel("dielectric", eta=eta).average()
    breaks = (0, float(mp.sqrt(1 - eta * eta)), 1) if eta < 1 else (0, 1)
    reference = float(mp_average(lambda mu: mp_fresnel(mu, eta), breaks))
    assert abs(float(value) - reference) <= 1e-12


def test_channels_and_kulla_conty_colour():
    value, _ = Fresnel("conductor", eta=np.array([0.2, 1.1, 1.2]), k=np.array([3.9, 2.6, 2.4])).average()
    assert value.shape == (3,) and np.all((value > 0.5) & (value < 1))
    # F_avg = 1 keeps all the energy: F_ms = 1; F_avg = 0 gives none.
    assert multiple_scattering_colour(1.0, 0.7) == pytest.approx(1.0, abs=1e-16)
    assert multiple_scattering_colour(0.0, 0.7) == 0.0
    f, e = 0.8, 0.6  # the geometric series Σ F_avg (F_avg(1 − E_avg))^k · E_avg · F_avg... written out
    series = sum(f * e * (f * (1 - e)) ** j * f for j in range(400))
    assert multiple_scattering_colour(f, e) == pytest.approx(series, rel=1e-14)


def test_kulla_conty_fit_audit():
    audit = audit_artistic_fit(41, r_min=0.05)
    exact = float(mp_average(lambda mu: mp_fresnel(mu, *map(float, artistic_to_complex(audit.argmax_r,
                                                                                        audit.argmax_g)))))
    fit = float(kulla_conty_artistic_fit(audit.argmax_r, audit.argmax_g))
    assert abs(abs(fit - exact) - audit.max_error) <= 1e-12
    assert 0.04 < audit.max_error < 0.06  # the cubic is off by ~0.05 at g = 1, r ≈ 0.56


def test_bad_inputs():
    with pytest.raises(ArgumentError, match="r < 1"):
        artistic_to_complex(1.0, 0.5)
    with pytest.raises(ArgumentError, match="unknown Fresnel"):
        Fresnel("fancy")
    with pytest.raises(ArgumentError, match="exponent"):
        Fresnel("generalized-schlick", exponent=0.0)
    assert np.allclose(schlick(1.0, 0.3), 0.3)
