"""GLSL built-in functions (GLSL 4.10 §8.1–§8.7) on component tuples, with Mesa llvmpipe's semantics.

Each built-in is resolved from its argument types to a result type and an implementation taking the
arguments' component tuples (see :mod:`.types`). Where the specification leaves a result undefined,
the implementation does what Mesa 22.3's llvmpipe returns, as measured with compute shaders over the
special values ±0, ±1, ±2, ±0.5, ±inf and NaN (tests/glsl/test_compiler.py re-measures them when an EGL
context can be created):

* ``pow(x, y)`` is evaluated as ``exp2(y·log2(x))`` with ``x == 0 → 0``: NaN for x < 0 (any y), 0 for
  x = ±0 or NaN (any y), NaN for 1^±inf, 1^NaN and inf^0. Mesa's optimizer first rewrites a constant
  exponent 1, 2, 4 to ``x``, ``x·x``, ``(x·x)·(x·x)`` and a constant base 2 to ``exp2(y)`` (so
  ``pow(-2.0, 2.0)`` is 4) and folds calls with constant arguments with the C library's ``powf``;
  :func:`pow_impl` takes the constant arguments to do the same.
* ``atan(y, x)`` follows Mesa's ``nir_atan2``: ±3π/4 at x = y = 0, ±π/2 or ±0 when an argument is
  NaN; ``atan(NaN) = 0``; ``tanh(NaN) = -1``; ``sign(NaN) = 0``.
* ``min``/``max``/``clamp`` return the other operand when one is NaN (``clamp(NaN, 0, 1) = 0``),
  ``step(e, NaN) = 0``, ``mix(x, y, a) = x + a·(y − x)``, ``mod(x, y) = x − y·floor(x/y)``,
  ``fract(x) = x − floor(x)``, ``inversesqrt(x) = 1/sqrt(x)``, ``normalize(0) = NaN``,
  ``smoothstep(e, e, x)`` is 1 above the edge and 0 at or below it (clamp of ±inf and NaN),
  round = roundEven.

Everything else is IEEE float64 arithmetic; float32 overflow and underflow are not imitated.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from .types import BOOL, FLOAT, Type

Components = tuple
Impl = Callable[..., Components]
Resolved = tuple[Type, Impl]

HALF_PI = 0.5 * math.pi


def _fix_nan(result, value):
    """``result`` with NaN lanes replaced by ``value`` (only when there are any)."""
    nan = result != result
    if np.any(nan):
        return np.where(nan, value, result)
    return result


# --- componentwise scalar functions with Mesa's special cases -------------------------------------------


def pow_runtime(x, y, out=None):
    """Mesa's run-time ``pow``: ``exp2(y·log2(x))``, 0 where x is 0 or NaN (see module docstring).

    ``out`` may be ``x`` itself (a temporary): the masks are taken before it is overwritten.
    """
    positive = x > 0
    special = None if np.all(positive) else np.where(x < 0, np.nan, 0.0)
    # exp2(log2(x)·y) is NaN where the product is 0·inf: 1^±inf, 1^NaN, inf^0 (np.power gives 1 there).
    if np.ndim(y) == 0:
        bad = (x == np.inf) if y == 0 else (x == 1) if not np.isfinite(y) else None
    else:
        bad = ((x == 1) & ~np.isfinite(y)) | ((x == np.inf) & (y == 0))
    result = np.power(x, y, out=out)
    if special is not None:
        result = np.where(positive, result, special)
    if bad is not None and np.any(bad):
        result = np.where(bad, np.nan, result)
    return result


def pow_impl(x_const, y_const) -> Callable:
    """Componentwise ``pow`` given the constant components of base and exponent (None if not constant)."""
    if x_const is not None and y_const is not None:
        return np.power  # constant folding uses the C library's powf
    if y_const is not None:
        if y_const == 1.0:
            return lambda x, y: x
        if y_const == 2.0:
            return lambda x, y: x * x
        if y_const == 4.0:
            return lambda x, y: (x * x) * (x * x)
    if x_const is not None and x_const == 2.0:
        return lambda x, y: np.exp2(y)
    return pow_runtime


def _atan2_mesa(y, x):
    # nir_atan2: rotate the left half-plane by π/2, take atan(|s|/|t|) with 0/0 and ∞/∞ read as 1.
    flip = x <= 0
    ax = np.abs(x)
    s = np.where(flip, ax, y)
    t = np.where(flip, y, ax)
    with np.errstate(all="ignore"):
        ratio = np.where(ax == np.abs(y), 1.0, np.abs(s) / np.abs(t))
        arc = np.where(flip, HALF_PI, 0.0) + _fix_nan(np.arctan(ratio), 0.0)
        negative = np.fmin(y, 1.0 / t) < 0
    return np.where(negative, -arc, arc)


def atan2(y, x):
    """GLSL ``atan(y, x)`` with Mesa's results at zeros and NaN (see the module docstring)."""
    result = np.arctan2(y, x)
    special = ((x == 0) & (y == 0)) | (x != x) | (y != y)
    if np.any(special):
        result = np.where(special, _atan2_mesa(y, x), result)
    return result


def _atan(x):
    return _fix_nan(np.arctan(x), 0.0)


def _tanh(x):
    return _fix_nan(np.tanh(x), -1.0)


def _sign(x):
    return _fix_nan(np.sign(x), 0.0)


def _fract(x):
    return x - np.floor(x)


def _mod(x, y):
    return x - y * np.floor(x / y)


def _clamp(x, lo, hi, out=None):
    return np.fmin(np.fmax(x, lo, out=out), hi, out=out)


def _mix(x, y, a):
    return x + a * (y - x)


def _step(edge, x):
    return np.where(x >= edge, 1.0, 0.0)


def _smoothstep(e0, e1, x):
    t = _clamp((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _inversesqrt(x):
    return 1.0 / np.sqrt(x)


_RADIANS = math.pi / 180.0
_DEGREES = 180.0 / math.pi

# name -> (function of components, has integer overloads)
_UNARY: dict[str, Callable] = {
    "radians": lambda x: x * _RADIANS,
    "degrees": lambda x: x * _DEGREES,
    "sin": np.sin,
    "cos": np.cos,
    "tan": np.tan,
    "asin": np.arcsin,
    "acos": np.arccos,
    "sinh": np.sinh,
    "cosh": np.cosh,
    "tanh": _tanh,
    "asinh": np.arcsinh,
    "acosh": np.arccosh,
    "atanh": np.arctanh,
    "exp": np.exp,
    "log": np.log,
    "exp2": np.exp2,
    "log2": np.log2,
    "sqrt": np.sqrt,
    "inversesqrt": _inversesqrt,
    "floor": np.floor,
    "ceil": np.ceil,
    "trunc": np.trunc,
    "round": np.rint,
    "roundEven": np.rint,
    "fract": _fract,
}

# Componentwise functions: name -> list of (parameter pattern, function, integer overloads allowed).
# Pattern letters: g = genType (float or vecN, all g of one size), s = float scalar, b = bool / bvecN.
_COMPONENTWISE: dict[str, list[tuple[str, Callable, bool]]] = {
    **{name: [("g", fn, False)] for name, fn in _UNARY.items()},
    "atan": [("g", _atan, False), ("gg", atan2, False)],
    "abs": [("g", np.abs, True)],
    "sign": [("g", _sign, True)],
    "pow": [("gg", pow_runtime, False)],
    "mod": [("gg", _mod, False), ("gs", _mod, False)],
    "min": [("gg", np.fmin, True), ("gs", np.fmin, True)],
    "max": [("gg", np.fmax, True), ("gs", np.fmax, True)],
    "clamp": [("ggg", _clamp, True), ("gss", _clamp, True)],
    "mix": [("ggg", _mix, False), ("ggs", _mix, False), ("ggb", lambda x, y, a: np.where(a, y, x), False)],
    "step": [("gg", _step, False), ("sg", _step, False)],
    "smoothstep": [("ggg", _smoothstep, False), ("ssg", _smoothstep, False)],
    "fma": [("ggg", lambda a, b, c: a * b + c, False)],
}

_PREDICATES: dict[str, Callable] = {"isnan": np.isnan, "isinf": np.isinf}

_RELATIONAL: dict[str, Callable] = {
    "lessThan": np.less,
    "lessThanEqual": np.less_equal,
    "greaterThan": np.greater,
    "greaterThanEqual": np.greater_equal,
    "equal": np.equal,
    "notEqual": np.not_equal,
}


def _vector_size(t: Type) -> int | None:
    """Vector size of a scalar or vector (not matrix, not array) type, else None."""
    if t.length is not None or t.cols != 1 or t.base == "void":
        return None
    return t.rows


def _resolve_componentwise(name: str, args: Sequence[Type], reusable: Sequence[bool] = ()) -> Resolved | None:
    for pattern, fn, integer in _COMPONENTWISE[name]:
        if len(pattern) != len(args):
            continue
        sizes = [_vector_size(t) for t in args]
        if None in sizes:
            continue
        n = max(size for size, p in zip(sizes, pattern, strict=False) if p == "g")
        ok = all(
            (p == "g" and size == n and t.is_numeric)
            or (p == "s" and size == 1 and t.is_numeric)
            or (p == "b" and size == n and t.base == "bool")
            for p, size, t in zip(pattern, sizes, args, strict=False)
        )
        if not ok:
            continue
        numeric = [t.base for t, p in zip(args, pattern, strict=False) if p != "b"]
        base = numeric[0] if integer and all(b == numeric[0] for b in numeric) and numeric[0] != "float" else "float"
        expand = [n if size == 1 and n > 1 else 0 for size in sizes]

        def impl(*values, fn=fn, n=n, expand=expand):
            values = [v * e if e else v for v, e in zip(values, expand, strict=False)]
            return tuple(fn(*(v[i] for v in values)) for i in range(n))

        # A temporary argument of full size can receive a ufunc's result (fewer large allocations).
        buffer = next((k for k, r in enumerate(reusable) if r and sizes[k] == n and pattern[k] == "g"), None)
        if buffer is not None and (isinstance(fn, np.ufunc) or (fn in (_clamp, pow_runtime) and buffer == 0)):

            def impl(*values, fn=fn, n=n, expand=expand, k=buffer):  # noqa: F811
                values = [v * e if e else v for v, e in zip(values, expand, strict=False)]
                out = []
                for i in range(n):
                    comps = [v[i] for v in values]
                    target = comps[k]
                    if in_place_ok(target, 0.0) and all(in_place_ok(target, c) for j, c in enumerate(comps) if j != k):
                        out.append(fn(*comps, out=target))
                    else:
                        out.append(fn(*comps))
                return tuple(out)

        return Type(base, n), impl
    return None


def in_place_ok(buffer, other) -> bool:
    """True when ``buffer`` (a temporary of ours) can receive ``buffer ∘ other`` in place."""
    return (
        isinstance(buffer, np.ndarray)
        and buffer.ndim > 0
        and buffer.dtype == np.float64
        and (np.ndim(other) == 0 or np.shape(other) == buffer.shape)
    )


def _dot(a: Components, b: Components):
    # Accumulates in place: fresh allocations of large arrays (page faults) dominate the cost otherwise.
    total = a[0] * b[0]
    buffer = None
    for x, y in zip(a[1:], b[1:], strict=True):
        if isinstance(buffer, np.ndarray) and buffer.ndim and np.shape(x) == buffer.shape == np.shape(y):
            term = np.multiply(x, y, out=buffer)
        else:
            term = buffer = x * y
        total = np.add(total, term, out=total) if in_place_ok(total, term) else total + term
    return total


def _normalize(v: Components) -> Components:
    scale = _dot(v, v)
    if in_place_ok(scale, 0.0):
        np.sqrt(scale, out=scale)
        np.divide(1.0, scale, out=scale)
    else:
        scale = 1.0 / np.sqrt(scale)
    return tuple(x * scale for x in v)


def _reflect(i: Components, n: Components) -> Components:
    d2 = 2.0 * _dot(n, i)
    return tuple(x - d2 * y for x, y in zip(i, n, strict=False))


def _refract(i: Components, n: Components, eta: Components) -> Components:
    (e,) = eta
    d = _dot(n, i)
    k = 1.0 - e * e * (1.0 - d * d)
    outside = k < 0
    scale = e * d + np.sqrt(k)
    return tuple(np.where(outside, 0.0, e * x - scale * y) for x, y in zip(i, n, strict=False))


def _faceforward(n: Components, i: Components, nref: Components) -> Components:
    front = _dot(nref, i) < 0
    return tuple(np.where(front, x, -x) for x in n)


def _cross(a: Components, b: Components) -> Components:
    return (a[1] * b[2] - b[1] * a[2], a[2] * b[0] - b[2] * a[0], a[0] * b[1] - b[0] * a[1])


def _normalize_in_place(v: Components) -> Components:
    scale = 1.0 / np.sqrt(_dot(v, v))
    return tuple(np.multiply(x, scale, out=x) if in_place_ok(x, scale) else x * scale for x in v)


def _resolve_geometric(name: str, args: Sequence[Type], reusable: Sequence[bool] = ()) -> Resolved | None:
    sizes = [_vector_size(t) for t in args]
    if None in sizes or not all(t.is_numeric for t in args):
        return None
    if name == "normalize" and len(args) == 1 and reusable and reusable[0]:
        return Type("float", sizes[0]), _normalize_in_place
    n = sizes[0]
    same = all(size == n for size in sizes)
    vec = Type("float", n)
    if name == "length" and len(args) == 1:
        return FLOAT, lambda a: (np.sqrt(_dot(a, a)),)
    if name == "distance" and len(args) == 2 and same:
        return FLOAT, lambda a, b: (np.sqrt(_dot(*[tuple(x - y for x, y in zip(a, b, strict=False))] * 2)),)
    if name == "dot" and len(args) == 2 and same:
        return FLOAT, lambda a, b: (_dot(a, b),)
    if name == "cross" and len(args) == 2 and same and n == 3:
        return vec, _cross
    if name == "normalize" and len(args) == 1:
        return vec, _normalize
    if name == "faceforward" and len(args) == 3 and same:
        return vec, _faceforward
    if name == "reflect" and len(args) == 2 and same:
        return vec, _reflect
    if name == "refract" and len(args) == 3 and sizes[0] == sizes[1] and sizes[2] == 1:
        return vec, _refract
    return None


# --- matrices --------------------------------------------------------------------------------------------


def determinant_of(m: Components, n: int):
    """Determinant of an n×n column-major matrix by cofactor expansion along the first column."""
    if n == 1:
        return m[0]
    if n == 2:
        return m[0] * m[3] - m[2] * m[1]
    total = 0.0
    for i in range(n):
        minor = _minor(m, n, i, 0)
        term = m[i] * determinant_of(minor, n - 1)
        total = total + term if i % 2 == 0 else total - term
    return total


def _minor(m: Components, n: int, row: int, col: int) -> Components:
    return tuple(m[j * n + i] for j in range(n) if j != col for i in range(n) if i != row)


def _inverse(m: Components, n: int) -> Components:
    # Adjugate over determinant, as Mesa's GLSL built-in implementation does (no pivoting, no error for
    # singular matrices: inf / NaN).
    inv_det = 1.0 / determinant_of(m, n)
    out = []
    for j in range(n):  # column j of the inverse = row j of the cofactor matrix
        for i in range(n):
            cofactor = determinant_of(_minor(m, n, j, i), n - 1) if n > 1 else 1.0
            sign = 1.0 if (i + j) % 2 == 0 else -1.0
            out.append(sign * cofactor * inv_det)
    return tuple(out)


def _resolve_matrix(name: str, args: Sequence[Type]) -> Resolved | None:
    if name == "matrixCompMult" and len(args) == 2 and args[0] == args[1] and args[0].is_matrix:
        return args[0], lambda a, b: tuple(x * y for x, y in zip(a, b, strict=False))
    if name == "outerProduct" and len(args) == 2:
        c, r = args
        if c.is_vector and r.is_vector and c.is_numeric and r.is_numeric:
            return Type("float", c.rows, r.rows), lambda a, b: tuple(x * y for y in b for x in a)
    if len(args) != 1 or not args[0].is_matrix:
        return None
    (m,) = args
    if name == "transpose":
        rows, cols = m.rows, m.cols
        return Type("float", cols, rows), lambda a: tuple(a[j * rows + i] for i in range(rows) for j in range(cols))
    if m.rows != m.cols:
        return None
    if name == "determinant":
        return FLOAT, lambda a: (determinant_of(a, m.rows),)
    if name == "inverse":
        return m, lambda a: _inverse(a, m.rows)
    return None


# --- vector relational -------------------------------------------------------------------------------------


def _resolve_relational(name: str, args: Sequence[Type]) -> Resolved | None:
    if name in ("any", "all", "not"):
        if len(args) != 1 or not args[0].is_vector or args[0].base != "bool":
            return None
        if name == "not":
            return args[0], lambda a: tuple(np.logical_not(x) for x in a)
        reduce = np.logical_or if name == "any" else np.logical_and

        def fold(a, reduce=reduce):
            out = a[0]
            for x in a[1:]:
                out = reduce(out, x)
            return (out,)

        return BOOL, fold
    if len(args) != 2 or args[0].rows != args[1].rows or not args[0].is_vector or not args[1].is_vector:
        return None
    a, b = args
    if name in ("equal", "notEqual") and a.base == b.base == "bool":
        pass
    elif not (a.is_numeric and b.is_numeric):
        return None
    fn = _RELATIONAL[name]
    return Type("bool", a.rows), lambda x, y: tuple(fn(p, q) for p, q in zip(x, y, strict=False))


def _resolve_predicate(name: str, args: Sequence[Type]) -> Resolved | None:
    if len(args) != 1 or _vector_size(args[0]) is None or not args[0].is_numeric:
        return None
    fn = _PREDICATES[name]
    return Type("bool", args[0].rows), lambda a: tuple(fn(x) for x in a)


_RESOLVERS: dict[str, Callable[[str, Sequence[Type]], Resolved | None]] = {
    **{name: _resolve_componentwise for name in _COMPONENTWISE},
    **{
        name: _resolve_geometric
        for name in ("length", "distance", "dot", "cross", "normalize", "faceforward", "reflect", "refract")
    },
    **{name: _resolve_matrix for name in ("matrixCompMult", "outerProduct", "transpose", "determinant", "inverse")},
    **{name: _resolve_relational for name in (*_RELATIONAL, "any", "all", "not")},
    **{name: _resolve_predicate for name in _PREDICATES},
}

#: Number of parameters each built-in accepts (for "wrong number of arguments" messages).
ARITY: dict[str, tuple[int, ...]] = {
    **{name: tuple(sorted({len(p) for p, _, _ in specs})) for name, specs in _COMPONENTWISE.items()},
    "length": (1,),
    "distance": (2,),
    "dot": (2,),
    "cross": (2,),
    "normalize": (1,),
    "faceforward": (3,),
    "reflect": (2,),
    "refract": (3,),
    "matrixCompMult": (2,),
    "outerProduct": (2,),
    "transpose": (1,),
    "determinant": (1,),
    "inverse": (1,),
    **{name: (2,) for name in _RELATIONAL},
    "any": (1,),
    "all": (1,),
    "not": (1,),
    "isnan": (1,),
    "isinf": (1,),
    "modf": (2,),
}

#: Built-ins of GLSL outside the subset, mapped to the feature they belong to (for the error message).
UNSUPPORTED: dict[str, str] = {
    **{
        name: "texture sampling"
        for name in (
            "texture texture1D texture2D texture3D textureCube textureLod textureProj textureGrad textureOffset "
            "texelFetch texelFetchOffset textureSize textureQueryLod textureQueryLevels textureGather "
            "textureGatherOffset textureGatherOffsets textureProjLod textureProjGrad textureLodOffset "
            "textureGradOffset textureProjOffset textureSamples shadow2D"
        ).split()
    },
    **{
        name: "image load/store"
        for name in (
            "imageLoad imageStore imageSize imageAtomicAdd imageAtomicMin imageAtomicMax imageAtomicAnd "
            "imageAtomicOr imageAtomicXor imageAtomicExchange imageAtomicCompSwap"
        ).split()
    },
    **{
        name: "atomic operations"
        for name in (
            "atomicAdd atomicMin atomicMax atomicAnd atomicOr atomicXor atomicExchange atomicCompSwap "
            "atomicCounter atomicCounterIncrement atomicCounterDecrement"
        ).split()
    },
    **{name: "derivatives (fragment shaders only)" for name in "dFdx dFdy fwidth dFdxFine dFdyFine".split()},
    **{name: "noise functions" for name in "noise1 noise2 noise3 noise4".split()},
    **{name: "barriers" for name in "barrier memoryBarrier groupMemoryBarrier".split()},
    **{name: "fragment discard/interpolation" for name in "interpolateAtCentroid interpolateAtSample".split()},
    **{
        name: "bit-level floating-point functions"
        for name in (
            "floatBitsToInt floatBitsToUint intBitsToFloat uintBitsToFloat frexp ldexp packUnorm2x16 "
            "unpackUnorm2x16 packHalf2x16 unpackHalf2x16 bitfieldExtract bitfieldInsert bitfieldReverse "
            "bitCount findLSB findMSB uaddCarry usubBorrow umulExtended imulExtended"
        ).split()
    },
}


#: Built-ins whose result components are always new arrays (never an argument passed through), so the
#: compiler may reuse them as output buffers.
FRESH = frozenset(_COMPONENTWISE) - {"pow"} | {
    "length",
    "distance",
    "dot",
    "cross",
    "normalize",
    "faceforward",
    "reflect",
    "refract",
}


def is_builtin(name: str) -> bool:
    """Whether ``name`` is a supported built-in function."""
    return name in _RESOLVERS or name == "modf"


def resolve(name: str, args: Sequence[Type], reusable: Sequence[bool] = ()) -> Resolved | None:
    """Result type and implementation of built-in ``name`` for argument types ``args``, or None.

    ``reusable[k]`` tells that argument k's components are temporaries the result may be written into.
    """
    if reusable and _RESOLVERS[name] in (_resolve_componentwise, _resolve_geometric):
        return _RESOLVERS[name](name, args, reusable)
    return _RESOLVERS[name](name, args)
