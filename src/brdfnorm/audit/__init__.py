"""``brdfnorm.audit``: how wrong is a table (or a fitted formula) someone ships, in which convention, and its
exact drop-in replacement.

Modules: :mod:`.readers` (every format, decoded by the reader core :mod:`brdfnorm.inputs`: array literals in
C/GLSL/HLSL/JavaScript by :mod:`brdfnorm.inputs.literals`, PNG by :mod:`brdfnorm.inputs.png`),
:mod:`.conventions` (the declared hypothesis space), :mod:`.reference`
(exact values, cached), :mod:`.infer` (the search), :mod:`.quality` (interpolation error, error against
resolution), :mod:`.fix` (the replacement file), :mod:`.formula` (fits as expressions or GLSL functions),
:mod:`.report` (terminal text and PNG figures), :mod:`.api` (:func:`audit`).
"""

from .api import AuditResult, audit

__all__ = ["AuditResult", "audit"]
