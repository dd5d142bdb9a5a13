"""Run the seed articles' numerical claims (:mod:`brdfnorm.claims`), each a formula against independent numerics.

:data:`CHECKS` names the claims (one module per seed in :mod:`brdfnorm.claims`); :func:`verify` runs them and
:func:`certify` also checks the albedo-valued ones against guaranteed enclosures
(:mod:`brdfnorm.engine.routes.certified`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from .. import validate
from ..errors import ArgumentError
from ..registry import Registry
from . import DEFAULT_EXPONENTS, Claim, published, seed000, seed002, seed003

CHECKS: Registry[Callable[[np.ndarray], Claim]] = Registry("claim", "claim", {
    "phong-original": seed000.phong_original,
    "phong-modified": seed000.phong_modified,
    "blinn-phong-normal": seed000.blinn_phong_normal,
    "blinn-phong-n+8-approximation": seed000.blinn_phong_folklore,
    "phong-peak-at-normal": seed000.phong_peak,
    "blinn-phong-peak-at-normal": seed000.blinn_phong_peak,
    "bp-half-vector-length": seed002.half_vector_length,
    "bp-spherical-form": seed002.spherical_form,
    "bp-delta-theta-2f1": seed002.delta_theta_2f1,
    "bp-hypergeometric-series": seed002.hypergeometric_series,
    "bp-weierstrass": seed002.weierstrass,
    "stokes-cosine": seed002.stokes_cosine,
    "stokes-z-cubed-fails": seed002.stokes_z_cubed,
    "divergence-cosine": seed002.divergence_cosine,
    "gaussian-fit": seed003.gaussian_fit,
    "gaussian-fit-small-n-error": seed003.gaussian_small_n,
    "gaussian-hyperbola-beats-line": seed003.gaussian_hyperbola,
    # The second group: the field's published numbers (brdfnorm.claims.published).
    **published.CHECKS,
})
#: The group of each claim: the seed articles' claims, or the field's published numbers.
GROUPS = {claim_id: published.GROUP if claim_id in published.CHECKS else "seed claims" for claim_id in CHECKS}


def check_exponents(exponents: Sequence[float]) -> np.ndarray:
    """The exponents of the parametric claims: at least one, each in (0, 1e5]."""
    n = validate.real_array(exponents, "n").ravel()
    if n.size == 0:
        raise ArgumentError("give at least one exponent", where="n")
    if np.any(n <= 0) or np.any(n > 1e5):
        raise ArgumentError("exponents must be numbers in (0, 1e5]", where="n")
    return n


def verify(exponents: Sequence[float] = DEFAULT_EXPONENTS, only: Sequence[str] | None = None,
           certified: bool = False, digits: int = 30) -> list[Claim]:
    """Run the checks (all, or the ids in ``only``) at the given exponents for the parametric claims.

    ``certified``: also check every claim that is an albedo value against a guaranteed enclosure
    (:func:`certify`); a claim whose formula falls outside its enclosure is then not ok.
    """
    n = check_exponents(exponents)
    if isinstance(only, str):
        only = [only]
    ids = list(CHECKS) if only is None else [CHECKS.validate(i) for i in only]
    claims = [replace(CHECKS[i](n), group=GROUPS[i]) for i in ids]
    return [certify(claim, digits) for claim in claims] if certified else claims


#: Claims that are albedo values: id -> (model, view angle in degrees, whether the seed's formula is a closed form
#: (checked in ball arithmetic, brdfnorm.engine.routes.certified.NORMAL_INCIDENCE_CLOSED_FORMS) or a numerical
#: procedure (then it
#: must agree within the claim's tolerance)).
CERTIFIABLE: dict[str, tuple[str, float, bool]] = {
    "phong-original": ("phong", 0.0, True),
    "phong-modified": ("modified-phong", 0.0, True),
    "blinn-phong-normal": ("blinn-phong", 0.0, True),
    "bp-spherical-form": ("blinn-phong", 60.0, False),
    "bp-hypergeometric-series": ("blinn-phong", 45.0, False),
}
#: The tolerance of the claims whose formula is a float64 procedure (the claims' own, relative).
CERTIFIED_FLOAT_TOLERANCE = 1e-10


def certify(claim: Claim, digits: int = 30) -> Claim:
    """``claim`` with ``certified`` filled in: per exponent, the enclosure [lower, upper] of the albedo and whether
    the seed's formula lies inside it (closed forms, evaluated in Arb) or within the claim's tolerance of it
    (formulas that are float64 procedures). Claims that are not albedo values are returned unchanged."""
    if claim.id not in CERTIFIABLE:
        return claim
    from ..engine.routes import certified
    from ..extras import require

    flint = require("flint", "certified", where="certified")
    from ..models import REGISTRY

    model_name, degrees, closed_form = CERTIFIABLE[claim.id]
    cases = []
    for case in claim.cases:
        n = case["n"]
        (enclosure,) = certified.enclose(REGISTRY[model_name](n=n), np.radians(degrees), {"n": n}, digits=digits)
        if closed_form:
            inside = certified.closed_form_inside(model_name, n, enclosure)
        else:  # the claim's formula value is the albedo computed by the seed's procedure, in float64
            old, flint.ctx.prec = flint.ctx.prec, 4 * digits + 64
            try:
                value = flint.arb(float(case["formula_value"]))
                slack = CERTIFIED_FLOAT_TOLERANCE * abs(value)
                inside = bool(flint.arb(enclosure.lower) - slack <= value <= flint.arb(enclosure.upper) + slack)
            finally:
                flint.ctx.prec = old
        cases.append({"n": n, "lower": enclosure.lower, "upper": enclosure.upper, "inside": inside})
    summary = {"model": model_name, "theta_deg": degrees, "digits": digits, "exact_formula": closed_form,
               "ok": all(c["inside"] for c in cases), "cases": cases}
    return replace(claim, ok=claim.ok and summary["ok"], certified=summary)
