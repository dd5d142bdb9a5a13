"""The bounds of :mod:`brdfnorm.glsl.limits`, one by one: each is hit with a clear, located error, the
examples stay far inside every one, and chunked evaluation gives the very same values as unchunked.

(The same hostile cases run end to end under an address-space limit in ``test_glsl_memory.py``.)
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import paths

from brdfnorm.brdffile import load_brdf, random_hemisphere, read_brdf
from brdfnorm.errors import BrdfFileError, EvaluationError
from brdfnorm.glsl import compile_shader, limits, parser
from brdfnorm.glsl.compiler import Compiler, statements

EXAMPLES = sorted(paths.EXAMPLES.glob("*.brdf"))
SIGNATURE = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"
FRAME = ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])


def located(text: str, needle: str, match: str, occurrence: int = 1) -> BrdfFileError:
    """Compiling ``text`` fails with ``match`` at the ``occurrence``-th ``needle`` (1-based line, column)."""
    with pytest.raises(BrdfFileError, match=match) as info:
        compile_shader(text, path="x.brdf")
    index = -1
    for _ in range(occurrence):
        index = text.index(needle, index + 1)
    line = text.count("\n", 0, index) + 1
    column = index - (text.rfind("\n", 0, index) + 1) + 1
    assert (info.value.line, info.value.column) == (line, column), str(info.value)
    return info.value


def doubling_calls(levels: int) -> str:
    functions = "float f0(float x) { return x + 1.0; }\n" + "".join(
        f"float f{k}(float x) {{ return f{k - 1}(x) + f{k - 1}(x); }}\n" for k in range(1, levels + 1)
    )
    return functions + SIGNATURE + f" {{ return vec3(f{levels}(1.0)); }}"


def test_parse_work_is_bounded(monkeypatch):
    # Valid GLSL needs about one progress report per 100 bytes; a parse past the allowance is cancelled.
    text = SIGNATURE + " {\n    float s = 0.0;\n" + "    s += 1.0;\n" * 2000 + "    return vec3(s);\n}"
    assert compile_shader(text).brdf([0, 0, 1.0], [0, 0, 1.0], *FRAME)[0] == 2000.0
    monkeypatch.setattr(parser, "PARSE_REPORTS", 3)
    monkeypatch.setattr(parser, "PARSE_BYTES_PER_REPORT", 10**9)
    with pytest.raises(BrdfFileError, match="too complex to parse") as info:
        compile_shader("\n\n" + text, path="x.brdf", first_line=7, first_column=3)
    assert (info.value.line, info.value.column) == (7, 3)


def test_shader_size_is_bounded():
    text = SIGNATURE + " { return vec3(1.0); }\n//" + "x" * limits.MAX_SHADER_BYTES
    with pytest.raises(BrdfFileError, match=f"shader too large: {len(text)} bytes"):
        compile_shader(text, path="x.brdf")


def test_doubling_macros_are_refused_in_a_macro_definition():
    levels = 40
    text = "#define A0 1.0\n" + "".join(f"#define A{k} (A{k - 1} + A{k - 1})\n" for k in range(1, levels + 1))
    text += SIGNATURE + f" {{ return vec3(A{levels}); }}"
    with pytest.raises(BrdfFileError, match=f"more than {limits.MAX_COMPILED_NODES} syntax nodes") as info:
        compile_shader(text, path="x.brdf")
    assert 2 <= info.value.line <= levels + 1, str(info.value)
    # Twelve levels (4 096 expansions) compile and evaluate to 2**12.
    small = text.replace(f"vec3(A{levels})", "vec3(A12)")
    assert compile_shader(small).brdf([0, 0, 1.0], [0, 0, 1.0], *FRAME)[0] == 4096.0


def test_a_doubling_call_tree_is_refused_at_the_call_that_crosses_the_bound():
    # f_k inlines to about 10·2^k nodes: f15's calls of f14 (163 834 each) cross 200 000 at the second call.
    located(doubling_calls(40), "f14(x)", "'f15' runs more than 200000 nodes", occurrence=2)
    program = compile_shader(doubling_calls(10))
    assert program.brdf([0, 0, 1.0], [0, 0, 1.0], *FRAME)[0] == 2048.0


def test_global_initializers_are_bounded_with_their_calls_inlined():
    text = doubling_calls(14).replace(SIGNATURE, "float g = " + " + ".join(["f14(1.0)"] * 3) + ";\n" + SIGNATURE)
    located(text, "f14(1.0)", "global initializers run more than 200000", occurrence=2)


def test_variable_components_are_bounded():
    located(SIGNATURE + " { mat4 m[1024]; return vec3(1.0); }", "m[1024]", r"more than 4096 components.*16384")
    text = (
        SIGNATURE + " { float a[1000]; float b[1000]; float c[1000]; float d[1000]; float e[100]; return vec3(1.0); }"
    )
    located(text, "e[100]", "more than 4096 components")
    functions = "".join(f"float f{k}() {{ float a[1000]; return a[0]; }}\n" for k in range(5))
    located(functions + SIGNATURE + " { return vec3(1.0); }", "a[1000]", "more than 4096", occurrence=5)


def test_loop_work_is_bounded_with_calls_inlined(monkeypatch):
    monkeypatch.setattr(statements, "MAX_LOOP_NODES", 50_000)  # the real bound costs seconds to reach
    text = doubling_calls(8).replace(
        "return vec3(f8(1.0));", "float s = 0.0; for (int i = 0; i < 100; i++) s += f8(1.0); return vec3(s);"
    )
    program = compile_shader(text, path="x.brdf")
    with pytest.raises(EvaluationError, match=r"loops ran more than 50000 nodes.*\(2564 per iteration") as info:
        program.brdf([0, 0, 1.0], [0, 0, 1.0], *FRAME)
    loop = text.index("for (")
    assert info.value.where == f"x.brdf:{text.count(chr(10), 0, loop) + 1}:{loop - text.rfind(chr(10), 0, loop)}"
    # Within the bound: 19 iterations of 2 564 nodes, each adding f8(1.0) = 2**9.
    fewer = compile_shader(text.replace("i < 100", "i < 19"))
    assert fewer.brdf([0, 0, 1.0], [0, 0, 1.0], *FRAME)[0] == 19 * 512.0


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_the_examples_are_far_inside_every_bound(path):
    brdf = read_brdf(path)
    compiler = Compiler(brdf.shader.text, str(path), brdf.shader.line, brdf.shader.column, brdf.uniforms)
    compiler.compile()
    entry = compiler.functions["BRDF"][0]
    assert compiler.compiled_nodes * 100 < limits.MAX_COMPILED_NODES
    assert entry.inlined_size * 100 < limits.MAX_INLINED_NODES
    assert compiler.components * 50 < limits.MAX_VARIABLE_COMPONENTS
    assert len(brdf.shader.text.encode()) * 100 < limits.MAX_SHADER_BYTES


@pytest.mark.parametrize("name", ["ggx", "layered_series", "banded_specular", "anisotropic_ggx"])
def test_chunked_evaluation_equals_unchunked(name):
    model = load_brdf(EXAMPLES[0].parent / f"{name}.brdf")
    rng = np.random.default_rng(5)
    L = random_hemisphere(rng, 600).reshape(20, 30, 3)
    V = random_hemisphere(rng, 30)[None, :, :]  # broadcast against L
    params = {p.name: p.default for p in model.parameters}
    first = next(p for p in model.parameters if p.kind == "float")
    params[first.name] = np.linspace(first.minimum, first.maximum, 30)  # a per-lane uniform
    with np.errstate(all="ignore"):
        whole = model.evaluate(L, V, params)
        assert model.program.chunk > L.size
        model.program.chunk = 7
        chunked = model.evaluate(L, V, params)
    assert chunked.shape == whole.shape == (20, 30, 3)
    np.testing.assert_array_equal(chunked, whole)
