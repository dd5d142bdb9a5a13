"""Nothing of a shader's text reaches the native backend's generated source (issue 39, as issue 14 class 1 asks
of every emitter): the source is the fixed header and one function whose every name is generated (``tN``,
``pN``, the arguments, ``u``), whose every constant is a number or a bool printed from its value, and whose
every call is one of the numpy functions of the ufunc table. Shaders naming their variables, parameters,
functions and macros after the generated names, Python builtins and the module's globals evaluate to the numpy
backend's values; mutated example shaders either stay with the numpy backend or give such a source.
"""

from __future__ import annotations

import ast
import re
import warnings

import numpy as np
import pytest
from helpers import paths
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from glsl.test_hostile import EXAMPLES, mutated_shaders
from glsl.test_native import assert_same, directions, native_values

pytest.importorskip("numba")

from brdfnorm.brdffile import load_brdf, read_brdf  # noqa: E402 - after the skip: the backend needs Numba
from brdfnorm.errors import BrdfnormError  # noqa: E402
from brdfnorm.glsl import compile_shader  # noqa: E402
from brdfnorm.glsl.native.generate import HEADER, INTEGER_FUNCTIONS, Unsupported, generate  # noqa: E402
from brdfnorm.glsl.native.tracer import UFUNCS  # noqa: E402

_GENERATED = re.compile(r"[tpk][0-9]+\Z")
_NAMES = {"lx", "ly", "lz", "vx", "vy", "vz", "u", "np", "NAN", "INF", "float", "abs", *INTEGER_FUNCTIONS.values()}
_NUMPY = {m.group(1) for _, _, template in UFUNCS.values() for m in re.finditer(r"np\.(\w+)", template)}


def check_source(source: str) -> None:
    """The generated module: the header, then one body of assignments, conditionals, loops and a return over
    generated names, numbers, bools and the numpy functions of the table — nothing else."""
    assert source.startswith(HEADER)
    assert source.isascii()
    tree = ast.parse(source)
    function = tree.body[-1]
    assert isinstance(function, ast.FunctionDef) and function.name == "brdf"
    assert [a.arg for a in function.args.args] == ["lx", "ly", "lz", "vx", "vy", "vz", "u"]
    for node in (node for statement in function.body for node in ast.walk(statement)):
        if isinstance(node, ast.Name):
            assert _GENERATED.match(node.id) or node.id in _NAMES, node.id
        elif isinstance(node, ast.Attribute):
            assert isinstance(node.value, ast.Name) and node.value.id == "np" and node.attr in _NUMPY, node.attr
        elif isinstance(node, ast.Constant):
            assert type(node.value) in (int, float, bool), repr(node.value)
        elif isinstance(node, ast.Subscript):
            assert isinstance(node.value, ast.Name) and node.value.id == "u"
            assert isinstance(node.slice, ast.Constant) and type(node.slice.value) is int
        else:
            assert isinstance(node, (
                ast.Assign, ast.Return, ast.While, ast.If, ast.Break, ast.Call, ast.BinOp, ast.UnaryOp,
                ast.BoolOp, ast.Compare, ast.IfExp, ast.Tuple, ast.Load, ast.Store, ast.operator, ast.unaryop,
                ast.boolop, ast.cmpop,
            )), type(node).__name__


HOSTILE_SHADER = r"""
// """ + '"""' + r"""; import os; os.system("touch PWNED") #
#define brdf (u * np + NAN)
const float INF = 2.0;
float NativeLimit(float t1, inout float p1) { p1 = t1 * INF; return p1 + brdf; }
float njit(float k1) { return k1 * 0.1 + 1e-300 + 3.4e38; }
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    float __exec = 0.0;  /* eval("1") */
    float lx = NativeLimit(dot(N, L), __exec);
    vec3 abs_ = vec3(njit(lx), __exec, -0.0);
    for (int float_ = 0; float_ < 3; float_++) { __exec += lx * float(float_); }
    return lz ? abs_ * __exec * vx : vec3(-1.5e-30);
}
"""
HOSTILE_PARAMETERS = "float u 0 1 0.5\nfloat np 0 1 0.25\nbool lz 1\ncolor vx 0.1 0.2 0.3\nfloat NAN 0 1 0.125"


def test_hostile_names_and_comments_give_generated_names_only(tmp_path):
    path = tmp_path / "hostile.brdf"
    path.write_text(f"analytic\n::begin parameters\n{HOSTILE_PARAMETERS}\n::end parameters\n::begin shader\n"
                    f"{HOSTILE_SHADER}\n::end shader\n")
    model = load_brdf(path)
    brdf = model.brdf_file
    generated = generate(brdf.shader.text, path=str(path), first_line=brdf.shader.line,
                         first_column=brdf.shader.column, uniforms=brdf.uniforms)
    check_source(generated.source)
    for word in ("os", "system", "PWNED", "eval", "__exec", "njit(", "import os", "abs_", "float_"):
        assert word not in generated.source[len(HEADER):], word
    kernel = model.native_kernel()
    L, V = directions(np.random.default_rng(3), 50)
    for params in (model.params, model.with_params(lz=False, u=0.9, np=0.0, NAN=1.0).params):
        with np.errstate(all="ignore"):
            reference = model.evaluate(L, V, params)
        assert_same(native_values(kernel, L, V, params), reference, str(params))


def test_every_example_gives_a_source_of_generated_names_only():
    for path in sorted(paths.EXAMPLES.glob("*.brdf")):
        brdf = load_brdf(path).brdf_file
        check_source(generate(brdf.shader.text, path=str(path), first_line=brdf.shader.line,
                              first_column=brdf.shader.column, uniforms=brdf.uniforms).source)


def _generated(case):
    """The mutated shader's generated source, or None where it does not compile or stays with numpy."""
    brdf, shader = case
    try:
        compile_shader(shader, path="fuzz.brdf", uniforms=brdf.uniforms)
    except BrdfnormError:
        return None
    try:
        return generate(shader, path="fuzz.brdf", first_line=1, first_column=1, uniforms=brdf.uniforms)
    except Unsupported:
        return None


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_shaders())
def test_mutated_shaders_give_safe_sources_or_none(case):
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        generated = _generated(case)
    if generated is not None:
        check_source(generated.source)


# Same-kind substitutions keep most mutants compiling: they exercise the built-ins at special values (0/0, ±inf,
# NaN, overflow) and other branches of the lobes, which the numpy backend defines and the kernel must follow.
_SWAPS = [
    ["+", "-", "*", "/"], ["<", ">", "<=", ">=", "==", "!="], ["&&", "||", "^^"],
    ["sin", "cos", "tan", "asin", "acos", "atan", "exp", "log", "exp2", "log2", "sqrt", "inversesqrt", "abs",
     "sign", "floor", "ceil", "fract", "tanh", "sinh", "cosh", "asinh", "acosh", "atanh", "radians", "trunc",
     "round", "roundEven"],
    ["pow", "min", "max", "mod", "atan", "step", "distance"],
    ["0.0", "1.0", "-0.0", "0.5", "2.0", "1e-300", "1e38", "3.0e-45", "100.0", "-1.0"],
    ["dot", "distance"], ["normalize", "sign", "abs", "fract", "floor"], ["L", "V", "N", "X", "Y"],
]
_KIND = {word: group for group in _SWAPS for word in group}
_SWAP_TOKEN = re.compile(r"[A-Za-z_]\w*|\d+\.\d*(?:e-?\d+)?|&&|\|\||\^\^|[<>=!]=|[-+*/<>]")


@st.composite
def swapped_shaders(draw):
    """An example shader with 1–6 tokens swapped for others of the same kind (line structure kept)."""
    brdf = read_brdf(draw(st.sampled_from(EXAMPLES)))
    text = brdf.shader.text
    spots = [m for m in _SWAP_TOKEN.finditer(text) if m.group() in _KIND]
    for m in sorted(draw(st.lists(st.sampled_from(spots), min_size=1, max_size=6, unique_by=lambda m: m.start())),
                    key=lambda m: -m.start()):
        text = text[: m.start()] + draw(st.sampled_from(_KIND[m.group()])) + text[m.end():]
    return brdf, text


@pytest.mark.slow
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=swapped_shaders())
def test_mutated_shaders_compile_to_the_numpy_backends_values(case, tmp_path_factory):
    """The kernel of a mutated shader, where there is one, gives the numpy backend's values."""
    brdf, shader = case
    path = tmp_path_factory.mktemp("fuzz") / "fuzz.brdf"
    params = "\n".join(p.kind + " " + p.name + " " + _declared(p) for p in brdf.parameters)
    path.write_text(f"analytic\n::begin parameters\n{params}\n::end parameters\n::begin shader\n{shader}\n"
                    "::end shader\n")
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            model = load_brdf(path)
        except BrdfnormError:
            return  # the mutant does not compile
        L, V = directions(np.random.default_rng(5), 20)
        try:
            reference = model.evaluate(L, V, model.params)
        except BrdfnormError:
            reference = None  # a loop bound: the kernel's NaN there is tested on its own
        kernel = model.native_kernel()
        assert kernel is not None, shader
        if reference is None:
            return
        assert_same(native_values(kernel, L, V, model.params), reference, shader)


def _declared(p) -> str:
    if p.kind == "bool":
        return "1" if p.default else "0"
    if p.kind == "color":
        return " ".join(repr(float(c)) for c in p.default)
    return f"{p.minimum!r} {p.maximum!r} {p.default!r}"


@pytest.mark.parametrize("line", [
    "t1 = __import__", "t1 = 'x'", "t1 = os.system", "t1 = lx; exec(t1)", "t1 = q1", "t1 = np.load",
    "t1 = lx  # comment", 't1 = f"{lx}"', "t1 = lambda: 0",
])
def test_the_generator_refuses_a_body_with_anything_but_its_own_words(line):
    """The last check before compiling: a body holding another word, a string, a comment is refused."""
    from brdfnorm.glsl.native.generate import _check_body

    _check_body("    t1 = (lx * u[0])\n    return (t1, NAN, (-1.5e-300))\n")
    with pytest.raises(Unsupported):
        _check_body(f"    {line}\n    return (t1, t1, t1)\n")
