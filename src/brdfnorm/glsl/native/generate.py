"""From a ``.brdf`` shader to the Python source of one scalar function ``brdf(lx, ly, lz, vx, vy, vz, u)``.

The shader is compiled by the numpy backend's own compiler (:mod:`..compiler`: the same typed syntax tree,
overloads, conversions, Mesa's folds and built-ins), then its ``BRDF`` runs once on :class:`.tracer.Tracer`
components: L and V as the arguments, N, X, Y as the constants +z, +x, +y, each parameter as ``u[k]``. Every
operation becomes one line; control flow whose condition depends on the directions or the parameters is
predicated (both branches, then a select: the numpy backend's own lane masks on one lane). Loops are the
exception: :class:`NativeCompiler` runs them as real ``while`` loops whose loop-carried state (every variable,
the lane mask, the return value, the bounds' counters) lives in generated variables, with the per-loop,
total-iteration and loop-node bounds of :mod:`..limits` checked as the numpy backend checks them. Where the
numpy backend raises its :class:`~brdfnorm.errors.EvaluationError`, the function returns NaN in every channel:
an exception raised inside a Numba ``prange`` loop is lost (measured with Numba 0.68: the loop finishes as if
nothing happened), a NaN is not. The caller reports it as today by evaluating that pair with the numpy backend,
which raises the error naming the loop's ``FILE:LINE:COL``.
"""

from __future__ import annotations

import io
import re
import tokenize
from dataclasses import dataclass

import numpy as np

from ..compiler import Compiler, Program, compile_shader
from ..compiler.statements import LoopParts
from ..compiler.values import zeros
from ..limits import MAX_LOOP_ITERATIONS, MAX_LOOP_NODES, MAX_TOTAL_ITERATIONS
from ..runtime import LoopState, mask_and, mask_and_not, mask_or
from .integers import SOURCE as INTEGER_SOURCE
from .tracer import UFUNCS, Recorder, Tracer, Unsupported, current, literal, operand, recording

_ARGUMENTS = ("lx", "ly", "lz", "vx", "vy", "vz")
_FRAME = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))  # N, X, Y as BrdfModel.evaluate passes them


#: Integer operators the numpy backend computes on int64 bit patterns -> the :mod:`.integers` function the
#: generated code calls instead (a tracer cannot follow ``np.asarray(..., int64)``).
INTEGER_FUNCTIONS = {"%": "int_mod", "&": "int_and", "|": "int_or", "^": "int_xor", "<<": "int_shl", ">>": "int_shr"}


def _plain_arrays_refused(components: tuple) -> tuple:
    """A plain array where a component should be: what the numpy backend's int64 route makes of a tracer (its
    empty data). Refused rather than traced into a wrong value."""
    for c in components:
        if not isinstance(c, Tracer) and getattr(c, "ndim", 0):
            raise Unsupported("an integer bit operation on a value known only at run time")
    return components


class NativeCompiler(Compiler):
    """The numpy backend's compiler, with loops run as generated ``while`` loops when traced, and the integer bit
    operators of run-time values as calls of :mod:`.integers`."""

    def integer_function(self, op: str):
        original = super().integer_function(op)
        if op not in INTEGER_FUNCTIONS:
            return original
        name = INTEGER_FUNCTIONS[op]

        def fn(a, b):
            if isinstance(a, Tracer) or isinstance(b, Tracer):
                return current().value(f"{name}({operand(a, 'f')}, {operand(b, 'f')})", "f")
            return _plain_arrays_refused((original(a, b),))[0]

        return fn

    def loop_runner(self, parts: LoopParts):
        ret_zeros = zeros(self.function.ret) if self.function.ret.size else ()
        return lambda f: _traced_loop(f, parts, ret_zeros)


class _Carried:
    """The state a loop iteration reads and writes: every variable's components, the return value and the
    bounds' counters, each held in a generated loop variable ``pN``."""

    def __init__(self, f, ret_zeros: tuple) -> None:
        self.f = f
        if f.ret is None and ret_zeros:
            f.ret = ret_zeros  # zeros where no lane returned yet: the same values in every lane that returns
        self.slots = [i for i, v in enumerate(f.slots) if v is not None]
        self.globals = [i for i, v in enumerate(f.globals) if v is not None]
        self.names: list[tuple[str, str]] = []  # (generated name, kind) in the order of values()

    def values(self) -> list:
        f = self.f
        out = [c for i in self.slots for c in f.slots[i]] + [c for i in self.globals for c in f.globals[i]]
        out += list(f.ret or ()) + list(f.budget)
        return out

    def install(self, values: list) -> None:
        f, k = self.f, 0
        for i in self.slots:
            n = len(f.slots[i])
            f.slots[i], k = tuple(values[k : k + n]), k + n
        for i in self.globals:
            n = len(f.globals[i])
            f.globals[i], k = tuple(values[k : k + n]), k + n
        if f.ret is not None:
            n = len(f.ret)
            f.ret, k = tuple(values[k : k + n]), k + n
        f.budget[:] = values[k:]

    def declare(self, rec: Recorder) -> list[Tracer]:
        """``pN = value`` for every component before the loop; the tracers for them, installed into the frame."""
        phis = []
        for value in self.values():
            kind = value.kind if isinstance(value, Tracer) else ("b" if _is_bool(value) else "f")
            name = rec.name("p")
            rec.emit(f"{name} = {operand(value, kind)}")
            self.names.append((name, kind))
            phis.append(Tracer.of(name, kind))
        self.install(phis)
        return phis

    def fresh(self) -> list[Tracer]:
        """New tracers for the loop variables (after the loop, whatever the body did to the old objects)."""
        return [Tracer.of(name, kind) for name, kind in self.names]


def _is_bool(value) -> bool:
    return isinstance(value, bool | np.bool_)


def assign(rec: Recorder, targets: list[tuple[str, str]], values: list) -> int:
    """``name = value`` for every pair, as one parallel assignment (a value may be another target's name); the
    number of names that change."""
    pairs = [(name, operand(v, kind)) for (name, kind), v in zip(targets, values, strict=True)]
    pairs = [(name, source) for name, source in pairs if name != source]
    changed = {name for name, _ in pairs}
    staged = []
    for name, source in pairs:
        if source in changed:
            temp = rec.name()
            rec.emit(f"{temp} = {source}")
            source = temp
        staged.append((name, source))
    for name, source in staged:
        rec.emit(f"{name} = {source}")
    return len(staged)


def _check(rec: Recorder, value, bound: int) -> None:
    """Stop with NaN where the numpy backend raises: ``value`` past ``bound``."""
    rec.emit(f"if {operand(value, 'f')} > {literal(bound)}:")
    rec.emit("    return (NAN, NAN, NAN)")


def _traced_loop(f, parts: LoopParts, ret_zeros: tuple) -> None:
    """One loop as a generated ``while True:``, with the numpy backend's per-iteration semantics (one lane)."""
    rec = current()
    if parts.init is not None:
        parts.init(f)
    state = LoopState()
    f.loops.append(state)
    try:
        carried = _Carried(f, ret_zeros)
        carried.declare(rec)
        control = [("", "b"), ("", "b"), ("", "b"), ("", "f")]  # mask, exited, broken, iteration count
        control = [(rec.name("p"), kind) for _, kind in control]
        assign(rec, control, [True if f.mask is None else f.mask, False, False, 0.0])
        mask, exited, broken, count = (Tracer.of(name, kind) for name, kind in control)
        rec.emit("while True:")
        rec.depth += 1
        f.mask = mask

        def test(exited):
            c = parts.cond(f)
            exited = mask_or(exited, mask_and_not(f.mask, c))
            f.mask = mask_and(f.mask, c)
            return exited

        if parts.test_first:
            if parts.cond is not None:
                exited = test(exited)
                assign(rec, control[1:2], [exited])
            rec.emit(f"if not {operand(f.mask, 'b')}:")
            rec.emit("    break")
        count = rec.value(f"{count.sym} + 1.0", "f")
        _check(rec, count, MAX_LOOP_ITERATIONS)
        f.budget[0] = f.budget[0] + 1.0
        _check(rec, f.budget[0], MAX_TOTAL_ITERATIONS)
        f.budget[1] = f.budget[1] + float(parts.cost())
        _check(rec, f.budget[1], MAX_LOOP_NODES)
        state.broken = broken
        parts.body(f)
        f.mask = mask_or(f.mask, state.continued)
        state.continued = False
        if parts.update is not None:
            parts.update(f)  # under the lanes still running: a lane that left keeps its values
        if not parts.test_first and parts.cond is not None:
            exited = test(exited)
        rec.carry(assign(rec, carried.names + control, carried.values() + [f.mask, exited, state.broken, count]))
        if not parts.test_first:
            rec.emit(f"if not {control[0][0]}:")
            rec.emit("    break")
        rec.depth -= 1
        before_slots, before_globals = set(carried.slots), set(carried.globals)
        for i in range(len(f.slots)):  # variables declared in the body are out of scope after the loop
            if i not in before_slots:
                f.slots[i] = None
        for i in range(len(f.globals)):
            if i not in before_globals:
                f.globals[i] = None
        carried.install(carried.fresh())
        _, exited, broken, _ = (Tracer.of(name, kind) for name, kind in control)
        f.mask = mask_or(exited, broken)
    finally:
        f.loops.pop()


@dataclass(frozen=True)
class Generated:
    """A shader's generated source, the parameters' places in ``u`` (name, GLSL type, offset) and the number of
    values in ``u``."""

    source: str
    layout: tuple[tuple[str, str, int], ...]
    size: int


HEADER = (
    '''"""Generated by brdfnorm.glsl.native from a .brdf shader's syntax tree: do not edit (regenerated)."""
import numpy as np
from numba import njit

NAN = np.nan
INF = np.inf
'''
    + INTEGER_SOURCE
    + '''

@njit(cache=True, error_model="numpy", nogil=True)
def brdf(lx, ly, lz, vx, vy, vz, u):
'''
)


def generate(text: str, *, path: str, first_line: int, first_column: int, uniforms: dict[str, str]) -> Generated:
    """Trace a shader's ``BRDF`` into the source of one scalar function; :class:`Unsupported` where it cannot.

    Compile errors are the numpy backend's :class:`~brdfnorm.errors.BrdfFileError` (the model compiled the same
    text already). The loader compiles it without the disk cache where there is no safe cache directory.
    """
    program = compile_shader(
        text, path=path, first_line=first_line, first_column=first_column, uniforms=uniforms,
        compiler_class=NativeCompiler,
    )
    rec = Recorder()
    layout: list[tuple[str, str, int]] = []
    try:
        with recording(rec):
            ret, size = _trace(program, rec, layout)
    except RecursionError:
        raise Unsupported("nested too deeply to trace") from None
    except (TypeError, ValueError, IndexError, AttributeError) as error:  # a path of the numpy code a tracer
        raise Unsupported(f"{type(error).__name__} while tracing") from None  # cannot take: numpy evaluates
    result = ", ".join(operand(c, "f") for c in ret)
    body = f"{chr(10).join(rec.lines)}\n    return ({result})\n"
    _check_body(body)
    return Generated(HEADER + body, tuple(layout), size)


#: The only words the generated body may hold besides generated names (``tN``, ``pN``).
_WORDS = frozenset(
    ["lx", "ly", "lz", "vx", "vy", "vz", "u", "np", "NAN", "INF", "float", "abs", "if", "else", "not", "and",
     "or", "while", "True", "False", "break", "return", *INTEGER_FUNCTIONS.values()]
    + [m.group(1) for _, _, template in UFUNCS.values() for m in re.finditer(r"np\.(\w+)", template)]
)
_GENERATED = re.compile(r"[tp][0-9]+\Z")


def _check_body(body: str) -> None:
    """Refuse a body holding anything but generated names, the words above, numbers and operators: what the
    tracer writes, checked again on the text itself before it is ever compiled (defence in depth)."""
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(body).readline))
    except (tokenize.TokenError, SyntaxError):
        raise Unsupported("generated source that does not tokenize") from None
    for token in tokens:
        if token.type == tokenize.NAME:
            if token.string not in _WORDS and not _GENERATED.match(token.string):
                raise Unsupported(f"generated source holding the word {token.string!r}")
        elif token.type not in _SAFE_TOKENS:
            raise Unsupported(f"generated source holding a {tokenize.tok_name[token.type]} token")


_SAFE_TOKENS = frozenset({tokenize.NUMBER, tokenize.OP, tokenize.NEWLINE, tokenize.NL, tokenize.INDENT,
                          tokenize.DEDENT, tokenize.ENDMARKER})


def _trace(program: Program, rec: Recorder, layout: list) -> tuple[tuple, int]:
    """Run the program's entry point on tracers: the result's three components, and the size of ``u``."""
    from ..runtime import Frame

    globals_ = list(program._global_defaults)
    offset = 0
    for name, (t, slot, caller, default) in program._uniforms.items():
        if not caller:
            globals_[slot] = default  # its initializer, else zero as OpenGL does
            continue
        if t.base not in ("float", "bool") or t.is_matrix or t.is_array:
            raise Unsupported(f"a uniform of type {t}")
        comps = []
        for i in range(t.size):
            c = rec.value(f"u[{offset + i}]", "f")
            comps.append(rec.value(f"({c.sym} != 0.0)", "b") if t.base == "bool" else c)
        globals_[slot] = tuple(comps)
        layout.append((name, str(t), offset))
        offset += t.size
    budget = [0.0, 0.0]
    entry = program._entry
    frame = Frame(entry.nslots, globals_, None, budget)
    directions = [
        tuple(Tracer.of(name, "f") for name in _ARGUMENTS[:3]),
        tuple(Tracer.of(name, "f") for name in _ARGUMENTS[3:]),
        *_FRAME,
    ]
    for k in program._used_params:
        frame.slots[entry.param_slots[k]] = directions[k]
    init_frame = Frame(0, globals_, None, budget)
    for init in program._inits:
        init(init_frame)
    entry.body(frame)
    return (frame.ret if frame.ret is not None else (0.0, 0.0, 0.0)), offset


__all__ = ["Generated", "NativeCompiler", "Unsupported", "generate"]
