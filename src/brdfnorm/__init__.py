"""brdfnorm: exact energy normalization of analytic BRDFs.

Directional albedo E(V) = ∫ f(L, V)(N·L) dL over the upper hemisphere (seed 002's statement), normalization
factors 1/E under a named convention, fits of cheap formulas, shader code, and checks of the seed articles.
Frame: N = +z, X = +x, Y = +y; angles in radians in the API, degrees on the command line.
"""

from __future__ import annotations

__version__ = "0.1.0"
