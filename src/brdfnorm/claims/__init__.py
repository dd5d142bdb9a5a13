"""The seed articles' numerical claims, each re-checked: formula against independent numerics.

This package holds :class:`Claim` and its helpers; the claims themselves live in :mod:`.seed000`, :mod:`.seed002`
and :mod:`.seed003`, and :mod:`brdfnorm.claims.verify` runs them.

Seed 000 ("Phong Normalization Factor derivation"), seed 002 ("Energy-Normalizing Blinn–Phong Specular") and
seed 003 (the Gaussian Blinn-Phong BRDF Explorer shader and its fitted factor) state formulas and say
"validated numerically" or "I have no proof … experimental evidence". Each :class:`Claim` here recomputes one
statement by its formula and by a route that shares nothing with the formula's derivation — brdfnorm's adaptive
hemisphere cubature of the BRDF itself, mpmath at 30 digits, or a direct numerical integral of the seed's
own intermediate form — and its verdict ``ok`` is computed from the two, never written down. Where a seed shows
a step failing (Stokes's theorem with G = (0, 0, z³)), the claim is the failure, and ``ok`` says whether the
failure is reproduced.

Conventions: albedo E(V) = ∫ f(L, V)(N·L) dL with the view V fixed; the factor is 1/E. For the Phong lobes
the seed's "reflected energy for light L", ∫ (R·V)^n dV, is the same function of the fixed direction's polar
angle as E (R·V = L·mirror(V)), so the peak premises are checked on E.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

SOURCES = {
    "000": "seed 000 (Phong Normalization Factor derivation)",
    "002": "seed 002 (Energy-Normalizing Blinn–Phong Specular)",
    "003": "seed 003 (Gaussian Blinn-Phong, BRDF Explorer)",
}
DEFAULT_EXPONENTS = (1.0, 10.0, 100.0, 512.0)
#: Exponent range of the peak premises (issue 5: n ∈ [0.01, 1e4]).
PREMISE_EXPONENTS = np.geomspace(0.01, 1e4, 29)
PREMISE_THETA = np.radians(np.linspace(0.0, 89.9, 180))
GAUSSIAN_RANGE = (1.0, 512.0)

TWO_PI = 2.0 * np.pi


#: What a claim states about its two values A (``formula_value``: the seed's formula or side) and B
#: (``numeric_value``: the independent computation), in words a reader of a table needs.
RELATIONS = {
    "equal": "A = B",
    "differ": "A ≠ B (a claimed failure or error)",
    "less": "A < B",
    "peak": "A ≥ B (A at L = N; B the largest elsewhere)",
}


@dataclass(frozen=True)
class Claim:
    """One checked statement. ``rel_error`` = |formula − numeric| / |numeric| (or what ``detail`` says);
    ``ok`` is the verdict. ``relation`` (a key of :data:`RELATIONS`) says what the claim states about the two
    values, ``criterion`` the test the verdict applies, in words."""

    id: str
    source: str
    statement: str
    formula_value: float
    numeric_value: float
    rel_error: float
    ok: bool
    detail: str = ""
    cases: list[dict] = field(default_factory=list)
    #: With ``verify(certified=True)``: the albedo enclosures the claim was checked against (see :func:`certify`).
    certified: dict | None = None
    #: "seed claims" or "published numbers" (set by :func:`brdfnorm.claims.verify.verify`).
    group: str = ""
    relation: str = "equal"
    criterion: str = ""

    def as_dict(self) -> dict:
        return {
            **({} if self.certified is None else {"certified": self.certified}),
            "id": self.id,
            "group": self.group,
            "source": self.source,
            "statement": self.statement,
            "formula_value": float(self.formula_value),
            "numeric_value": float(self.numeric_value),
            "rel_error": float(self.rel_error),
            "ok": bool(self.ok),
            "detail": self.detail,
            "relation": self.relation,
            "criterion": self.criterion,
            "cases": self.cases,
        }


def rel_error(formula, numeric) -> np.ndarray:
    """|formula − numeric| / |numeric|, elementwise."""
    formula, numeric = np.asarray(formula, dtype=float), np.asarray(numeric, dtype=float)
    return np.abs(formula - numeric) / np.abs(numeric)


def parametric(claim_id: str, source: str, statement: str, n, formula, numeric, tol: float, detail: str = "") -> Claim:
    """A claim checked at several exponents: the row shows the worst one, ``cases`` all of them."""
    errors = rel_error(formula, numeric)
    worst = int(np.argmax(errors))
    cases = [
        {"n": float(k), "formula_value": float(f), "numeric_value": float(v), "rel_error": float(e)}
        for k, f, v, e in zip(n, formula, numeric, errors, strict=True)
    ]
    where = f"worst at n = {n[worst]:g} of n = {', '.join(f'{k:g}' for k in n)}; tolerance {tol:g}"
    return Claim(
        claim_id,
        SOURCES[source],
        statement,
        float(formula[worst]),
        float(numeric[worst]),
        float(errors[worst]),
        bool(np.all(errors <= tol)),
        f"{detail}; {where}" if detail else where,
        cases,
        criterion=f"|A − B| / |B| ≤ {tol:g} at every n",
    )


def quadrature_albedo(model_name: str, n: np.ndarray, theta: float = 0.0) -> np.ndarray:
    """brdfnorm's adaptive hemisphere cubature of the BRDF itself (no reduction to one dimension)."""
    from ..engine.methods import albedo
    from ..models import REGISTRY

    model = REGISTRY[model_name](n=np.asarray(n, dtype=float)[:, None])
    return albedo(model, theta, method="quadrature", rtol=1e-12).value.reshape(len(n))
