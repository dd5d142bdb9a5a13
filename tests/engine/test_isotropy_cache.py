"""The per-stage isotropy cache of the generic route (brdfnorm.engine.routes.quadrature.isotropy_cache): a cached
verdict is what a fresh test returns, isotropic and not, per set of parameter values and rtol; within the block the
test runs once per set; outside it nothing is kept; a table's E_avg chain (lut.table.average_over_mu, which opens
one) gives the values, errors and counts it gives without the cache, bit for bit."""

from __future__ import annotations

import contextlib

import numpy as np
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.engine.methods import make_problem
from brdfnorm.engine.routes import quadrature
from brdfnorm.lut import table


def _problem(alpha_x, alpha_y):
    model = bn.load(str(EXAMPLES / "anisotropic_ggx.brdf"), alpha_x=np.asarray(alpha_x, dtype=float),
                    alpha_y=np.asarray(alpha_y, dtype=float))
    return make_problem(model, np.full(len(alpha_x), 0.6))


def _counted(monkeypatch):
    calls = []
    fresh = quadrature.rotation_invariant

    def counted(brdf, cases, rtol):
        calls.append(len(cases))
        return fresh(brdf, cases, rtol)

    monkeypatch.setattr(quadrature, "rotation_invariant", counted)
    return calls


def test_cached_verdicts_are_the_fresh_ones_and_each_set_is_tested_once(monkeypatch):
    problem = _problem([0.1, 0.1, 0.3, 0.1], [0.1, 0.4, 0.3, 0.1])  # isotropic, anisotropic, isotropic, repeated
    fresh = quadrature._isotropic_cases(problem, 1e-8)
    assert fresh.tolist() == [True, False, True, True]
    calls = _counted(monkeypatch)
    with quadrature.isotropy_cache() as verdicts:
        first = quadrature._isotropic_cases(problem, 1e-8)
        again = quadrature._isotropic_cases(problem, 1e-8)
        shuffled = quadrature._isotropic_cases(_problem([0.1, 0.3, 0.2], [0.4, 0.3, 0.2]), 1e-8)  # one new set
        looser = quadrature._isotropic_cases(problem, 1e-3)  # another rtol: another threshold, tested anew
    assert first.tolist() == again.tolist() == fresh.tolist() == looser.tolist()
    assert shuffled.tolist() == [False, True, True]
    assert calls == [3, 1, 3]  # three distinct sets, then only the new one, then the new rtol's three
    assert len(verdicts) == 7
    quadrature._isotropic_cases(problem, 1e-8)  # outside the block: tested again, nothing kept
    assert calls[-1] == 3


def test_average_over_mu_is_the_same_with_and_without_the_cache(monkeypatch):
    model = bn.load(str(EXAMPLES / "ggx.brdf"), f0=1.0)
    combos = {"roughness": np.array([0.1, 0.5])}
    cached = table.average_over_mu(model, combos, rtol=1e-6, threads=1)
    calls = _counted(monkeypatch)
    monkeypatch.setattr(table, "isotropy_cache", contextlib.nullcontext)
    plain = table.average_over_mu(model, combos, rtol=1e-6, threads=1)
    assert len(calls) > 2  # (without the cache every albedo call tests its sets again)
    for a, b in zip(cached, plain, strict=True):
        assert np.array_equal(np.asarray(a), np.asarray(b))
