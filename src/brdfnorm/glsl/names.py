"""Names a shader cannot give to a variable, a parameter or a macro: GLSL keywords, types, built-ins.

The keyword and reserved-word lists are those of the OpenGL Shading Language 4.10 specification, §3.6;
type names are recognised by :mod:`.types`, built-in functions by :mod:`.builtins`. Importing this module
does not load tree-sitter (the ``.brdf`` reader checks parameter names before any GLSL is compiled).
"""

from __future__ import annotations

from . import builtins
from .types import parse_type_name, unsupported_type_feature

#: GLSL 4.10 §3.6 keywords (type names are matched by pattern in :func:`is_reserved`).
KEYWORDS = frozenset(
    """
    attribute const uniform varying buffer shared coherent volatile restrict readonly writeonly atomic_uint
    layout centroid flat smooth noperspective patch sample break continue do for while switch case default
    if else subroutine in out inout true false invariant precise discard return lowp mediump highp precision
    struct
    """.split()
)
#: GLSL 4.10 §3.6 words reserved for future use (an error when used).
RESERVED_WORDS = frozenset(
    """
    common partition active asm class union enum typedef template this resource goto inline noinline public
    static extern external interface long short half fixed unsigned superp input output hvec2 hvec3 hvec4
    fvec2 fvec3 fvec4 sampler3DRect filter sizeof cast namespace using
    """.split()
)
#: The entry point every ``.brdf`` shader defines.
ENTRY_POINT = "BRDF"


def reserved_kind(name: str) -> str | None:
    """What makes ``name`` unusable as a variable or macro name ("a GLSL keyword", ...), or None."""
    if name in KEYWORDS:
        return "a GLSL keyword"
    if name in RESERVED_WORDS:
        return "a word GLSL reserves"
    if parse_type_name(name) is not None or unsupported_type_feature(name) is not None:
        return "a GLSL type name"
    if builtins.is_builtin(name) or name in builtins.UNSUPPORTED:
        return "a GLSL built-in function"
    if name.startswith("gl_"):
        return "reserved for GLSL built-in variables (gl_ prefix)"
    return None


def is_reserved(name: str) -> bool:
    """Whether ``name`` is a keyword, reserved word, type name or built-in function of GLSL."""
    return reserved_kind(name) is not None
