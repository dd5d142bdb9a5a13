"""Test helper: a Hypothesis strategy of example ``.brdf`` shaders with a few tokens replaced, inserted,
deleted or duplicated (moved from tests/glsl/test_hostile.py, issue 40 item 6)."""

from __future__ import annotations

import re

from hypothesis import strategies as st

from brdfnorm.brdffile import read_brdf
from helpers.paths import EXAMPLES as _EXAMPLES_DIR

EXAMPLES = sorted(_EXAMPLES_DIR.glob("*.brdf"))

VOCABULARY = [
    "09", "0x", "0xFFFFFFFFF", "4294967296", "99999999999999999999", "1e39", "1e-400", "-1u", "2147483647", "3u",
    "int", "uint", "float", "vec3", "mat4", "bool", "[", "]", "[1024]", "[0]", "[-1]", "[3]", "(", ")", "{", "}",
    ";", ",", ".", ".xyz", ".w", "++", "--", "+", "-", "*", "/", "%", "<<", ">>", "&", "|", "^", "^^", "~",
    "!", "==", "<", "?", ":", "=", "+=", "/=", "%=", "for", "while", "if", "else", "return", "break",
    "continue", "switch", "case", "default", "discard", "const", "uniform", "in", "out", "inout", "#define",
    "#undef", "\n", "true", "false", "L", "V", "N", "pow", "dot", "normalize", "length", "modf", "mix", "mod",
    "int(", "float[3](", ".length()", "BRDF", "0.0/0.0", "int(0.0/0.0)", "1.0/0.0", "// c", "/*", "*/", "#if",
]  # fmt: skip
_TOKEN = re.compile(r"\w+|\S")


@st.composite
def mutated_shaders(draw):
    brdf = read_brdf(draw(st.sampled_from(EXAMPLES)))
    tokens = _TOKEN.findall(brdf.shader.text)
    for _ in range(draw(st.integers(1, 4))):
        at = draw(st.integers(0, len(tokens)))
        action = draw(st.sampled_from(["replace", "insert", "delete", "duplicate"]))
        if action == "replace" and at < len(tokens):
            tokens[at] = draw(st.sampled_from(VOCABULARY))
        elif action == "insert":
            tokens.insert(at, draw(st.sampled_from(VOCABULARY)))
        elif action == "delete":
            del tokens[at : at + draw(st.integers(1, 6))]
        else:
            tokens[at:at] = tokens[at : at + draw(st.integers(1, 12))]
    return brdf, " ".join(tokens)
