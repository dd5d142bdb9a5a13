"""Hostile GLSL in ``.brdf`` shaders (issue 14, classes 4 and 10): bad shaders are bad input.

Every case is a :class:`~brdfnorm.errors.BrdfFileError` at the FILE:LINE:COL of the offending text (found by
searching the test's own text), or evaluates to what GLSL says (integer wrap-around, computed here with
Python integers); never another exception. A property test mutates the example shaders token by token with
GLSL vocabulary and requires that compiling and evaluating them raises nothing but the project's errors.
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers import paths
from helpers.brdf_files import DIRECTIONS, brdf_text, hang_guard, where, write
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from brdfnorm.brdffile import load_brdf, read_brdf
from brdfnorm.errors import BrdfFileError, BrdfnormError
from brdfnorm.glsl import compile_shader

EXAMPLES = sorted(paths.EXAMPLES.glob("*.brdf"))
SIGNATURE = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"


def refused(tmp_path: Path, body: str, needle: str, match: str, params: str = "float n 1 100 10") -> BrdfFileError:
    """The file made of ``body`` fails to load with ``match`` at the first ``needle``."""
    text = brdf_text(body, params)
    path = write(tmp_path, text)
    with pytest.raises(BrdfFileError, match=match) as info:
        load_brdf(path)
    assert (info.value.line, info.value.column) == where(text, needle), str(info.value)
    assert str(info.value).startswith(f"{path}:{info.value.line}:{info.value.column}: ")
    return info.value


def value_of(tmp_path: Path, body: str, **params) -> np.ndarray:
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # values outside the slider range
        return load_brdf(write(tmp_path, brdf_text(body)), **params).eval(*DIRECTIONS)


# -- class 4: internal errors for bad shaders become FILE:LINE:COL errors ----------------------------------


@pytest.mark.parametrize(
    ("statement", "needle", "match"),
    [
        ("int a = 09;", "09", "octal literals"),
        ("int a = 0779;", "0779", "octal literals"),
        ("int a = " + "7" * 5000 + ";", "7777", "out of range"),
        ("uint a = " + "1" * 5000 + "u;", "1111", "out of range"),
        ("float a = " + "3" * 5000 + ".0;", "3333", "out of range"),
        ("int a = 0x" + "f" * 5000 + ";", "0xfff", "out of range"),
        ("int a = 4294967296;", "4294967296", "out of range"),
        ("float a = 1e400;", "1e400", "out of range"),
        ("float a[int(1.0/0.0)];", "int(1.0/0.0)", "array size must be positive"),
        ("float a[int(0.0/0.0)];", "int(0.0/0.0)", "array size must be positive"),
        ("float a[65536 * 65536];", "65536 *", "array size must be positive"),  # wraps to 0
        ("vec3 a = L; float b = a[int(0.0/0.0)];", "int(0.0/0.0)", "index -2147483648 is out of range"),
        ("vec3 a = L; float b = a[65536 * 65536 + 5];", "65536", "index 5 is out of range"),
        ("float a[3]; a[int(1.0/0.0)] = 1.0;", "int(1.0/0.0)", "out of range"),
    ],
)
def test_bad_literals_sizes_and_constant_indices_are_located(tmp_path, statement, needle, match):
    body = SIGNATURE + " {\n    " + statement + "\n    return vec3(1.0);\n}"
    refused(tmp_path, body, needle, match)


@pytest.mark.parametrize(
    ("n", "expected"),
    [
        (7.0, [0.0, 0.0, 6.0]),  # i = 7·10^12 wraps to -796692480: out of range, the store is dropped
        (1e30, [5.0, 0.0, 10.0]),  # int(1e30) is INT_MIN (x86), and INT_MIN·10^12 wraps to 0
        (3e9, [5.0, 0.0, 10.0]),
    ],
)
def test_an_index_computed_from_a_parameter_that_overflows_wraps(tmp_path, n, expected):
    # An out-of-range index reads 0 and drops a store; int(n * 1e30) is INT_MIN: out of range. Nothing raises.
    body = (
        SIGNATURE
        + """ {
    float a[3] = float[3](1.0, 2.0, 3.0);
    int i = int(n) * 1000000 * 1000000;
    a[i] = 5.0;
    return vec3(a[i], a[int(n * 1e30)], a[0] + a[1] + a[2]);
}"""
    )
    assert ((7 * 10**12 + 2**31) % 2**32) - 2**31 == -796692480
    np.testing.assert_array_equal(value_of(tmp_path, body, n=n), [expected] * 2)


def test_a_global_read_before_its_initializer_ran_is_zero(tmp_path):
    # g's initializer calls f, which reads g: GLSL leaves the value undefined; here it is 0, never a crash.
    body = "float g = f() + 2.0;\nfloat f() { return g + 1.0; }\n" + SIGNATURE + " { return vec3(g); }"
    np.testing.assert_array_equal(value_of(tmp_path, body), [[3.0] * 3] * 2)


def test_a_global_in_its_own_initializer_is_not_yet_declared(tmp_path):
    # GLSL 4.10 §4.2.2: a variable's scope begins after its initializer.
    refused(tmp_path, "float g = g + 1.0;\n" + SIGNATURE + " { return vec3(g); }", "g + 1.0", "unknown identifier 'g'")


# -- class 10: macros, parameter names, uint wrap-around ---------------------------------------------------


@pytest.mark.parametrize("name", ["return", "for", "vec3", "float", "pow", "sampler2D", "double"])
def test_define_of_a_keyword_type_or_builtin_is_refused(tmp_path, name):
    body = f"#define {name} discard\n" + SIGNATURE + " { return vec3(1.0); }"
    refused(tmp_path, body, name + " discard", f"'#define {name}' redefines")


def test_define_of_a_user_function_name_is_refused(tmp_path):
    body = "#define f 1.0\nfloat f() { return 2.0; }\n" + SIGNATURE + " { return vec3(f()); }"
    refused(tmp_path, body, "f 1.0", "'#define f' redefines")


def test_define_with_a_trailing_comment_is_accepted_and_later_errors_keep_their_line(tmp_path):
    body = (
        "#define M 2.0 // a comment\n#define K (M + 1.0) /* another */\n"
        + SIGNATURE
        + " {\n    return vec3(M, K, M);\n}"
    )
    np.testing.assert_array_equal(value_of(tmp_path, body), [[2.0, 3.0, 2.0]] * 2)
    broken = body.replace("vec3(M, K, M)", "vec3(M, K, q)")
    refused(tmp_path, broken, "q)", "unknown identifier 'q'")


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        ("#define X 1.0\n" + SIGNATURE + " { return vec3(X); }", "BRDF"),  # a parameter of BRDF
        ("#define a 1.0\n" + SIGNATURE + " { float a = 2.0; return vec3(a); }", "a = 2.0"),
        ("#define g 1.0\nfloat g = 2.0;\n" + SIGNATURE + " { return vec3(g); }", "g = 2.0"),
    ],
    ids=["parameter", "local", "global"],
)
def test_a_declaration_of_a_defined_macro_name_is_refused(tmp_path, body, needle):
    # GLSL's preprocessor would replace the declared name (Mesa: a syntax error); silently declaring it is wrong.
    refused(tmp_path, body, needle, "while a macro of that name is defined")


def test_an_error_inside_a_macro_body_is_located_in_the_macro(tmp_path):
    body = "#define M (1.0 + q) // a comment\n" + SIGNATURE + " {\n    return vec3(M);\n}"
    refused(tmp_path, body, "q)", "unknown identifier 'q'")


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("for", "a GLSL keyword"),
        ("return", "a GLSL keyword"),
        ("vec3", "a GLSL type name"),
        ("mat2x3", "a GLSL type name"),
        ("sampler2D", "a GLSL type name"),
        ("BRDF", "entry point"),
        ("dot", "built-in function"),
        ("class", "reserves"),
        ("gl_Position", "gl_ prefix"),
    ],
)
def test_parameter_names_glsl_reserves_are_refused_at_their_position(tmp_path, name, kind):
    text = brdf_text(SIGNATURE + " { return vec3(1.0); }", f"float a 0 1 0.5\nfloat {name} 0 1 0.5")
    path = write(tmp_path, text)
    with pytest.raises(BrdfFileError, match=kind) as info:
        read_brdf(path)
    assert (info.value.line, info.value.column) == where(text, f"{name} 0 1"), str(info.value)


def _int32(value: int) -> int:
    return (value + 2**31) % 2**32 - 2**31


WRAPPING = [
    ("-1u", 2**32 - 1),
    ("0u - 1u", 2**32 - 1),
    ("uint(0) - 5u", 2**32 - 5),
    ("3000000000u * 3u", 3000000000 * 3 % 2**32),
    ("4294967295u + 2u", 1),
    ("-(-2147483647 - 1)", -(2**31)),
    ("2147483647 + 1", _int32(2**31)),
    ("65537 * 65537 * 65537", _int32(65537**3)),
    ("123456789 * 987654321", _int32(123456789 * 987654321)),
    ("~0u", 2**32 - 1),
    ("10u / uint(-1)", 0),
    ("(-7) / 2", -3),
]


@pytest.mark.parametrize(("expression", "expected"), WRAPPING)
def test_integer_arithmetic_wraps_to_32_bits(expression, expected):
    # Constant-folded, and at run time: every literal plus a uniform 0 of its type, so nothing folds.
    at_run_time = re.sub(r"\b(\d+)(u?)\b", lambda m: f"({m[1]}{m[2]} + z{m[2] or 'i'})", expression)
    for text in (expression, at_run_time):
        program = compile_shader(
            SIGNATURE + f" {{ return vec3(float({text})); }}", uniforms={"zi": "int", "zu": "uint"}
        )
        result = program.brdf(*DIRECTIONS, *DIRECTIONS, DIRECTIONS[0], {"zi": 0, "zu": 0})
        np.testing.assert_array_equal(result, np.full((2, 3), float(expected)), err_msg=text)


def test_integer_increments_wrap(tmp_path):
    body = SIGNATURE + " { int i = 2147483647; i++; uint u = 0u; u--; return vec3(float(i), float(u), 0.0); }"
    np.testing.assert_array_equal(value_of(tmp_path, body), [[-(2.0**31), 2.0**32 - 1, 0.0]] * 2)


# -- fuzz: mutated example shaders ------------------------------------------------------------------------

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


@settings(
    max_examples=int(os.environ.get("BRDFNORM_FUZZ_EXAMPLES", "300")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(mutated_shaders())
def test_mutated_shaders_raise_only_the_projects_errors(case):
    brdf, shader = case
    with hang_guard(30), warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            program = compile_shader(shader, path="fuzz.brdf", uniforms=brdf.uniforms)
            values = {
                p.name: (np.asarray(p.default, dtype=float) if p.kind != "bool" else p.default) for p in brdf.parameters
            }
            program.brdf(*DIRECTIONS, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], values)
        except BrdfnormError as error:
            assert "fuzz.brdf" in str(error)


@pytest.mark.parametrize("expression", [e for e, _ in WRAPPING])
def test_integer_wrap_around_agrees_with_mesa(expression):
    # The same expression in Mesa's llvmpipe (a compute shader, float32 output), folded and at run time.
    from glsl.test_compiler import mesa

    at_run_time = re.sub(r"\b(\d+)(u?)\b", lambda m: f"({m[1]}{m[2]} + z{m[2] or 'i'})", expression)
    for text in (expression, at_run_time):
        shader = SIGNATURE + f" {{ return vec3(float({text}), 0.0, 0.0); }}"
        types, values = {"zi": "int", "zu": "uint"}, {"zi": 0, "zu": 0}
        ours = compile_shader(shader, uniforms=types).brdf(*DIRECTIONS, *DIRECTIONS, DIRECTIONS[0], values)
        theirs = mesa(shader, values, types, dirs=(*DIRECTIONS, *DIRECTIONS, DIRECTIONS[0]))
        np.testing.assert_allclose(ours, theirs, rtol=1e-7, err_msg=text)


def test_the_number_of_parameters_is_bounded(tmp_path):
    from brdfnorm.brdffile import MAX_PARAMETERS

    declarations = "\n".join(f"float p{k} 0 1 0.5" for k in range(MAX_PARAMETERS + 1))
    text = brdf_text(SIGNATURE + " { return vec3(p0); }", declarations)
    with pytest.raises(BrdfFileError, match=f"too many parameters: at most {MAX_PARAMETERS}") as info:
        read_brdf(write(tmp_path, text))
    assert (info.value.line, info.value.column) == where(text, f"float p{MAX_PARAMETERS} ")
    fewer = text.replace(f"\nfloat p{MAX_PARAMETERS} 0 1 0.5", "")
    np.testing.assert_array_equal(load_brdf(write(tmp_path, fewer)).eval(*DIRECTIONS), [[0.5] * 3] * 2)


@pytest.mark.parametrize(
    ("prelude", "expression", "expected"),
    [
        ("", "(float(L.x) + 1.0)", lambda L, V: L[:, 0] + 1.0),
        (
            "",
            "float(int(3.7) + 1) + (int(V.z * 10.0) > 3 ? 1.0 : 0.0)",
            lambda L, V: 4.0 + (np.trunc(V[:, 2] * 10) > 3),
        ),
        ("", "((bool(L.x) && true) ? 2.0 : 3.0)", lambda L, V: np.where(L[:, 0] != 0, 2.0, 3.0)),
        ("#define XOR (L.x > 0.0 ^^ true)\n", "(XOR ? 1.0 : 2.0)", lambda L, V: np.where(L[:, 0] > 0, 2.0, 1.0)),
        ("#define M (float(1) + 0.5) // a comment\n", "M * L.y", lambda L, V: 1.5 * L[:, 1]),
    ],
    ids=["float-in-parentheses", "int", "bool", "xor-in-a-macro", "constructor-in-a-macro"],
)
def test_valid_glsl_the_grammar_needs_rewrites_for_evaluates_as_mesa_does(prelude, expression, expected):
    # `(float(x) + 1.0)` reads as a C cast to tree-sitter, and a macro body's `^^` was lost: both parse now.
    from glsl.test_compiler import mesa

    L, V = DIRECTIONS
    shader = prelude + SIGNATURE + f" {{ return vec3({expression}); }}"
    ours = compile_shader(shader).brdf(L, V, L, L, L)
    np.testing.assert_allclose(ours[:, 0], expected(L, V), rtol=1e-15)
    np.testing.assert_allclose(ours, mesa(shader, dirs=(L, V, L, L, L)), rtol=1e-6)


def test_a_user_function_named_like_a_rewritten_constructor_is_its_own():
    shader = "float __flo(float x) { return 2.0 * x; }\n" + SIGNATURE + " { return vec3(__flo(3.0), float(3), 0.0); }"
    np.testing.assert_array_equal(compile_shader(shader).brdf(*DIRECTIONS, *DIRECTIONS, DIRECTIONS[0])[0], [6, 3, 0])
