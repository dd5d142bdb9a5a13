"""Hostile API calls (issue 14, class 9): every one raises one of the project's errors — a BrdfnormError that is
also a ValueError or a TypeError, so callers may catch either — with the argument named; nothing is cast
silently (complex numbers, dates, text, bools as numbers), and no raw numpy/Python exception escapes."""

from __future__ import annotations

import datetime
import decimal
import fractions
from pathlib import Path

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.claims.verify import check_exponents, verify
from brdfnorm.engine.routes.series import blinn_phong_albedo_series
from brdfnorm.errors import BrdfnormError
from brdfnorm.fit import fit, parse_form
from brdfnorm.fit.codegen import emit

BP = bn.load("blinn-phong", n=8)
LAMBERT = bn.load("lambert")
X = np.linspace(1.0, 10.0, 12)
Y = 1.0 + 0.5 * X

#: Values no real-number argument accepts.
NOT_REAL = {
    "text": "abc", "numeric-text": "0.5", "bytes": b"0.5", "none": None, "complex": 1j, "complex-real": 0.5 + 0j,
    "complex-array": np.array([0.1 + 0j]), "datetime": datetime.datetime(2026, 1, 1),
    "np-datetime": np.datetime64("2026-01-01"), "timedelta": datetime.timedelta(1), "bool": True,
    "np-bool": np.bool_(False), "dict": {"a": 1}, "set": {0.1}, "object": object(), "nan": float("nan"),
    "inf": float("inf"), "huge-int": 10**400, "ragged": [[0.1], [0.1, 0.2]], "list-of-text": ["0.1"],
    "decimal-nan": decimal.Decimal("nan"),
}

CALLS = {
    **{f"albedo-theta-{k}": (lambda v=v: bn.albedo(BP, v)) for k, v in NOT_REAL.items()},
    **{f"albedo-phi-{k}": (lambda v=v: bn.albedo(BP, 0.1, v)) for k, v in NOT_REAL.items()
       if k != "numeric-text"},
    **{f"albedo-rtol-{k}": (lambda v=v: bn.albedo(BP, 0.1, rtol=v)) for k, v in NOT_REAL.items()},
    **{f"load-n-{k}": (lambda v=v: bn.load("blinn-phong", n=v)) for k, v in NOT_REAL.items()
       if k != "numeric-text"},  # text is a command-line value: "0.5" parses as the number it spells
    "albedo-theta-negative": lambda: bn.albedo(BP, -0.1),
    "albedo-theta-90": lambda: bn.albedo(BP, np.pi / 2),
    "albedo-theta-degrees": lambda: bn.albedo(BP, 45.0),
    "albedo-rtol-negative": lambda: bn.albedo(BP, 0.1, rtol=-1e-6),
    "albedo-rtol-one": lambda: bn.albedo(BP, 0.1, rtol=1.0),
    "albedo-rtol-tiny": lambda: bn.albedo(BP, 0.1, rtol=1e-20),
    "albedo-atol-text": lambda: bn.albedo(BP, 0.1, atol="0"),
    "albedo-rtol-array": lambda: bn.albedo(BP, 0.1, rtol=[1e-6, 1e-8]),
    "albedo-method-list": lambda: bn.albedo(BP, 0.1, method=["quadrature"]),
    "albedo-method-none": lambda: bn.albedo(BP, 0.1, method=None),
    "albedo-method-unknown": lambda: bn.albedo(BP, 0.1, method="magic"),
    "albedo-method-not-applicable": lambda: bn.albedo(LAMBERT, 0.1, method="series"),
    "albedo-over-list": lambda: bn.albedo(BP, 0.1, over=["light"]),
    "albedo-over-array": lambda: bn.albedo(BP, 0.1, over=np.array(["light", "view"])),
    "albedo-over-unknown": lambda: bn.albedo(BP, 0.1, over="sideways"),
    "albedo-nonfinite-bool": lambda: bn.albedo(BP, 0.1, nonfinite=True),
    "albedo-model-none": lambda: bn.albedo(None, 0.1),
    "albedo-model-name": lambda: bn.albedo("blinn-phong", 0.1),
    "albedo-model-class": lambda: bn.albedo(type(BP), 0.1),
    "albedo-shapes": lambda: bn.albedo(BP, np.zeros(3), np.zeros(4)),
    "albedo-max-evaluations-float": lambda: bn.albedo(BP, 0.1, max_evaluations=1.5),
    "albedo-max-evaluations-zero": lambda: bn.albedo(BP, 0.1, max_evaluations=0),
    "albedo-too-many-integrals": lambda: bn.albedo(BP.with_params(n=np.ones((20_000, 1))), np.zeros(1000)),
    "normalize-at-list": lambda: bn.normalize(BP, at=["max"]),
    "normalize-at-unknown": lambda: bn.normalize(BP, at="maximum"),
    "normalize-sweep-list": lambda: bn.normalize(BP, sweep=[1, 2, 3]),
    "normalize-sweep-tuple": lambda: bn.normalize(BP, sweep=("n", [1, 2])),
    "normalize-sweep-two": lambda: bn.normalize(BP, sweep={"n": [1], "m": [2]}),
    "normalize-sweep-unknown": lambda: bn.normalize(BP, sweep={"m": [1, 2]}),
    "normalize-sweep-text-values": lambda: bn.normalize(BP, sweep={"n": "1,2"}),
    "normalize-sweep-complex": lambda: bn.normalize(BP, sweep={"n": [1 + 1j]}),
    "normalize-sweep-empty": lambda: bn.normalize(BP, sweep={"n": []}),
    "normalize-sweep-nan": lambda: bn.normalize(BP, sweep={"n": [np.nan]}),
    "normalize-sweep-int-key": lambda: bn.normalize(BP, sweep={1: [1.0]}),
    "normalize-view-no-theta": lambda: bn.normalize(BP, at="view"),
    "normalize-view-theta-text": lambda: bn.normalize(BP, at="view", theta="0,1"),
    "normalize-search-points": lambda: bn.normalize(BP, at="max", search_points=10**9),
    "normalize-model-none": lambda: bn.normalize(None),
    "eval-L-2d": lambda: BP.eval(np.zeros((4, 2)), np.array([0, 0, 1.0])),
    "eval-V-scalar": lambda: BP.eval(np.array([0, 0, 1.0]), 1.0),
    "eval-not-broadcast": lambda: BP.eval(np.zeros((4, 3)), np.zeros((5, 3))),
    "eval-complex": lambda: BP.eval(np.array([0, 0, 1j]), np.array([0, 0, 1.0])),
    "eval-text": lambda: BP.eval("up", np.array([0, 0, 1.0])),
    "eval-nan": lambda: BP.eval(np.array([0, 0, np.nan]), np.array([0, 0, 1.0])),
    "load-none": lambda: bn.load(None),
    "load-int": lambda: bn.load(3),
    "load-bytes": lambda: bn.load(b"blinn-phong"),
    "load-unknown": lambda: bn.load("blinn-phong-typo"),
    "load-directory": lambda: bn.load(Path(__file__).parent),
    "load-unknown-parameter": lambda: bn.load("blinn-phong", m=3),
    "load-negative-n": lambda: bn.load("blinn-phong", n=-1),
    "load-n-fraction-huge": lambda: bn.load("blinn-phong", n=fractions.Fraction(10**400, 3)),
    "load-reflectance-above-range": lambda: bn.load("lambert", reflectance=[0.1, 1.5]),
    "with-params-complex": lambda: BP.with_params(n=2 + 0j),
    "parameter-unhashable": lambda: BP.parameter(["n"]),
    "series-n-text": lambda: blinn_phong_albedo_series("8", 0.1),
    "series-theta-complex": lambda: blinn_phong_albedo_series(8.0, 0.1j),
    "series-rtol-none": lambda: blinn_phong_albedo_series(8.0, 0.1, rtol=None),
    "fit-metric-list": lambda: fit(X, Y, form="linear", metric=["abs-lsq"]),
    "fit-metric-unknown": lambda: fit(X, Y, form="linear", metric="l1"),
    "fit-form-none": lambda: fit(X, Y, form=None),
    "fit-form-list": lambda: fit(X, Y, form=["linear"]),
    "fit-form-unknown": lambda: fit(X, Y, form="spline:3"),
    "fit-target-none": lambda: fit(X, Y, target=None),
    "fit-target-negative": lambda: fit(X, Y, target=-1.0),
    "fit-max-coefficients-float": lambda: fit(X, Y, max_coefficients=3.5),
    "fit-names-text": lambda: fit(X, Y, form="linear", names="n"),
    "fit-x-text": lambda: fit("1,2,3", Y, form="linear"),
    "fit-y-complex": lambda: fit(X, Y + 0j, form="linear"),
    "fit-x-datetime": lambda: fit(np.array(["2026-01-01"] * 12, dtype="datetime64[D]"), Y, form="linear"),
    "fit-sizes": lambda: fit(X[:5], Y, form="linear"),
    "parse-form-int": lambda: parse_form(3),
    "parse-form-auto": lambda: parse_form("auto"),
    "emit-language-list": lambda: emit(fit(X, Y, form="linear"), ["c"], "m"),
    "emit-language-unknown": lambda: emit(fit(X, Y, form="linear"), "rust", "m"),
    "verify-exponents-text": lambda: check_exponents("1,2"),
    "verify-exponents-complex": lambda: check_exponents([1j]),
    "verify-only-unknown": lambda: verify([2.0], only=["no-such-claim"]),
    "verify-only-int": lambda: verify([2.0], only=[3]),
}


def test_there_are_at_least_90_hostile_calls():
    assert len(CALLS) >= 90


@pytest.mark.parametrize("name", sorted(CALLS))
def test_hostile_call_raises_a_project_error(name):
    with np.errstate(all="raise"):  # and no silent numpy float error on the way
        with pytest.raises(BrdfnormError) as caught:
            CALLS[name]()
    error = caught.value
    assert isinstance(error, (ValueError, TypeError)), type(error).__mro__
    assert error.where, f"{name}: the error names no argument: {error}"
    assert len(str(error)) < 600 and "\n" not in str(error)


@pytest.mark.parametrize("value", [np.complex128(0.5), np.array([0.5 + 0j]), datetime.date(2026, 1, 1)])
def test_complex_and_date_values_are_refused_not_cast(value):
    with pytest.raises(TypeError):
        bn.load("blinn-phong", n=value)


def test_large_finite_numbers_are_finite():
    """2e307 is a float64 number like any other: a parameter without an upper limit accepts it."""
    assert bn.load("blinn-phong", n=2e307).params["n"] == 2e307
