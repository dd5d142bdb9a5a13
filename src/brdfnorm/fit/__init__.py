"""Cheap formulas fitted to sampled normalization factors or tables, with their error, and emitted as code.

- :mod:`.fitting` — the fitting driver: :func:`fit`, the form names (:data:`FORMS`, :func:`parse_form`), the
  metrics and :class:`FitResult`.
- :mod:`.families` — the formula families (polynomial, rational, hyperbola, Smith) and their solvers.
- :mod:`.exact` — the exact factors of :mod:`brdfnorm.models.closed_forms` as a form without coefficients
  (``--form closed-form``).
- :mod:`.codegen` — a fitted formula as a GLSL, HLSL, C or Python function.

``from brdfnorm.fit import fit`` keeps working: this package exports the fitting driver's public names.
"""

from __future__ import annotations

from .families import Form, HyperbolaForm, RationalForm, SmithForm
from .fitting import (
    AUTO_MAX_COEFFICIENTS,
    DEGENERATE,
    FORMS,
    METRICS,
    FitResult,
    auto_candidates,
    fit,
    parse_form,
    smith_candidates,
)

__all__ = ["AUTO_MAX_COEFFICIENTS", "DEGENERATE", "FORMS", "METRICS", "FitResult", "Form", "HyperbolaForm",
           "RationalForm", "SmithForm", "auto_candidates", "fit", "parse_form", "smith_candidates"]
