"""What generated native shader modules import: the exception a run-time bound raises inside compiled code.

Generated code raises ``NativeLimit(code)`` with a small integer only (nothing of the shader's text reaches the
generated source); :func:`brdfnorm.glsl.native.limit_error` turns it into the
:class:`~brdfnorm.errors.EvaluationError` the numpy backend raises, naming the loop's ``FILE:LINE:COL``.
"""

from __future__ import annotations


class NativeLimit(Exception):  # noqa: N818 - the name says what it is: a bound of brdfnorm.glsl.limits hit
    """A loop bound of :mod:`brdfnorm.glsl.limits` hit inside a compiled shader; ``args[0]`` is the code
    (loop index × 3 + which bound: per loop, total iterations, nodes run in loops)."""
