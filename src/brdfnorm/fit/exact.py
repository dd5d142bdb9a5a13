"""Exact normalization factors as a fit form: ``fit --form closed-form`` (and ``--form auto``, which prefers it).

Where a lobe's factor at L = N has a closed form, a fitted rational is both costlier and less accurate than the
formula itself. Seed 000 derives them: original Phong 1/E = (n + 1)/2π, modified Phong (n + 2)/2π, and
Blinn-Phong α(n) = (n + 2)(n + 4)/(8π(2^(−n/2) + n)) (:mod:`brdfnorm.models.closed_forms`, each checked against
quadrature by ``brdfnorm verify``). :class:`ExactForm` has no coefficients; its error on the samples is measured
against the quadrature factor like any fit's, so a wrong formula would show as a large error.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..models import closed_forms
from .families import Form

TWO_PI = 2.0 * np.pi
EIGHT_PI = 8.0 * np.pi


@dataclass(frozen=True)
class Exact:
    """One lobe's exact factor at L = N as a function of ``parameter``: numpy, text, and code."""

    parameter: str
    factor: Callable[[np.ndarray], np.ndarray]
    text: str  # with {x} for the variable
    #: (variable, literal, power) -> expression; ``power(base, exponent)`` spells a power in the target language
    code: Callable[[str, Callable[[float], str], Callable[[str, str], str]], str]
    operations: dict


#: The lobes whose factor at L = N (``--at normal``) has a closed form, by model name.
EXACT: dict[str, Exact] = {
    "phong": Exact("n", lambda n: 1.0 / closed_forms.phong_original_albedo_normal(n), "({x} + 1)/(2π)",
                   lambda x, lit, pw: f"({x} + 1.0) * {lit(1.0 / TWO_PI)}", {"add": 1, "mul": 1}),
    "modified-phong": Exact("n", lambda n: 1.0 / closed_forms.phong_modified_albedo_normal(n), "({x} + 2)/(2π)",
                            lambda x, lit, pw: f"({x} + 2.0) * {lit(1.0 / TWO_PI)}", {"add": 1, "mul": 1}),
    "blinn-phong": Exact("n", lambda n: 1.0 / closed_forms.blinn_phong_albedo_normal(n),
                         "({x} + 2)({x} + 4)/(8π(2^(−{x}/2) + {x}))",
                         lambda x, lit, pw: f"({x} + 2.0) * ({x} + 4.0) / ({lit(EIGHT_PI)} * "
                                            f"({pw('2.0', f'-0.5 * {x}')} + {x}))",
                         {"add": 3, "mul": 3, "div": 1, "pow": 1}),
}


@dataclass(frozen=True)
class ExactForm(Form):
    """The closed-form factor of one lobe (no coefficients)."""

    model: str = ""
    spec: str = "closed-form"
    n_coefficients: int = 0
    two_d: bool = False

    @property
    def exact(self) -> Exact:
        return EXACT[self.model]

    def evaluate(self, c, x, t=None):
        return self.exact.factor(np.asarray(x, dtype=float))

    def fit(self, x, t, y, metric):
        return np.empty(0)

    def expression(self, c: Sequence[float], x: str, t: str) -> str:
        return self.exact.text.format(x=x)

    def operations(self) -> dict[str, int]:
        return dict(self.exact.operations)

    def code(self, x: str, literal: Callable[[float], str], power: Callable[[str, str], str]) -> str:
        """The expression in a target language (``literal`` spells a float, ``power`` a power)."""
        return self.exact.code(x, literal, power)


def exact_form(model_name: str, parameter: str, at: str) -> ExactForm | None:
    """The closed form of ``model_name``'s factor over ``parameter`` at ``at``, or None when there is none (only
    at L = N, and only over the parameter the formula is written in)."""
    exact = EXACT.get(model_name)
    if exact is None or at != "normal" or parameter != exact.parameter:
        return None
    return ExactForm(model=model_name)
