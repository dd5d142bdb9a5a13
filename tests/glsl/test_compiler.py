"""Tests of the GLSL evaluator (brdfnorm.glsl): features against independent numpy computations and, where
an EGL context can be created, against Mesa's llvmpipe running the same shader in a compute shader; error
positions in the file's own numbering; Mesa's choices for undefined results; bounded loops.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from brdfnorm.errors import BrdfFileError, EvaluationError
from brdfnorm.glsl import MAX_LOOP_ITERATIONS, compile_shader

SIGNATURE = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"
RNG = np.random.default_rng(20261121)
COUNT = 256


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _hemisphere(count: int) -> np.ndarray:
    d = _unit(RNG.normal(size=(count, 3)))
    d[:, 2] = np.abs(d[:, 2]) + 0.05
    return _unit(d)


# Random directions and a random (non-axis-aligned) orthonormal frame per lane.
L, V = _hemisphere(COUNT), _hemisphere(COUNT)
N = _unit(RNG.normal(size=(COUNT, 3)))
X = _unit(np.cross(N, RNG.normal(size=(COUNT, 3))))
Y = np.cross(N, X)
DIRS = (L, V, N, X, Y)


def evaluate(shader: str, uniforms: dict | None = None, types: dict | None = None, dirs=DIRS) -> np.ndarray:
    program = compile_shader(shader, uniforms=types or {})
    return program.brdf(*dirs, uniforms or {})


# --- Mesa llvmpipe through moderngl ---------------------------------------------------------------------

_HEADER = """#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer BnIn { float bn_in[]; };
layout(std430, binding = 1) writeonly buffer BnOut { float bn_out[]; };
uniform uint bn_count;
"""

_MAIN = """
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= bn_count) return;
    vec3 d[5];
    for (int k = 0; k < 5; k++)
        for (int c = 0; c < 3; c++) d[k][c] = bn_in[15u * i + 3u * uint(k) + uint(c)];
    vec3 r = BRDF(d[0], d[1], d[2], d[3], d[4]);
    bn_out[3u * i] = r.x; bn_out[3u * i + 1u] = r.y; bn_out[3u * i + 2u] = r.z;
}
"""


#: What the output buffer holds where llvmpipe wrote nothing (see :func:`mesa`).
MESA_SENTINEL = 1234.5


@functools.cache
def _mesa_context():
    try:
        import moderngl

        return moderngl.create_context(standalone=True, backend="egl", require=430)
    except Exception as exc:  # a missing libEGL / driver surfaces as a plain Exception
        return f"no headless EGL OpenGL 4.3 context: {exc}"


def mesa(shader: str, uniforms: dict | None = None, types: dict | None = None, dirs=DIRS) -> np.ndarray:
    """The shader's BRDF evaluated by Mesa (float32) on the same lanes; skips (printing why) without EGL."""
    ctx = _mesa_context()
    if isinstance(ctx, str):
        print(f"skipping the Mesa comparison: {ctx}")
        pytest.skip(ctx)
    declarations = "".join(f"uniform {t} {name};\n" for name, t in (types or {}).items())
    program = ctx.compute_shader(_HEADER + declarations + shader + _MAIN)
    for name, value in (uniforms or {}).items():
        if name in program:
            program[name].value = tuple(value) if np.ndim(value) else value
    stacked = np.stack(np.broadcast_arrays(*dirs), axis=-2).astype(np.float32)  # (count, 5, 3)
    count = stacked.shape[0]
    program["bn_count"].value = count
    # The output starts as a sentinel: llvmpipe writes nothing for some shaders (e.g. dividing by a constant
    # 0.0), which must not pass for a result of 0.
    sentinel = np.full((count, 3), MESA_SENTINEL, dtype=np.float32)
    source, target = ctx.buffer(stacked.tobytes()), ctx.buffer(sentinel.tobytes())
    try:
        source.bind_to_storage_buffer(0)
        target.bind_to_storage_buffer(1)
        program.run(group_x=(count + 63) // 64)
        return np.frombuffer(target.read(), dtype=np.float32).reshape(count, 3).astype(np.float64)
    finally:
        source.release()
        target.release()
        program.release()


def check(shader, expected, uniforms=None, types=None, dirs=DIRS, rtol=1e-12, mesa_rtol=2e-4, mesa_atol=2e-5):
    """Compiled result == the independent numpy value (float64) and == Mesa's (float32 accuracy)."""
    ours = evaluate(shader, uniforms, types, dirs)
    np.testing.assert_allclose(ours, np.broadcast_to(expected, ours.shape), rtol=rtol, atol=1e-14, equal_nan=True)
    theirs = mesa(shader, uniforms, types, dirs)
    np.testing.assert_allclose(ours, theirs, rtol=mesa_rtol, atol=mesa_atol, equal_nan=True)


def dot(a, b):
    return np.sum(a * b, axis=-1)


def vec3(*columns):
    return np.stack(np.broadcast_arrays(*columns), axis=-1)


# --- features -------------------------------------------------------------------------------------------


def test_blinn_phong_with_uniform_exponent():
    shader = SIGNATURE + "{ vec3 H = normalize(L + V); return vec3(pow(max(0, dot(N, H)), n)); }"
    H = _unit(L + V)
    expected = np.maximum(0, dot(N, H)) ** 40.0
    check(shader, vec3(expected, expected, expected), {"n": 40.0}, {"n": "float"})


def test_seed_003_gaussian_lobe_with_bool_uniform():
    shader = (
        SIGNATURE
        + """ { vec3 H = normalize( L + V ); float Dot = clamp( dot( N, H ), 0, 1 );
        float Threshold = 0.04; float CosAngle = pow( Threshold, 1 / n );
        float NormAngle = ( Dot - 1 ) / ( CosAngle - 1 ); float D = exp( -NormAngle * NormAngle );
        if ( normalized ) { D *= 0.17287429 + 0.01388682 * n; } return vec3( D ); }"""
    )
    n = 100.0
    angle = (np.clip(dot(N, _unit(L + V)), 0, 1) - 1) / (0.04 ** (1 / n) - 1)
    d = np.exp(-angle * angle)
    for flag, factor in ((True, 0.17287429 + 0.01388682 * n), (False, 1.0)):
        check(
            shader,
            vec3(d * factor, d * factor, d * factor),
            {"n": n, "normalized": flag},
            {"n": "float", "normalized": "bool"},
        )


def test_vec3_uniform_and_array_valued_uniforms_broadcast():
    shader = SIGNATURE + "{ return color * k * L.z; }"
    color = np.array([0.2, 0.5, 0.9])
    k = np.linspace(0.5, 2.0, COUNT)
    ours = evaluate(shader, {"color": color, "k": k}, {"color": "vec3", "k": "float"})
    np.testing.assert_allclose(ours, color * (k * L[:, 2])[:, None], rtol=1e-15)
    # (S, 1) parameter values against (C,) lanes: the result broadcasts to (S, C, 3)
    sweep = np.array([[1.0], [3.0]])
    out = evaluate(shader, {"color": color, "k": sweep}, {"color": "vec3", "k": "float"})
    assert out.shape == (2, COUNT, 3)
    np.testing.assert_allclose(out[1], 3 * color * L[:, 2:3], rtol=1e-15)


def test_constructors():
    shader = (
        SIGNATURE
        + """{
        vec4 a = vec4(L, 2.0);            // vec4(vec3, float)
        vec2 b = vec2(a.wz);               // from a swizzle
        vec3 c = vec3(b, V.x);             // vec3(vec2, float)
        vec3 d = vec3(vec4(N, 7.0));       // dropping a larger vector's extra components
        vec3 e = vec3(1);                  // vec3(int scalar)
        ivec2 i = ivec2(vec2(-2.7, 2.7));  // float -> int truncates toward zero
        bool t = bool(0.5) && !bool(0);
        float f = float(true) + float(i.x) + float(i.y);
        return vec3(c.x + d.y, c.y * e.z + f, c.z) + (t ? 1.0 : 0.0);
    }"""
    )
    expected = vec3(3.0 + N[:, 1], L[:, 2] + 1.0 + (-2 + 2) + 1.0, V[:, 0] + 1.0)
    check(shader, expected)


def test_swizzle_reads_and_writes():
    shader = (
        SIGNATURE
        + """{
        vec3 a = L.zyx;
        vec4 b = vec4(V, 1.0).rgba;
        vec2 c = N.st + N.pp;
        vec3 w = vec3(0.0);
        w.xy = c;           // write a swizzle
        w.z = a.x;
        w.x += 1.0;         // compound assignment to a component
        w.zx = w.xz;        // permuted write (right side read first)
        w.y *= b.a * 2.0;
        return w + a.yyy * 0.0 + b.xyz;
    }"""
    )
    c = N[:, :2] + N[:, 2:3]
    w = np.stack([c[:, 0] + 1.0, c[:, 1], L[:, 2]], axis=-1)
    w[:, [2, 0]] = w[:, [0, 2]]
    w[:, 1] *= 2.0
    check(shader, w + V)


def test_matrices_are_column_major_with_glsl_products():
    shader = (
        SIGNATURE
        + """{
        mat3 toLocal = transpose(mat3(X, Y, N));   // columns X, Y, N; transposed: rows
        vec3 l = toLocal * L;                        // components of L in the frame
        vec3 v = V * mat3(X, Y, N);                  // row vector times matrix: the same projection
        mat3 m = mat3(X, Y, N) * toLocal;            // orthonormal: identity
        mat2 r = mat2(1.0, 2.0, 3.0, 4.0);           // columns (1,2), (3,4)
        vec2 p = r * vec2(1.0, 10.0);                // (31, 42)
        mat3 big = mat3(r);                          // upper-left r, identity elsewhere
        m[1][2] += 5.0;                              // column 1, row 2
        float det = determinant(mat3(X, Y, N));      // +1 (right-handed frame)
        mat2 inv = inverse(r);
        return vec3(l.x + v.y, m[1].z + p.x + big[2][2], det + inv[1][0] + matrixCompMult(r, r)[1][1]);
    }"""
    )
    lx, vy = dot(L, X), dot(V, Y)
    inv = np.linalg.inv(np.array([[1.0, 3.0], [2.0, 4.0]]))  # row-major view of mat2(1,2,3,4)
    expected = vec3(lx + vy, 5.0 + 31.0 + 1.0, np.full(COUNT, 1.0 + inv[0, 1] + 16.0))
    check(shader, expected, rtol=1e-11)


def test_non_square_matrices_and_outer_product():
    shader = (
        SIGNATURE
        + """{
        mat2x3 m = mat2x3(L, V);          // 2 columns of 3 rows
        vec3 a = m * vec2(2.0, -1.0);      // 2L - V
        vec2 b = N * m;                    // (N.L, N.V)
        mat3 o = outerProduct(X, Y);       // o[j][i] = X[i] * Y[j]
        return a + vec3(b, o[2][1]);
    }"""
    )
    expected = 2 * L - V + vec3(dot(N, L), dot(N, V), X[:, 1] * Y[:, 2])
    check(shader, expected)


def test_integer_arithmetic_and_implicit_conversions():
    shader = (
        SIGNATURE
        + """{
        int a = 7 / 2, b = -7 / 2, c = 7 % 3;      // 3, -3 (truncation toward zero), 1
        int k = int(L.x * 10.0) / 3;                // per lane, truncating
        float x = 2 * dot(L, V) + max(0, L.y);      // int operands convert to float
        uint u = 3u;
        float y = float(u) / 2u + 1 / 2;            // float division 1.5; int division 0
        return vec3(a + b * 10 + c * 100, k, x + y);
    }"""
    )
    k = np.trunc(np.trunc(L[:, 0] * 10) / 3)
    expected = vec3(np.full(COUNT, 3 - 30 + 100.0), k, 2 * dot(L, V) + np.maximum(0, L[:, 1]) + 1.5)
    check(shader, expected)


def test_increments_and_comma():
    shader = (
        SIGNATURE
        + """{
        float x = L.x;
        float a = x++;          // a = old x
        float b = ++x;          // b = old x + 2
        float c = -x--;         // -(x++) semantics: c = -(old x + 2)
        int i = 0;
        i += 3, i *= 2;         // comma expression
        return vec3(a, b + c, x + float(i));
    }"""
    )
    check(shader, vec3(L[:, 0], np.zeros(COUNT), L[:, 0] + 1.0 + 6.0))


def test_per_lane_if_else_blends_assignments():
    shader = (
        SIGNATURE
        + """{
        float r = 0.0; vec3 c = vec3(1.0);
        if (L.x > 0.0) { r = L.x; c.y = 2.0; }
        else if (L.y > 0.0) r = -L.y;
        else { r = 10.0; c = V; }
        return c * r;
    }"""
    )
    r = np.where(L[:, 0] > 0, L[:, 0], np.where(L[:, 1] > 0, -L[:, 1], 10.0))
    c = np.ones((COUNT, 3))
    c[L[:, 0] > 0, 1] = 2.0
    rest = (L[:, 0] <= 0) & (L[:, 1] <= 0)
    c[rest] = V[rest]
    assert 0 < np.count_nonzero(L[:, 0] > 0) < COUNT  # the branch really diverges
    check(shader, c * r[:, None])


def test_early_return_inside_branches_and_loops():
    shader = (
        SIGNATURE
        + """{
        if (L.x < -0.3) return vec3(1.0, 0.0, 0.0);
        for (int i = 0; i < 10; i++) {
            if (float(i) * 0.1 > L.z) return vec3(2.0, float(i), 0.0);
        }
        return vec3(3.0);
    }"""
    )
    first = np.ceil(L[:, 2] / 0.1 + 1e-12)  # the first i with 0.1 i > L.z
    first = np.array([next((i for i in range(10) if i * 0.1 > z), -1) for z in L[:, 2]], dtype=float)
    expected = np.where((first >= 0)[:, None], vec3(np.full(COUNT, 2.0), first, np.zeros(COUNT)), 3.0)
    expected[L[:, 0] < -0.3] = [1.0, 0.0, 0.0]
    check(shader, expected)


def test_loops_with_per_lane_trip_counts_break_and_continue():
    shader = (
        SIGNATURE
        + """{
        float x = 1.0 + 10.0 * L.z; int halvings = 0;
        while (x > 0.1) { x *= 0.5; halvings++; }           // per-lane trip count
        float s = 0.0;
        for (int i = 0; i < 20; ++i) {
            if (i % 2 == 0) continue;                        // uniform continue
            if (float(i) > 10.0 * V.z) break;                // per-lane break
            s += float(i);
        }
        int k = 0;
        do { k += 1; } while (float(k) < 5.0 * N.z);       // body runs at least once
        return vec3(float(halvings), s, float(k));
    }"""
    )
    x0 = 1.0 + 10.0 * L[:, 2]
    halvings = np.array([math.ceil(math.log2(x / 0.1)) if x > 0.1 else 0 for x in x0], dtype=float)
    s = np.array(
        [sum(i for i in range(1, 20, 2) if not any(j > 10 * vz for j in range(1, i + 1, 2))) for vz in V[:, 2]]
    )
    k = np.maximum(1, np.ceil(5.0 * N[:, 2]))
    check(shader, vec3(halvings, s, k))


def test_switch_with_fall_through_default_break_and_continue_per_lane():
    shader = (
        SIGNATURE
        + """{
        float a = 0.0, s = 0.0;
        for (int k = 0; k < 3; k++) {
            int i = int(L.x * 4.0) + k;
            switch (i) {
                case 1:
                case 2: a += 1.0; break;
                default: { a += 10.0; }        // falls through into case 3
                case 3:
                    a += 100.0;
                    if (L.y > 0.0) continue;   // continues the enclosing loop
                    s += 1.0;
            }
        }
        return vec3(a, s, 0.0);
    }"""
    )

    def reference(lx, ly):
        a = s = 0.0
        for k in range(3):
            i = int(np.trunc(lx * 4)) + k
            if i in (1, 2):
                a += 1
                continue
            a += 100 + (10 if i != 3 else 0)
            if ly <= 0:
                s += 1
        return a, s, 0.0

    check(shader, np.array([reference(lx, ly) for lx, ly in L[:, :2]]))


def test_preprocessor_lines_that_change_nothing_are_accepted():
    shader = (
        "#version 410\n#extension GL_ARB_gpu_shader5 : enable\n#pragma optimize(on)\n"
        + SIGNATURE
        + """{
        #define K 3.0
        precision highp float;
        highp float x = K * L.x;
        return vec3(x);
    }"""
    )
    ours = evaluate(shader)
    np.testing.assert_allclose(ours, 3.0 * L[:, :1] * np.ones(3), rtol=1e-15)


def test_user_functions_overloading_out_inout_and_shadowed_builtin():
    shader = (
        """
    float twice(float x) { return 2.0 * x; }
    vec3 twice(vec3 v) { return 3.0 * v; }            // overload chosen by argument type
    vec3 reflect(vec3 i, vec3 n) { return n; }         // hides the built-in reflect
    void split(in vec3 v, out float a, out vec2 b, inout float c) { a = v.x; b = v.yz; c += 1.0; }
    float early(const in float x) { if (x > 0.0) return 1.0; return -1.0; }
    """
        + SIGNATURE
        + """{
        float a; vec2 b; float c = L.z;
        split(V, a, b, c);
        return twice(L) + vec3(twice(a), b.x + c, b.y * early(N.x)) + reflect(L, X);
    }"""
    )
    expected = 3.0 * L + vec3(2.0 * V[:, 0], V[:, 1] + L[:, 2] + 1.0, V[:, 2] * np.where(N[:, 0] > 0, 1.0, -1.0)) + X
    check(shader, expected)


def test_out_parameter_written_under_a_per_lane_branch():
    shader = (
        """
    void setIfPositive(float x, inout float target) { if (x > 0.0) target = x; }
    """
        + SIGNATURE
        + """{
        float t = -1.0;
        if (L.y < 0.5) setIfPositive(L.x, t);
        return vec3(t);
    }"""
    )
    t = np.where((L[:, 1] < 0.5) & (L[:, 0] > 0), L[:, 0], -1.0)
    check(shader, vec3(t, t, t))


def test_ternaries_logic_and_short_circuit_side_effects():
    shader = (
        SIGNATURE
        + """{
        int count = 0;
        bool p = L.x > 0.0, q = L.y > 0.0;
        if (p && (count++ > -1)) {}          // increments only where p
        if (q || (count++ > -1)) {}          // increments only where !q
        bool x = p ^^ q;                     // '^^' binds tighter than '||'
        bool y = false || p ^^ true;
        if (q ^^ p || (count++ > -1)) {}     // ... and '||' after '^^' still short-circuits
        return vec3(float(count), x ? 1.0 : 0.0, (y ? L.z : -L.z) + (!p ? 10.0 : 0.0));
    }"""
    )
    p, q = L[:, 0] > 0, L[:, 1] > 0
    count = p.astype(float) + (~q).astype(float) + (~(p ^ q)).astype(float)
    expected = vec3(count, (p ^ q).astype(float), np.where(~p, L[:, 2], -L[:, 2]) + np.where(~p, 10.0, 0.0))
    check(shader, expected)


def test_globals_consts_arrays_and_defines():
    shader = (
        """
    #define SCALE 2.0
    const float PI = 3.14159265358979;
    const vec3 AXIS = vec3(0.0, 0.0, 1.0);
    float counter = 1.0;                     // a global variable, reset for each evaluation
    void bump() { counter += 1.0; }
    """
        + SIGNATURE
        + """{
        bump(); bump();
        float w[3] = float[3](1.0, 10.0, 100.0);
        int i = int(L.x > 0.0) + int(L.y > 0.0);   // per-lane index 0..2
        w[1] = SCALE;
        vec3 v = V;
        v[i] = -1.0;                               // per-lane indexed write
        return vec3(w[i] + counter, PI * dot(AXIS, L), v.x + v.y + v.z);
    }"""
    )
    i = (L[:, 0] > 0).astype(int) + (L[:, 1] > 0).astype(int)
    w = np.array([1.0, 2.0, 100.0])[i]
    v = V.copy()
    v[np.arange(COUNT), i] = -1.0
    check(shader, vec3(w + 3.0, 3.14159265358979 * L[:, 2], v.sum(axis=-1)))
    # evaluating twice gives the same result: globals are re-initialized
    program = compile_shader(shader)
    np.testing.assert_array_equal(program.brdf(*DIRS, {}), program.brdf(*DIRS, {}))


def test_python_names_are_plain_glsl_identifiers():
    shader = (
        """
    float exec(float os) { return os * 2.0; }
    float eval = 3.0;
    """
        + SIGNATURE
        + """{
        float __import__ = L.x; float os = 1.0; vec3 __class__ = V; float open = 0.5;
        int globals = 2; float lambda = exec(__import__) + eval + open;
        return vec3(lambda, __class__.y * os, float(globals));
    }"""
    )
    check(shader, vec3(2 * L[:, 0] + 3.5, V[:, 1], np.full(COUNT, 2.0)))


# Componentwise built-ins in their valid domains: (GLSL expression of a, b, c) -> numpy function.
_A = RNG.uniform(-0.9, 0.9, COUNT)
_B = RNG.uniform(0.1, 2.0, COUNT)
_C = RNG.uniform(-3.0, 3.0, COUNT)
BUILTINS = {
    "radians(c)": lambda a, b, c: np.radians(c),
    "degrees(a)": lambda a, b, c: np.degrees(a),
    "sin(c) + cos(c) + tan(a)": lambda a, b, c: np.sin(c) + np.cos(c) + np.tan(a),
    "asin(a)": lambda a, b, c: np.arcsin(a),
    "acos(a)": lambda a, b, c: np.arccos(a),
    "atan(c)": lambda a, b, c: np.arctan(c),
    "atan(a, c)": lambda a, b, c: np.arctan2(a, c),
    "sinh(a) + cosh(a) + tanh(c)": lambda a, b, c: np.sinh(a) + np.cosh(a) + np.tanh(c),
    "asinh(c) + acosh(b + 1.0) + atanh(a)": lambda a, b, c: np.arcsinh(c) + np.arccosh(b + 1) + np.arctanh(a),
    "pow(b, c)": lambda a, b, c: b**c,
    "exp(a) + log(b) + exp2(a) + log2(b)": lambda a, b, c: np.exp(a) + np.log(b) + np.exp2(a) + np.log2(b),
    "sqrt(b) + inversesqrt(b)": lambda a, b, c: np.sqrt(b) + 1 / np.sqrt(b),
    "abs(c) + sign(c)": lambda a, b, c: np.abs(c) + np.sign(c),
    "floor(c) + ceil(c) * 10.0 + trunc(c) * 100.0": lambda a, b, c: np.floor(c) + 10 * np.ceil(c) + 100 * np.trunc(c),
    "round(c * 2.0) + roundEven(c) + fract(c)": lambda a, b, c: np.rint(2 * c) + np.rint(c) + c - np.floor(c),
    "mod(c, b) + mod(-c, 0.7)": lambda a, b, c: c - b * np.floor(c / b) + (-c - 0.7 * np.floor(-c / 0.7)),
    "min(a, c) + max(a, 0.5) + clamp(c, -1.0, b)": lambda a, b, c: (
        np.minimum(a, c) + np.maximum(a, 0.5) + np.clip(c, -1, b)
    ),
    "mix(a, c, b) + mix(1.0, 2.0, c > 0.0)": lambda a, b, c: a + b * (c - a) + np.where(c > 0, 2.0, 1.0),
    "step(0.2, a) + smoothstep(-1.0, 1.5, c)": lambda a, b, c: (
        (a >= 0.2) + np.clip((c + 1) / 2.5, 0, 1) ** 2 * (3 - 2 * np.clip((c + 1) / 2.5, 0, 1))
    ),
    "float(isnan(a / (b - b))) + float(isinf(c / (b - b)))": lambda a, b, c: np.ones_like(a),
    "length(vec2(a, c)) + distance(vec3(a), vec3(c))": lambda a, b, c: np.hypot(a, c) + np.sqrt(3) * np.abs(a - c),
    "fma(a, b, c)": lambda a, b, c: a * b + c,
}


@pytest.mark.parametrize("expression", list(BUILTINS))
def test_componentwise_builtins(expression):
    shader = SIGNATURE + "{ float a = L.x, b = L.y, c = L.z; return vec3(" + expression + "); }"
    dirs = (np.stack([_A, _B, _C], axis=-1), V, N, X, Y)
    value = BUILTINS[expression](_A, _B, _C)
    # llvmpipe's asin/acos are polynomial approximations good to about 3e-4 (measured); the rest to ~1e-6.
    tolerance = 1e-3 if expression in ("asin(a)", "acos(a)") else 5e-5
    check(shader, vec3(value, value, value), dirs=dirs, rtol=1e-13, mesa_rtol=tolerance, mesa_atol=tolerance)


def test_vector_builtins():
    shader = (
        SIGNATURE
        + """{
        vec3 r = reflect(-L, N);
        vec3 t = refract(-L, N, 0.6);
        vec3 f = faceforward(N, L, X);
        vec3 c = cross(X, Y);
        bvec3 lt = lessThan(L, V);
        float b = float(any(lt)) + 2.0 * float(all(lt)) + 4.0 * float(not(lt).x) + float(equal(lt, lt).y);
        return r + t + f + c + b + max(L, 0.25) + min(V, vec3(0.5)) + clamp(N, 0.0, 1.0) + pow(abs(L), vec3(1.5));
    }"""
    )
    c = dot(N, L)
    r = -L + 2 * c[:, None] * N
    k = 1 - 0.36 * (1 - c * c)
    t = np.where((k < 0)[:, None], 0.0, -0.6 * L - (0.6 * -c + np.sqrt(np.maximum(k, 0)))[:, None] * N)
    f = np.where((dot(X, L) < 0)[:, None], N, -N)
    lt = L < V
    b = lt.any(-1) + 2.0 * lt.all(-1) + 4.0 * ~lt[:, 0] + 1.0
    expected = r + t + f + np.cross(X, Y) + b[:, None] + np.maximum(L, 0.25) + np.minimum(V, 0.5)
    expected += np.clip(N, 0, 1) + np.abs(L) ** 1.5
    check(shader, expected, rtol=1e-12)


def test_modf_out_parameter():
    shader = SIGNATURE + "{ vec3 whole; vec3 fraction = modf(L * 7.0, whole); return fraction + 10.0 * whole; }"
    check(shader, (7 * L - np.trunc(7 * L)) + 10 * np.trunc(7 * L), rtol=1e-12)


def test_uniform_branch_runs_only_the_taken_side():
    # The untaken branch would loop forever: a uniform condition must not execute it at all.
    shader = SIGNATURE + "{ if (flag) { while (true) {} } return vec3(L.z); }"
    out = evaluate(shader, {"flag": False}, {"flag": "bool"})
    np.testing.assert_array_equal(out, vec3(L[:, 2], L[:, 2], L[:, 2]))


def test_shader_declared_uniforms_and_scalar_directions():
    shader = "uniform float k;\nuniform vec3 tint;\nuniform float g = 0.5;\n" + SIGNATURE
    shader += "{ return tint * k * dot(L, N) + g - 0.5; }"
    program = compile_shader(shader, uniforms={"k": "float"})
    out = program.brdf(L, V, [0, 0, 1.0], [1.0, 0, 0], [0, 1.0, 0], {"k": 2.0, "tint": (1.0, 2.0, 3.0)})
    np.testing.assert_allclose(out, 2.0 * L[:, 2:3] * np.array([1.0, 2.0, 3.0]), rtol=1e-15)
    assert program.uniforms == {"k": "float", "tint": "vec3", "g": "float"}
    assert {"k", "tint", "dot"} <= program.uses
    single = program.brdf([0, 0, 1.0], [0, 0, 1.0], [0, 0, 1.0], [1.0, 0, 0], [0, 1.0, 0], {"k": 1.0})
    assert single.shape == (3,) and np.all(single == 0)  # an undeclared-by-caller uniform defaults to 0


# --- Mesa's choices where GLSL leaves the result undefined -----------------------------------------------

SPECIAL = np.array([-np.inf, -2.0, -1.0, -0.5, -0.0, 0.0, 0.5, 1.0, 2.0, np.inf, np.nan])
_GA, _GB = (g.ravel() for g in np.meshgrid(SPECIAL, SPECIAL, indexing="ij"))
GRID = (vec3(_GA, _GB, np.zeros_like(_GA)), vec3(_GA, _GB, np.zeros_like(_GA)), N[:1], X[:1], Y[:1])


def _mesa_pow(a, b):
    """pow as measured on llvmpipe: exp2(b·log2(a)), 0 where a is ±0 or NaN, NaN where a < 0."""
    with np.errstate(all="ignore"):
        value = np.exp2(b * np.log2(np.where(a > 0, a, np.nan)))
    return np.where((a == 0) | np.isnan(a), 0.0, value)


def _smoothstep(e0, e1, x):
    with np.errstate(all="ignore"):
        t = np.fmin(np.fmax((x - e0) / (e1 - e0), 0.0), 1.0)
    return t * t * (3 - 2 * t)


def _mesa_atan2(y, x):
    """atan(y, x) as measured: IEEE atan2 except ±3π/4 at (±0, ±0), and NaN arguments (see builtins)."""
    with np.errstate(all="ignore"):
        value = np.arctan2(y, x)
    value = np.where((x == 0) & (y == 0), np.copysign(0.75 * np.pi, y), value)
    value = np.where(np.isnan(y), np.where(x <= 0, np.pi / 2, 0.0), value)
    return np.where(np.isnan(x) & ~np.isnan(y), 0.0, value)


SPECIAL_CASES = {
    "pow(a, b)": _mesa_pow,
    "atan(a, b)": _mesa_atan2,
    "a / b": lambda a, b: np.divide(a, b),
    "mod(a, b)": lambda a, b: a - b * np.floor(a / b),
    "max(a, b)": np.fmax,
    "min(a, b)": np.fmin,
    "clamp(a, 0.0, 1.0) + step(b, a)": lambda a, b: np.fmin(np.fmax(a, 0.0), 1.0) + (a >= b),
    "sign(a) + atan(b)": lambda a, b: np.nan_to_num(np.sign(a), nan=0.0) + np.nan_to_num(np.arctan(b), nan=0.0),
    "tanh(a)": lambda a, b: np.nan_to_num(np.tanh(a), nan=-1.0),
    "sqrt(a) + log(b)": lambda a, b: np.sqrt(a) + np.log(b),
    "inversesqrt(a)": lambda a, b: 1.0 / np.sqrt(a),
    "normalize(vec2(a, b)).x": lambda a, b: a / np.hypot(a, b),
    "smoothstep(a, b, 0.5)": lambda a, b: _smoothstep(a, b, 0.5),
    "mix(1.0, 2.0, a)": lambda a, b: 1.0 + a,
    "fract(a)": lambda a, b: a - np.floor(a),
}


@pytest.mark.parametrize("expression", list(SPECIAL_CASES))
def test_undefined_results_follow_mesa(expression):
    shader = SIGNATURE + "{ float a = L.x, b = L.y; return vec3(" + expression + "); }"
    with np.errstate(all="ignore"):
        expected = SPECIAL_CASES[expression](_GA, _GB)
    ours = evaluate(shader, dirs=GRID)[:, 0]
    np.testing.assert_allclose(ours, expected, rtol=1e-12, atol=0, equal_nan=True)
    theirs = mesa(shader, dirs=GRID)[:, 0]
    # exact special values (NaN, ±inf, 0) must coincide; finite ones to llvmpipe's float32 accuracy (atan ~4e-6)
    np.testing.assert_allclose(ours, theirs, rtol=1e-5, atol=1e-5, equal_nan=True)


def test_pow_rewrites_of_constant_arguments_follow_mesa():
    # Mesa rewrites pow(x, 2.0) to x*x (also through a never-written variable), pow(x, 4.0) to (x*x)^2,
    # pow(2.0, y) to exp2(y), and folds constant calls with the C library: these differ from the run-time
    # rule for negative bases.
    shader = (
        """
    const float TWO = 2.0;
    """
        + SIGNATURE
        + """{
        float a = L.x, k = 4.0;
        return vec3(pow(a, TWO) + pow(a, 3.0), pow(a, k), pow(2.0, a) + pow(-2.0, 3.0) + pow(0.0, 0.0));
    }"""
    )
    with np.errstate(all="ignore"):
        expected = vec3(_GA * _GA + _mesa_pow(_GA, 3.0), (_GA * _GA) ** 2, np.exp2(_GA) - 8.0 + 1.0)
    ours = evaluate(shader, dirs=GRID)
    np.testing.assert_allclose(ours, expected, rtol=1e-12, equal_nan=True)
    np.testing.assert_allclose(ours, mesa(shader, dirs=GRID), rtol=1e-6, equal_nan=True)


def test_calls_with_only_constant_arguments_fold_with_ieee_arithmetic():
    shader = SIGNATURE + "{ return vec3(smoothstep(0.25, 0.25, 0.5), mod(0.5, 0.0), 0.5 / 0.0); }"
    ours = evaluate(shader, dirs=GRID)
    np.testing.assert_array_equal(ours, np.broadcast_to([1.0, np.nan, np.inf], ours.shape))
    np.testing.assert_array_equal(ours, mesa(shader, dirs=GRID))


def test_products_with_and_quotients_of_constant_zero_are_zero_even_for_inf_and_nan():
    shader = SIGNATURE + "{ float a = L.x, b = L.y; return vec3(a * 0.0 + 0.0 * a, 0.0 / a, (a * 0.0) / b); }"
    ours = evaluate(shader, dirs=GRID)
    np.testing.assert_array_equal(ours, 0.0)
    np.testing.assert_allclose(ours, mesa(shader, dirs=GRID), equal_nan=True)


def test_integer_division_and_remainder_by_zero_and_negative_follow_mesa():
    shader = (
        SIGNATURE
        + """{
        int a = int(L.x * 4.0), b = int(L.y);
        return vec3(float(a / b), float(a % b), float(7 % b));
    }"""
    )
    ga, gb = np.meshgrid([-7.0, -1.75, 0.0, 1.0, 1.75], [-3.0, -2.0, 0.0, 2.0, 3.0])
    pairs = vec3(ga.ravel(), gb.ravel(), 0.0)
    dirs = (pairs, pairs, N[:1], X[:1], Y[:1])
    a = np.trunc(dirs[0][:, 0] * 4.0)
    b = np.trunc(dirs[0][:, 1])

    def urem(x, y):  # unsigned 32-bit remainder, x % 0 = 0xFFFFFFFF, read back as signed
        ux, uy = np.mod(x.astype(np.int64), 2**32), np.mod(y.astype(np.int64), 2**32)
        r = np.where(uy == 0, 2**32 - 1, ux % np.maximum(uy, 1))
        return np.where(r >= 2**31, r - 2**32, r).astype(float)

    with np.errstate(all="ignore"):
        div = np.where(b == 0, 0.0, np.trunc(a / b))
    ours = evaluate(shader, dirs=dirs)
    np.testing.assert_array_equal(ours, vec3(div, urem(a, b), urem(np.full_like(b, 7), b)))
    np.testing.assert_array_equal(ours, mesa(shader, dirs=dirs))


# --- errors --------------------------------------------------------------------------------------------


def _error(source: str, **kwargs) -> BrdfFileError:
    with pytest.raises(BrdfFileError) as info:
        compile_shader(source, path="f.brdf", **kwargs)
    return info.value


def _position(source: str, needle: str, first_line: int = 1, first_column: int = 1) -> tuple[int, int]:
    index = source.index(needle)
    row = source.count("\n", 0, index)
    column = index - (source.rfind("\n", 0, index) + 1)
    return first_line + row, (first_column + column if row == 0 else column + 1)


@pytest.mark.parametrize(("first_line", "first_column"), [(1, 1), (12, 1), (3, 57)])
def test_unknown_identifier_position_in_file_numbering(first_line, first_column):
    source = SIGNATURE + "\n{\n    float x = 1.0;\n    return vec3(x * roughnes);\n}"
    error = _error(source, first_line=first_line, first_column=first_column)
    assert (error.line, error.column) == _position(source, "roughnes", first_line, first_column)
    assert "roughnes" in error.message and str(error).startswith(f"f.brdf:{error.line}:{error.column}: ")


def test_position_on_the_first_line_of_a_one_line_shader():
    source = SIGNATURE + " { return vec3(m); }"
    error = _error(source, first_line=1, first_column=80)
    assert (error.line, error.column) == (1, 80 + source.index("m);"))


def test_position_counts_characters_not_bytes():
    source = "// déjà vu, ∫ f dω\n" + SIGNATURE + " { /* é */ return vec3(unknowné); }"
    error = _error(source)
    assert (error.line, error.column) == _position(source, "unknown")


def test_syntax_error_position():
    source = SIGNATURE + "\n{\n    float a = 1.0 +;\n    return vec3(a);\n}"
    error = _error(source, first_line=7)
    assert "syntax error" in error.message
    assert error.line == 7 + 2 and error.column is not None


def test_missing_semicolon_is_a_syntax_error():
    error = _error(SIGNATURE + "{ float a = 1.0\n return vec3(a); }")
    assert "syntax error" in error.message and error.line in (1, 2)


@pytest.mark.parametrize(
    ("body", "needle", "match"),
    [
        ("return vec3(dot(L, V, N));", "dot(", "wrong number of arguments to 'dot'"),
        ("return vec3(max(L, true));", "max(", "no matching overload for 'max"),
        ("return vec3(normalize(1, 2));", "normalize(", "wrong number of arguments"),
        ("return vec3(L.xyzw);", "xyzw", "swizzle"),
        ("return vec3(L + vec2(1.0));", "L + vec2", "cannot be applied"),
        ("float f = true; return vec3(f);", "true", "cannot convert bool to float"),
        ("return vec3(vec4(1.0, 2.0, 3.0));", "vec4(", "not enough components"),
        ("const float c = L.x; return vec3(c);", "L.x", "constant initializer"),
        ("L.x = 1.0; return vec3(dot(L, L) * undefinedThing);", "undefinedThing", "unknown identifier"),
        ("return vec3(foo(1.0));", "foo", "unknown function 'foo'"),
        ("break; return vec3(1);", "break", "outside a loop"),
        ("float a[100000000]; return vec3(a[0]);", "100000000", "exceeds the supported maximum"),
        ("float a[2]; return vec3(a[2]);", "2]);", "index 2 is out of range"),
        ("if (1.0) return vec3(0); return vec3(1);", "1.0)", "condition must be a bool"),
    ],
)
def test_type_and_arity_errors_are_located(body, needle, match):
    source = SIGNATURE + "\n{\n    " + body + "\n}"
    error = _error(source, first_line=5)
    assert match in error.message
    assert (error.line, error.column) == _position(source, needle, first_line=5)


@pytest.mark.parametrize(
    ("source", "feature"),
    [
        ("uniform sampler2D tex;\n" + SIGNATURE + "{ return texture(tex, L.xy).rgb; }", "sampler2D"),
        (SIGNATURE + "{ return texture(L, L.xy).rgb; }", "texture sampling"),
        (SIGNATURE + "{ return textureLod(L, L.xy, 0.0).rgb; }", "texture sampling"),
        ("layout(rgba8) uniform image2D img;\n" + SIGNATURE + "{ return vec3(0); }", "image2D"),
        ("layout(std430) buffer B { float d[]; };\n" + SIGNATURE + "{ return vec3(0); }", "storage buffers"),
        ("struct S { float a; };\n" + SIGNATURE + "{ return vec3(0); }", "structs"),
        ("#define SQ(x) ((x)*(x))\n" + SIGNATURE + "{ return vec3(SQ(L.x)); }", "function-like macro"),
        ("#ifdef FOO\n#endif\n" + SIGNATURE + "{ return vec3(0); }", "#ifdef"),
        (SIGNATURE + "{ return vec3(dFdx(L.x)); }", "derivatives"),
        (SIGNATURE + "{ double d = 1.0; return vec3(d); }", "double"),
        (SIGNATURE + "{ if (L.x < 0.0) discard; return L; }", "discard"),
        (SIGNATURE + "{ return gl_FragCoord.xyz; }", "gl_FragCoord"),
    ],
)
def test_unsupported_features_are_named(source, feature):
    error = _error(source)
    assert "unsupported" in error.message and feature in error.message


def test_missing_and_wrong_brdf_signature():
    assert "no BRDF function" in _error("float f(float x) { return x; }").message
    error = _error("\n\nfloat BRDF(vec3 L, vec3 V) { return 1.0; }")
    assert "wrong signature" in error.message and "float BRDF(vec3, vec3)" in error.message
    assert error.line == 3


@pytest.mark.parametrize(
    "source",
    [
        "float f(float x) { return x > 1.0 ? f(x - 1.0) : x; }\n" + SIGNATURE + "{ return vec3(f(L.x)); }",
        "float g(float x);\nfloat f(float x) { return g(x); }\nfloat g(float x) { return f(x); }\n"
        + SIGNATURE
        + "{ return vec3(f(L.x)); }",
    ],
)
def test_recursion_is_refused_at_compile_time(source):
    error = _error(source)
    assert "recursion" in error.message and error.line in (1, 2, 3)


def test_infinite_loops_stop_with_an_evaluation_error():
    for body, needle in (
        ("while (true) {}", "while"),
        ("for (;;) { if (L.x > 2.0) break; }", "for"),
        ("float s = 0.0; while (L.x > -2.0) s += 1.0;", "while"),
    ):
        source = SIGNATURE + "\n{\n    " + body + "\n    return vec3(1);\n}"
        program = compile_shader(source, path="loop.brdf", first_line=10)
        with pytest.raises(EvaluationError, match=f"loop exceeded {MAX_LOOP_ITERATIONS} iterations") as info:
            program.brdf(*DIRS, {})
        line, column = _position(source, needle, first_line=10)
        assert str(info.value).startswith(f"loop.brdf:{line}:{column}: ")


def test_nested_loops_are_bounded_in_total():
    source = SIGNATURE + "{ float s = 0.0; for (int i = 0; i < 5000; i++) for (int j = 0; j < 5000; j++) s += 1.0;"
    source += " return vec3(s); }"
    with pytest.raises(EvaluationError, match="in total"):
        compile_shader(source).brdf(*DIRS, {})


def test_missing_uniform_value_is_an_evaluation_error():
    program = compile_shader(SIGNATURE + "{ return vec3(n); }", uniforms={"n": "float"})
    with pytest.raises(EvaluationError, match="'n'"):
        program.brdf(*DIRS, {})


def test_deep_nesting_is_a_file_error_not_a_crash():
    source = (
        SIGNATURE + "{ float x = 0.0; " + "if (L.x > 0.0) {" * 2000 + "x = 1.0;" + "}" * 2000 + " return vec3(x); }"
    )
    assert "nested too deeply" in _error(source).message


def test_temporaries_reused_in_place_never_clobber_variables_or_inputs():
    shader = (
        SIGNATURE
        + """{
        float x = L.x * 3.0;
        float y = mod(x, 0.0) * 2.0;            // mod(x, 0.0) passes x through: not a temporary
        vec3 H = L + V;
        vec3 h = normalize(H) * 2.0;             // normalize of a variable: H must stay unnormalized
        float p = pow(max(0.0, x), 2.5) + 1.0;   // max/pow reuse their temporary argument
        float m = mix(x, 5.0, 0.0) * 0.5;        // mix(x, y, 0.0) passes x through
        return vec3(x + y + m, H.y + h.z, p) + L * 0.0;
    }"""
    )
    before = [d.copy() for d in DIRS]
    x = L[:, 0] * 3.0
    H = L + V
    expected = vec3(x + 2 * x + 0.5 * x, H[:, 1] + 2 * _unit(H)[:, 2], np.maximum(0, x) ** 2.5 + 1.0)
    check(shader, expected, rtol=1e-12)
    for d, b in zip(DIRS, before, strict=True):
        np.testing.assert_array_equal(d, b)


def test_assigning_a_const_parameter_or_a_uniform_is_refused():
    source = "float f(const in float a) { a = 1.0; return a; }\n" + SIGNATURE + "{ return vec3(f(L.x)); }"
    error = _error(source)
    assert "cannot assign to const parameter 'a'" in error.message and (error.line, error.column) == (1, 29)
    error = _error(SIGNATURE + "{ n += 1.0; return vec3(n); }", uniforms={"n": "float"})
    assert "cannot assign to uniform 'n'" in error.message
