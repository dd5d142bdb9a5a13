"""Audit a fitted formula: a Python-syntax expression (parsed by :mod:`ast` into a whitelist evaluator, never
``eval``) or a GLSL function compiled by brdfnorm's GLSL compiler, against the exact quantity it approximates.

Expression: real numbers (an integer beyond float range refused), the named arguments, + − * / **, unary −, and
calls of :data:`FUNCTIONS` with exactly their number of arguments (:data:`ARITY`, checked at compile time, so that
no argument can land in numpy's positional ``out``); an exponent must be a number of magnitude ≤
:data:`MAX_EXPONENT` or an expression (evaluated in float64, where overflow is inf, not a hang); anything else
(attributes, subscripts, other names, lambdas, comprehensions, strings, complex numbers, keywords) is refused with
one error naming the construct. A formula whose value is not finite somewhere on the domain (an overflow, a
division by zero, a logarithm of a negative) is refused naming the first such point: its error is not a number.
GLSL: the function ``NAME`` is called from a generated ``BRDF`` entry point that passes the arguments in the
components of L and V; its result (float, vec2, vec3, vec4) gives one quantity per component (``quantities``).

The domain is a node grid over μ ∈ [μ_min, 1] and the roughness axis (r with α = r², or α), with the same
clamps as the tables (μ ≥ 1e-4, α ≥ 1e-8); the exact values come from :class:`.reference.Reference`.
"""

from __future__ import annotations

import ast
import math

import numpy as np

from ..errors import ArgumentError
from ..inputs import read_bounded, shorten
from ..inputs.literals import Scanner
from ..lut.splitsum import DFG_F0, DFG_F90
from .reference import Reference

FUNCTIONS = {
    "exp": np.exp, "log": np.log, "sqrt": np.sqrt, "pow": np.power, "sin": np.sin, "cos": np.cos,
    "tan": np.tan, "atan": np.arctan, "asin": np.arcsin, "acos": np.arccos, "abs": np.abs, "min": np.minimum,
    "max": np.maximum, "floor": np.floor, "exp2": np.exp2, "log2": np.log2, "tanh": np.tanh,
    "clamp": lambda x, a, b: np.clip(x, a, b), "saturate": lambda x: np.clip(x, 0.0, 1.0),
    "mix": lambda a, b, t: a + (b - a) * t,
}
#: How many arguments each function takes.
ARITY = {name: 1 for name in FUNCTIONS} | {"pow": 2, "min": 2, "max": 2, "clamp": 3, "mix": 3}
MAX_EXPONENT = 64.0
MAX_TEXT = 4000
MAX_NODES = 2000
ARGUMENTS = ("mu", "r", "alpha", "theta")
QUANTITIES = ("E", "1-E", DFG_F0, DFG_F90, "E_avg")


def compile_expression(text: str, names: tuple[str, ...]):
    """A function of keyword arrays ``names`` evaluating ``text`` (see the module docstring)."""
    where = "--formula"
    if len(text) > MAX_TEXT:
        raise ArgumentError(f"expression longer than {MAX_TEXT} characters", where=where)
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, RecursionError, ValueError, MemoryError) as error:
        raise ArgumentError(f"not an arithmetic expression ({type(error).__name__})", where=where) from None
    count = sum(1 for _ in ast.walk(tree))
    if count > MAX_NODES:
        raise ArgumentError(f"expression of more than {MAX_NODES} nodes", where=where)
    binary = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide,
              ast.Pow: np.power}

    def build(node):
        if isinstance(node, ast.Expression):
            return build(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value,
                                                                                                        bool):
            try:
                value = float(node.value)
            except OverflowError:
                bits = abs(node.value).bit_length()  # str() of a huge integer is refused by Python itself
                raise ArgumentError(f"an integer of about {int(bits * 0.30103) + 1} digits, beyond float range",
                                    where=where) from None
            return lambda env: value
        if isinstance(node, ast.Constant):
            kind = "complex number" if isinstance(node.value, complex) else type(node.value).__name__
            raise ArgumentError(f"a {kind} constant ({shorten(repr(node.value), 40)}); a formula takes real numbers "
                                "only", where=where)
        if isinstance(node, ast.Name):
            if node.id not in names:
                raise ArgumentError(f"unknown name {node.id!r} (the arguments are {', '.join(names)})", where=where)
            name = node.id
            return lambda env: env[name]
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            inner = build(node.operand)
            return (lambda env: -inner(env)) if isinstance(node.op, ast.USub) else inner
        if isinstance(node, ast.BinOp) and type(node.op) in binary:
            op, left, right = binary[type(node.op)], build(node.left), build(node.right)  # operands checked first
            if isinstance(node.op, ast.Pow):
                _exponent_bounded(node.right)
            return lambda env: op(left(env), right(env))
        if isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS or node.keywords:
                what = node.func.id if isinstance(node.func, ast.Name) else type(node.func).__name__.lower()
                raise ArgumentError(f"call of {shorten(repr(what), 40)} refused (allowed: "
                                    f"{', '.join(sorted(FUNCTIONS))}; no keyword arguments)", where=where)
            name = node.func.id
            if len(node.args) != ARITY[name] or any(isinstance(a, ast.Starred) for a in node.args):
                raise ArgumentError(f"{name}() takes {ARITY[name]} argument{'s' if ARITY[name] > 1 else ''}, "
                                    f"{len(node.args)} given", where=where)
            function, args = FUNCTIONS[name], [build(a) for a in node.args]
            if name == "pow":
                _exponent_bounded(node.args[1])
            return lambda env: function(*(a(env) for a in args))
        raise ArgumentError(f"{type(node).__name__} is not allowed in a formula (numbers, arguments, + - * / **, "
                            "and math functions only)", where=where)

    try:
        return build(tree)
    except RecursionError:
        raise ArgumentError("expression nested too deeply", where=where) from None


def _exponent_bounded(exponent: ast.expr) -> None:
    """A constant exponent (signed) of magnitude at most :data:`MAX_EXPONENT` (an operand already checked real)."""
    if isinstance(exponent, ast.UnaryOp) and isinstance(exponent.operand, ast.Constant):
        exponent = exponent.operand
    if isinstance(exponent, ast.Constant) and abs(float(exponent.value)) > MAX_EXPONENT:
        raise ArgumentError(f"exponent {shorten(exponent.value, 40)} larger than {MAX_EXPONENT:g} in magnitude",
                            where="formula")


def _glsl_signature(text: str, name: str, where: str) -> tuple[str, list[tuple[str, str]]]:
    """(return type, [(type, name)]) of the first definition of function ``name`` — a linear token scan."""
    tokens = list(Scanner(text, where).tokens())
    for k in range(1, len(tokens) - 1):
        if tokens[k][:2] == ("id", name) and tokens[k + 1][:2] == ("op", "(") and tokens[k - 1][0] == "id":
            params, j, current = [], k + 2, []
            while j < len(tokens) and tokens[j][:2] != ("op", ")"):
                if tokens[j][:2] == ("op", ","):
                    params.append(current)
                    current = []
                elif tokens[j][0] == "id":
                    current.append(tokens[j][1])
                j += 1
            if current:
                params.append(current)
            params = [p for p in params if p and p != ["void"]]
            return tokens[k - 1][1], [(p[-2] if len(p) >= 2 else "float", p[-1]) for p in params]
    raise ArgumentError(f"no function {name!r} in the file", where=where)


def compile_glsl(path: str, function: str, bindings: dict[str, str | float]):
    """A function of keyword arrays (mu, r, alpha, theta) returning a list of component arrays."""
    from ..glsl import compile_shader

    text = read_bounded(path, 1024 * 1024).decode("utf-8", errors="replace")
    returns, params = _glsl_signature(text, function, path)
    slots = ["L.x", "L.y", "L.z", "V.x", "V.y", "V.z"]
    call, carried = [], []
    for kind, pname in params:
        if pname not in bindings:
            raise ArgumentError(f"argument {pname} of {function} is not bound (give --args {pname}=mu|r|alpha|NUMBER)",
                                where="bindings")
        value = bindings[pname]
        if isinstance(value, float):
            call.append(f"{kind}({value!r})")
        else:
            if kind != "float" or len(carried) == len(slots):
                raise ArgumentError(f"argument {pname} ({kind}) can take a number; only float arguments take "
                                    "mu, r, alpha or theta", where="bindings")
            call.append(slots[len(carried)])
            carried.append(value)
    result = {"float": "vec3({0}, 0.0, 0.0)", "vec2": "vec3({0}, 0.0)", "vec3": "{0}",
              "vec4": "({0}).xyz"}.get(returns)
    if result is None:
        raise ArgumentError(f"{function} returns {returns}; float, vec2, vec3 or vec4 expected", where="function")
    shim = ("\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return "
            + result.format(f"{function}({', '.join(call)})") + "; }\n")
    program = compile_shader(text + shim, path=path)
    width = {"float": 1, "vec2": 2, "vec3": 3, "vec4": 3}[returns]

    def evaluate(env):
        n = next(iter(env.values())).shape
        columns = [env[name] for name in carried] + [np.zeros(n)] * (6 - len(carried))
        L = np.stack(columns[:3], axis=-1)
        V = np.stack(columns[3:], axis=-1)
        axis = np.broadcast_to(np.array([0.0, 0.0, 1.0]), L.shape)
        out = program.brdf(L, V, axis, np.broadcast_to(np.array([1.0, 0, 0]), L.shape),
                           np.broadcast_to(np.array([0.0, 1, 0]), L.shape), {})
        return [out[..., i] for i in range(width)]

    return evaluate


def parse_args(text: str | None) -> dict[str, str | float]:
    """``NoV=mu,roughness=r,SpecularColor=1`` -> {name: argument or number}."""
    out: dict[str, str | float] = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        name, sep, value = item.partition("=")
        value = value.strip()
        if not sep:
            raise ArgumentError(f"expected NAME=VALUE, got {item!r}", where="args")
        if value in ARGUMENTS:
            out[name.strip()] = value
        else:
            try:
                number = float(value)
            except ValueError:
                raise ArgumentError(f"{name}: {value!r} is none of {', '.join(ARGUMENTS)} nor a number",
                                    where="args") from None
            if not math.isfinite(number):
                raise ArgumentError(f"{name}: not finite", where="args")
            out[name.strip()] = number
    return out


def domain(uses: set[str], size: int) -> dict[str, np.ndarray]:
    """Node grid over μ and the roughness axis (the arguments a formula uses)."""
    t = np.linspace(0.0, 1.0, size)
    if "mu" in uses or "theta" in uses:
        mu, rough = np.meshgrid(t, t, indexing="ij")
    else:
        mu, rough = None, t
    env = {"r": rough, "alpha": rough * rough if "r" in uses else rough}
    if "alpha" in uses and "r" not in uses:
        env["alpha"] = rough
        env["r"] = np.sqrt(rough)
    if mu is not None:
        env["mu"] = np.maximum(mu, 1e-4)
        env["theta"] = np.arccos(env["mu"])
    return env


def audit_formula(evaluate, uses: set[str], quantities: list[str], reference: Reference,
                  shadowing: str = "height-correlated", size: int | None = None,
                  arrays: dict | None = None) -> list[dict]:
    """Max/RMS error of each component against its quantity, with the argmax (μ, α); ``arrays`` (if given)
    receives quantity -> (signed error, μ grid or None, α grid) for the figures."""
    for q in quantities:
        if q not in QUANTITIES:
            raise ArgumentError(f"unknown quantity {q!r} (known: {', '.join(QUANTITIES)})", where="quantities")
    if size is None:  # nodes per axis: dense where the reference is cheap (E: ~25 µs a cell, F90: ~3 ms)
        size = 33 if any(Reference.expensive(q) for q in quantities) else (129 if uses & {"mu", "theta"} else 257)
    env = domain(uses, size)
    alpha = np.maximum(env["alpha"], 1e-8)
    with np.errstate(all="ignore"):
        values = evaluate({k: v for k, v in env.items()})
    if not isinstance(values, list):
        values = [np.broadcast_to(values, alpha.shape)]
    if len(values) < len(quantities):
        raise ArgumentError(f"the formula gives {len(values)} components; {len(quantities)} quantities asked",
                            where="quantities")
    for value in values[:len(quantities)]:
        bad = ~np.isfinite(np.broadcast_to(value, alpha.shape))
        if bad.any():
            k = np.unravel_index(int(np.argmax(bad)), bad.shape)
            at = ", ".join(f"{name} = {float(np.broadcast_to(env[name], alpha.shape)[k]):.4g}"
                           for name in ("mu", "alpha") if name in env)
            shown = float(np.broadcast_to(value, alpha.shape)[k])
            raise ArgumentError(f"the formula is not finite at {int(bad.sum())} of {bad.size} points ({shown} at "
                                f"{at}): an overflow, a division by zero or a function outside its domain",
                                where="formula")
    out = []
    for q, value in zip(quantities, values, strict=False):
        exact, error = reference.meaning(q, shadowing, env.get("mu"), alpha)
        diff = np.broadcast_to(value, exact.shape) - exact
        if arrays is not None:
            arrays[q] = (diff, env.get("mu"), alpha)
        magnitude = np.where(np.isfinite(diff), np.abs(diff), np.inf)
        k = np.unravel_index(int(np.argmax(magnitude)), diff.shape)
        at = {"alpha": float(alpha[k])}
        if "mu" in env:
            at["mu"] = float(env["mu"][k])
        out.append({"quantity": q, "max": float(magnitude[k]), "at": at,
                    "rms": float(np.sqrt(np.mean(np.where(np.isfinite(diff), diff, 0.0) ** 2))),
                    "points": int(diff.size), "reference_error": float(np.max(error))})
    return out
