"""Hostile and malformed ``.brdf`` files (issue 8, item 2): one clear error at FILE:LINE:COL, bounded work.

Every case asserts the error type and the location in the file's own numbering; expected locations are
found by searching the test's own text (:func:`where`), not by asking the reader. A property test feeds
arbitrary bytes and mutated example files to the loader: it returns a model or raises
:class:`~brdfnorm.errors.BrdfFileError` with a line number — nothing else, and never hangs.
"""

from __future__ import annotations

import contextlib
import random
import re
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers.brdf_files import DIRECTIONS, brdf_text, hang_guard, where, write
from helpers.mesa import MesaBrdf, MesaCompileError, MesaUnavailable
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import brdfnorm as bn
from brdfnorm.brdffile import load_brdf, random_hemisphere, read_brdf
from brdfnorm.errors import BrdfFileError, EvaluationError, ModelNotFoundError

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.brdf"))
SIGNATURE = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"


def assert_file_error(path: Path, line: int, column: int | None = None, match: str = "") -> BrdfFileError:
    with pytest.raises(BrdfFileError, match=match) as info:
        load_brdf(path)
    error = info.value
    assert error.path == str(path)
    assert error.line == line, str(error)
    if column is not None:
        assert error.column == column, str(error)
    else:
        assert isinstance(error.column, int), str(error)
    prefix = f"{path}:{line}:{error.column}: "
    assert str(error).startswith(prefix) and "\n" not in str(error)
    return error





# -- the file format --------------------------------------------------------------------------------------
def test_missing_end_of_shader(tmp_path):
    text = "analytic\n::begin shader\n" + SIGNATURE + " { return vec3(1); }\n"
    assert_file_error(write(tmp_path, text), *where(text, "::begin shader"), match="missing '::end shader'")


def test_missing_end_of_parameters(tmp_path):
    text = "analytic\n::begin parameters\nfloat n 1 2 1\n::begin shader\n::end shader\n"
    assert_file_error(write(tmp_path, text), *where(text, "::begin shader"), match="missing '::end parameters'")


def test_mismatched_end(tmp_path):
    text = "analytic\n::begin shader\n" + SIGNATURE + " { return vec3(1); }\n::end shaders\n"
    assert_file_error(write(tmp_path, text), *where(text, "::end"), match="expected '::end shader'")


def test_missing_analytic(tmp_path):
    text = "::begin shader\n" + SIGNATURE + " { return vec3(1); }\n::end shader\n"
    assert_file_error(write(tmp_path, text), 1, 1, match="expected 'analytic' first")


def test_unknown_section(tmp_path):
    text = "analytic\n# comment\n::begin shaders\n::end shaders\n"
    assert_file_error(write(tmp_path, text), *where(text, "shaders"), match="unknown section 'shaders'")


def test_no_shader_section(tmp_path):
    text = "analytic\n::begin parameters\nfloat n 1 2 1\n::end parameters\n"
    assert_file_error(write(tmp_path, text), 5, 1, match="no '::begin shader' section")


def test_text_outside_sections(tmp_path):
    text = brdf_text(SIGNATURE + " { return vec3(1); }") + "This aproximation was tweaked\n"
    assert_file_error(write(tmp_path, text), *where(text, "This"), match="outside a section")


@pytest.mark.parametrize(
    ("line", "needle", "message"),
    [
        ("float n 1 100", "float", "expected 'float NAME MIN MAX DEFAULT', got 'float n 1 100'"),
        ("float n 1 100 10 5", "5", "unexpected '5' after the declaration of 'n'"),
        ("float n 1 ten 10", "ten", "MAX must be a number, got 'ten'"),
        ("float n 1 nan 10", "nan", "MAX must be a number, got 'nan'"),
        ("float n 1 1e999 10", "1e999", "MAX must be finite"),
        ("float n 100 1 10", "100", "MIN 100 is greater than MAX 1"),
        ("bool b 2", "2", "DEFAULT must be 0 or 1, got '2'"),
        ("bool b", "bool", "expected 'bool NAME DEFAULT"),
        ("color c 1 1", "color", "expected 'color NAME R G B'"),
        ("int k 0 4 1", "int", "expected a parameter declaration \\(float, bool or color\\), got 'int'"),
        ("float 2x 0 1 0", "2x", "parameter name '2x' is not a GLSL identifier"),
    ],
    ids=[
        "count",
        "extra",
        "non-numeric",
        "nan",
        "overflow",
        "min>max",
        "bool",
        "bool-count",
        "color-count",
        "kind",
        "name",
    ],
)
def test_malformed_parameter_line(tmp_path, line, needle, message):
    text = brdf_text(SIGNATURE + " { return vec3(1); }", params=line)
    assert_file_error(write(tmp_path, text), *where(text, needle), match=message)


def test_duplicate_parameters(tmp_path):
    text = brdf_text(SIGNATURE + " { return vec3(n); }", params="float n 1 100 10\nbool n 1")
    line, column = where(text, "bool n")
    assert_file_error(write(tmp_path, text), line, column + 5, match="duplicate parameter 'n'")


def test_duplicate_section(tmp_path):
    text = brdf_text(SIGNATURE + " { return vec3(n); }") + "::begin shader\n::end shader\n"
    assert_file_error(write(tmp_path, text), *where(text, "::begin shader", 2), match="duplicate section")


def test_empty_file(tmp_path):
    assert_file_error(write(tmp_path, b""), 1, 1, match="empty file")


def test_blank_and_comment_only_file(tmp_path):
    assert_file_error(write(tmp_path, "\n  \n# only a comment\n\n"), 1, 1, match="empty file")


def test_binary_garbage(tmp_path):
    data = b"analytic\n::begin shader\n" + bytes(range(256)) * 4
    assert_file_error(write(tmp_path, data), 3, 1, match="NUL byte")


def test_binary_garbage_without_nul(tmp_path):
    data = b"analytic\n\x01\x02\x03\x1b[31m\n"
    assert_file_error(write(tmp_path, data), 2, 1, match="control character U\\+0001")


def test_non_utf8_text(tmp_path):
    data = "analytic\n# Schlick’s approximation\n".encode() + b"# caf\xe9 in Latin-1\n::begin shader\n"
    assert_file_error(write(tmp_path, data), 3, 6, match="not UTF-8 text: invalid byte 0xe9")


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(ModelNotFoundError, match="nowhere.brdf"):
        load_brdf(tmp_path / "nowhere.brdf")
    with pytest.raises(ModelNotFoundError):
        bn.load(str(tmp_path / "nowhere.brdf"))


def test_ten_megabytes_of_comments_load(tmp_path):
    comment = "# " + "a long comment line about nothing in particular " * 2 + "\n"
    count = 10 * 1024 * 1024 // len(comment) + 1
    text = "analytic\n" + comment * count + brdf_text(SIGNATURE + " { return vec3(n); }").removeprefix("analytic\n")
    path = write(tmp_path, text)
    assert path.stat().st_size >= 10 * 1024 * 1024
    with hang_guard(60):
        model = load_brdf(path)
    np.testing.assert_array_equal(model.eval([0, 0, 1.0], [0, 0, 1.0]), [10.0, 10.0, 10.0])


def test_error_lines_stay_exact_deep_in_a_large_file(tmp_path):
    text = "analytic\n" + "# filler\n" * 200_000 + brdf_text(SIGNATURE + " { return vec3(undefinedName); }")[9:]
    with hang_guard(60):
        assert_file_error(write(tmp_path, text), *where(text, "undefinedName"), match="undefinedName")


# -- the shader -------------------------------------------------------------------------------------------
def test_no_brdf_function(tmp_path):
    text = brdf_text("float helper(float x) { return x; }")
    error = assert_file_error(write(tmp_path, text), *where(text, "float helper"), match="BRDF")
    assert "no" in error.message.lower()


def test_wrong_brdf_signature(tmp_path):
    text = brdf_text("vec3 BRDF(vec3 L, vec3 V) { return vec3(1); }")
    assert_file_error(write(tmp_path, text), *where(text, "BRDF("), match="wrong signature")


def test_brdf_returning_float(tmp_path):
    text = brdf_text("float BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return 1.0; }")
    assert_file_error(write(tmp_path, text), *where(text, "BRDF("), match="wrong signature")


def test_glsl_syntax_error(tmp_path):
    text = brdf_text(SIGNATURE + "\n{\n    float a = 1.0 +;\n    return vec3(a);\n}")
    assert_file_error(write(tmp_path, text), *where(text, "+;"), match="syntax error near '\\+'")


def test_unknown_identifier(tmp_path):
    text = brdf_text(SIGNATURE + "\n{\n    return vec3(roughnes * n);\n}")
    assert_file_error(write(tmp_path, text), *where(text, "roughnes"), match="roughnes")


def test_unknown_identifier_in_one_line_form(tmp_path):
    text = "analytic ::begin parameters float n 1 2 1 ::end parameters ::begin shader " + SIGNATURE
    text += " { return vec3(m); } ::end shader"
    assert_file_error(write(tmp_path, text), *where(text, "m)"), match="'m'")


def test_wrong_argument_count(tmp_path):
    text = brdf_text(SIGNATURE + "\n{\n    return vec3(dot(L));\n}")
    assert_file_error(write(tmp_path, text), *where(text, "dot(L)"), match="dot")


def test_wrong_argument_type(tmp_path):
    text = brdf_text(SIGNATURE + "\n{\n    return vec3(normalize(true));\n}")
    assert_file_error(write(tmp_path, text), *where(text, "normalize"), match="normalize")


def test_wrong_argument_count_to_a_user_function(tmp_path):
    text = brdf_text("float f(float a, float b) { return a * b; }\n" + SIGNATURE + " { return vec3(f(1.0)); }")
    assert_file_error(write(tmp_path, text), *where(text, "f(1.0)"), match="'f'|f\\(")


def test_infinite_loop_hits_the_budget(tmp_path):
    text = brdf_text(SIGNATURE + "\n{\n    float s = 0.0;\n    for (;;) { s += 1.0; }\n    return vec3(s);\n}")
    path = write(tmp_path, text)
    with hang_guard(60), pytest.raises((EvaluationError, BrdfFileError)) as info:
        load_brdf(path).eval(*DIRECTIONS)
    assert str(info.value).startswith(f"{path}:{where(text, 'for')[0]}:")


def test_huge_loop_hits_the_budget(tmp_path):
    body = "\n{\n    float s = 0.0;\n    for (int i = 0; i < 2000000000; i++) { s += 1.0; }\n    return vec3(s);\n}"
    path = write(tmp_path, text := brdf_text(SIGNATURE + body))
    with hang_guard(60), pytest.raises((EvaluationError, BrdfFileError)) as info:
        load_brdf(path).eval(*DIRECTIONS)
    assert str(info.value).startswith(f"{path}:{where(text, 'for')[0]}:")


def test_per_lane_infinite_loop_hits_the_budget(tmp_path):
    # Only the lane with L.x > 0 (the second) loops forever; the first finishes at once.
    body = "\n{\n    float s = 0.0;\n    while (L.x > 0.0) { s += 1.0; }\n    return vec3(s);\n}"
    path = write(tmp_path, text := brdf_text(SIGNATURE + body))
    with hang_guard(60), pytest.raises((EvaluationError, BrdfFileError)) as info:
        load_brdf(path).eval(*DIRECTIONS)
    assert str(info.value).startswith(f"{path}:{where(text, 'while')[0]}:")


def test_recursion_is_refused(tmp_path):
    text = brdf_text("float f(float x) { return x > 1.0 ? f(x - 1.0) : x; }\n" + SIGNATURE + " { return vec3(f(n)); }")
    assert_file_error(write(tmp_path, text), *where(text, "f(x - 1.0)"), match="recursion")


def test_mutual_recursion_is_refused(tmp_path):
    body = "float g(float x);\nfloat f(float x) { return g(x); }\nfloat g(float x) { return f(x); }\n"
    text = brdf_text(body + SIGNATURE + " { return vec3(f(n)); }")
    with pytest.raises(BrdfFileError, match="recurs") as info:
        load_brdf(write(tmp_path, text))
    assert info.value.line in (where(text, "float f(float x) {")[0], where(text, "float g(float x) {")[0])


@pytest.mark.parametrize(
    ("declaration", "use", "feature"),
    [
        ("uniform sampler2D table;", "texture(table, L.xy).rgb", "sampler2D"),
        ("", "texture(L, L.xy).rgb", "texture"),
        ("layout(rgba32f) uniform image2D img;", "imageLoad(img, ivec2(0)).rgb", "image2D"),
    ],
    ids=["sampler", "texture", "image"],
)
def test_samplers_textures_images_are_named_as_unsupported(tmp_path, declaration, use, feature):
    text = brdf_text(f"{declaration}\n{SIGNATURE} {{ return {use}; }}")
    error = assert_file_error(write(tmp_path, text), *where(text, feature), match=feature)
    assert "unsupported" in error.message or "not supported" in error.message


def test_python_names_are_plain_glsl_identifiers(tmp_path):
    body = (
        "float exec(float os) { return os * 2.0; }\n"
        "const float eval = 0.25;\n" + SIGNATURE + "\n{\n"
        "    float __import__ = exec(n);\n"
        "    vec3 sys = vec3(__import__, eval, L.z);\n"
        "    return sys;\n}"
    )
    model = load_brdf(write(tmp_path, brdf_text(body, params="float os 0 1 0.5\nfloat n 1 100 10")))
    expected = [[20.0, 0.25, 1.0], [20.0, 0.25, 0.8]]
    np.testing.assert_array_equal(model.eval(*DIRECTIONS), expected)
    with contextlib.suppress(MesaUnavailable):  # the real compiler agrees that these are plain names
        mesa = MesaBrdf(model.brdf_file)(*DIRECTIONS, {"os": 0.5, "n": 10.0})
        np.testing.assert_allclose(mesa, expected, rtol=1e-7)


def test_nan_fails_the_albedo_naming_the_first_pair_unless_zeroed(tmp_path):
    # sqrt of a negative number is NaN wherever L·V < 0.5: on part of the hemisphere only.
    text = brdf_text(SIGNATURE + " { return vec3(sqrt(dot(L, V) - 0.5)); }")
    model = load_brdf(write(tmp_path, text))
    with pytest.raises(EvaluationError, match=r"L=.*V=") as info:
        bn.albedo(model, 0.5)
    assert "nonfinite" in str(info.value)
    with pytest.warns(UserWarning):
        zeroed = bn.albedo(model, 0.5, nonfinite="zero", rtol=1e-6)
    assert 0 < float(zeroed.nonfinite_fraction) < 1
    # Independent route: a midpoint rule in (θ, φ) with the NaNs counted as 0 (the integrand has a
    # square-root edge, so the crude rule is good to ~1e-3 only).
    t = (np.arange(300) + 0.5) * (np.pi / 2) / 300
    p = (np.arange(600) + 0.5) * (2 * np.pi) / 600
    T, P = np.meshgrid(t, p, indexing="ij")
    L = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    V = np.array([np.sin(0.5), 0.0, np.cos(0.5)])
    value = np.sqrt(np.maximum(L @ V - 0.5, 0.0)) * np.cos(T) * np.sin(T) * (np.pi / 600) * (np.pi / 300)
    np.testing.assert_allclose(zeroed.value, value.sum(), rtol=3e-3)


def test_division_by_zero_fails_the_albedo(tmp_path):
    text = brdf_text(SIGNATURE + " { return vec3(1.0 / (dot(N, L) - dot(N, L))); }")
    model = load_brdf(write(tmp_path, text))
    with pytest.raises(EvaluationError, match=r"L=.*V="):
        bn.albedo(model, 0.0)


# -- properties -------------------------------------------------------------------------------------------
def _load_and_touch(data: bytes) -> None:
    """Load bytes as a .brdf; if that works, evaluate two pairs. Only the project's errors may come out."""
    with tempfile.TemporaryDirectory() as directory:
        path = Path(directory) / "fuzz.brdf"
        path.write_bytes(data)
        with hang_guard(20), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                model = load_brdf(path)
            except BrdfFileError as error:
                assert error.line is not None and error.line >= 1, str(error)
                assert str(error).startswith(f"{path}:{error.line}")
                return
            try:
                with np.errstate(all="ignore"):
                    model.eval(*DIRECTIONS)
            except (EvaluationError, BrdfFileError):
                pass


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=600))
def test_any_bytes_load_or_fail_cleanly(data):
    _load_and_touch(data)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=400).map(lambda tail: b"analytic\n::begin shader\n" + tail))
def test_any_shader_bytes_load_or_fail_cleanly(data):
    _load_and_touch(data)


PIECES = [
    b"::end",
    b"::begin",
    b"shader",
    b"parameters",
    b"{",
    b"}",
    b"(",
    b")",
    b";",
    b"\n",
    b"#",
    b" ",
    b"0",
    b"1e40",
    b"-",
    b"/",
    b"for(;;)",
    b"while(true)",
    b"return",
    b"vec3(",
    b"float",
    b"bool",
    b"color",
    b"\xff",
    b"\x00",
    b"uniform sampler2D s;",
    b"BRDF",
    b".xyz",
    b"= ",
    b"//",
    b"/*",
    b"*/",
    b"if",
    b"else",
]


@st.composite
def mutated_examples(draw):
    data = bytearray(draw(st.sampled_from(EXAMPLES)).read_bytes())
    for _ in range(draw(st.integers(1, 4))):
        position = draw(st.integers(0, len(data)))
        action = draw(st.sampled_from(["delete", "insert", "duplicate"]))
        if action == "delete":
            del data[position : position + draw(st.integers(1, 40))]
        elif action == "insert":
            data[position:position] = draw(st.sampled_from(PIECES))
        else:
            data[position:position] = data[position : position + draw(st.integers(1, 40))]
    return bytes(data)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_examples())
def test_mutated_examples_load_or_fail_cleanly(data):
    _load_and_touch(data)


def test_shuffled_example_lines_fail_cleanly():
    # A deterministic complement to the property tests: whole lines of every example in random order.
    shuffle = random.Random(7)
    for path in EXAMPLES:
        lines = path.read_bytes().split(b"\n")
        shuffle.shuffle(lines)
        _load_and_touch(b"\n".join(lines))


def test_random_directions_are_strictly_in_the_upper_hemisphere():
    # The helpers above rely on it: N·L > 0 for every generated direction.
    directions = random_hemisphere(np.random.default_rng(0), 100_000)
    assert np.all(directions[:, 2] > 0)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0, rtol=1e-15)


@pytest.mark.parametrize(
    "body",
    [
        SIGNATURE + "\n{\n    float a = 1.0;\n    return vec3(roughnes * a);\n}",
        SIGNATURE + "\n{\n    vec3 H = normalize(L + V);\n    return vec3(dot(H));\n}",
        "float f(float a, float b) { return a * b; }\n\n" + SIGNATURE + "\n{\n    return vec3(f(1.0));\n}",
    ],
    ids=["unknown-identifier", "argument-count", "user-function-arguments"],
)
def test_error_lines_agree_with_mesa(tmp_path, body):
    # The real compiler, fed the same file with its lines kept (tests/helpers/mesa.py), names the same line.
    path = write(tmp_path, brdf_text(body))
    with pytest.raises(BrdfFileError) as info:
        load_brdf(path)
    try:
        MesaBrdf(read_brdf(path))
    except MesaUnavailable as exc:
        pytest.skip(str(exc))
    except MesaCompileError as exc:
        mesa_lines = {int(line) for line in re.findall(r"0:(\d+)\(\d+\): error", str(exc))}
        assert info.value.line in mesa_lines, str(exc)
    else:
        pytest.fail("Mesa compiled a shader brdfnorm refused")
