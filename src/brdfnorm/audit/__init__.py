"""``brdfnorm.audit``: how wrong is a table (or a fitted formula) someone ships, in which convention, and its
exact drop-in replacement.

Modules: :mod:`.readers` (every format, decoded by the reader core :mod:`brdfnorm.inputs`: array literals in
C/GLSL/HLSL/JavaScript by :mod:`brdfnorm.inputs.literals`, PNG by :mod:`brdfnorm.inputs.png`),
:mod:`.conventions` (the declared hypothesis space), :mod:`.reference`
(exact values, cached), :mod:`.infer` (the search), :mod:`.fits` (per-cell verdicts, ranking),
:mod:`.approximations` (fitted formulas engines ship), :mod:`.quality` (interpolation error, error against
resolution), :mod:`.fix` (the replacement file: only wrong cells rewritten), :mod:`.spans` (where a JSON or CSV
file's numbers stand), :mod:`.formula` (fits as expressions or GLSL functions), :mod:`.report` (terminal text,
PNG figures, the list of wrong cells), :mod:`.api` (:func:`audit`, the wrong cells).
"""

from .api import AuditResult, audit

__all__ = ["AuditResult", "audit"]
