"""Parsing GLSL with tree-sitter-glsl, and mapping syntax-tree positions to the ``.brdf`` file.

tree-sitter-glsl extends tree-sitter-c's grammar; two GLSL tokens it lacks are handled by
length-preserving rewrites of the text before parsing, so every position stays that of the file:

* ``^^`` (logical exclusive or, GLSL 4.10 §5.1) is parsed as ``||``; the positions of the rewritten
  operators are remembered and the compiler re-associates the ``||`` chains with GLSL precedence
  (``&&`` > ``^^`` > ``||``).
* precision qualifiers (``highp``, ``mediump``, ``lowp`` and ``precision ...;`` statements) have no
  effect in desktop GLSL (§4.7), nor ``#pragma`` lines here: they are blanked out.
* the parameter qualifiers ``const in`` are swapped to ``in const``, the order the grammar knows.
* the constructors ``int(``, ``bool(`` and ``float(`` become identifiers of the same length (``__i(``,
  ``__bo(``, ``__flo(``): as C primitive types the grammar reads ``(float(x) + 1.0)`` as a cast and fails.
  :meth:`Source.text_of` gives the original name back at those places.

Syntax errors are the first ``ERROR`` or ``MISSING`` node of the tree. Before the tree, a linear pre-scan refuses
mismatched or too deeply nested brackets (outside comments and preprocessor lines), where tree-sitter's error
recovery is slowest and can overflow its stack (issue 35). Parsing is bounded
(:mod:`.limits`): the text's size, and the parser's work through tree-sitter's progress callback, which
cancels the parse — error recovery on junk can otherwise take far more time and memory than its size.
"""

from __future__ import annotations

import re
import threading
import time
import warnings
from dataclasses import dataclass, field

import tree_sitter
import tree_sitter_glsl

from ..errors import BrdfFileError
from .limits import (
    MAX_BRACKET_DEPTH,
    MAX_SHADER_BYTES,
    PARSE_BYTES_PER_REPORT,
    PARSE_REPORTS,
    PARSE_SECONDS,
    PARSE_STACK_BYTES,
)

with warnings.catch_warnings():
    # tree-sitter 0.2x warns about the int handle that tree-sitter-glsl's binding returns.
    warnings.simplefilter("ignore", DeprecationWarning)
    LANGUAGE = tree_sitter.Language(tree_sitter_glsl.language())

#: Node types of preprocessor lines (``#define``, ``#if``, ...), from the grammar itself.
PREPROCESSOR_NODES = frozenset(
    LANGUAGE.node_kind_for_id(i)
    for i in range(LANGUAGE.node_kind_count)
    if LANGUAGE.node_kind_for_id(i).startswith("preproc")
)

_PRECISION = re.compile(
    rb"\bprecision\s+(?:lowp|mediump|highp)\s+\w+\s*;|\b(?:lowp|mediump|highp)\b"
    rb"|^[ \t]*#[ \t]*pragma\b[^\n]*",  # pragmas (no effect here) confuse the grammar
    re.MULTILINE,
)


# The grammar accepts `in const float a` but not the equally valid `const in float a`: swap the two words.
_CONST_IN = re.compile(rb"\bconst(\s+)in\b")
# Constructors named by a C primitive type, and the same-length identifiers they are parsed as.
_PRIMITIVE_CONSTRUCTOR = re.compile(rb"\b(int|bool|float)(?=[ \t\r\n]*\()")
_CONSTRUCTOR_ALIASES = {b"int": b"__i", b"bool": b"__bo", b"float": b"__flo"}


_STACK_LOCK = threading.Lock()  # threading.stack_size is process-wide: set and restored around one start


def _blank(match: re.Match) -> bytes:
    return re.sub(rb"[^\n]", b" ", match.group(0))


@dataclass
class Source:
    """A piece of GLSL text placed in a file: ``path``, and the file line/column of its first character."""

    text: bytes
    path: str
    first_line: int
    first_column: int
    xor_offsets: frozenset[int]
    original: bytes = b""  # the text before the length-preserving rewrites
    constructors: dict[int, str] = field(default_factory=dict)  # offset -> constructor name rewritten there

    def position(self, node: tree_sitter.Node) -> tuple[int, int]:
        """File (line, column), both 1-based, of a node's first character."""
        row, byte_column = node.start_point
        start = node.start_byte - byte_column
        column = len(self.text[start : start + byte_column].decode("utf-8", errors="replace"))
        if row == 0:
            return self.first_line, self.first_column + column
        return self.first_line + row, column + 1

    def error(self, message: str, node: tree_sitter.Node | None) -> BrdfFileError:
        """A :class:`BrdfFileError` located at ``node`` (at the start of the text when None)."""
        line, column = self.position(node) if node is not None else (self.first_line, self.first_column)
        return BrdfFileError(message, self.path, line, column)

    def place(self, offset: int) -> tuple[int, int]:
        """File (line, column) of the byte at ``offset`` of the text."""
        row = self.text.count(b"\n", 0, offset)
        start = self.text.rfind(b"\n", 0, offset) + 1
        column = len(self.text[start:offset].decode("utf-8", errors="replace"))
        return (self.first_line, self.first_column + column) if row == 0 else (self.first_line + row, column + 1)

    def error_at(self, message: str, offset: int) -> BrdfFileError:
        """A :class:`BrdfFileError` located at byte ``offset`` of the text."""
        return BrdfFileError(message, self.path, *self.place(offset))

    def text_of(self, node: tree_sitter.Node) -> str:
        """The text of ``node`` as parsed (a rewritten constructor name is given back as written)."""
        name = self.constructors.get(node.start_byte)
        if name is not None and node.end_byte - node.start_byte == len(name):
            return name
        return self.text[node.start_byte : node.end_byte].decode("utf-8", errors="replace")

    def original_text_of(self, node: tree_sitter.Node) -> str:
        """The text of ``node`` as written in the file, before any rewrite (macro bodies are parsed anew)."""
        return self.original[node.start_byte : node.end_byte].decode("utf-8", errors="replace")


def _first_error(root: tree_sitter.Node) -> tree_sitter.Node | None:
    """The first ERROR or MISSING node in document order (iterative: trees may be deep)."""
    stack = [root]
    while stack:
        node = stack.pop()
        if not node.has_error:
            continue
        if node.is_missing or (node.is_error and not any(c.has_error for c in node.children)):
            return node
        if node.is_error:
            # An ERROR node containing errors: report the innermost first one, or the node itself.
            inner = [c for c in node.children if c.has_error]
            stack.extend(reversed(inner))
            continue
        stack.extend(reversed(node.children))
    return None


# What the bracket pre-scan looks at: comments, preprocessor lines (a macro's body need not balance) and brackets.
_SCAN = re.compile(rb"//|/\*|^[ \t]*#|[()\[\]{}]", re.MULTILINE)
_CLOSES = {ord(b")"): ord(b"("), ord(b"]"): ord(b"["), ord(b"}"): ord(b"{")}


def _check_brackets(src: Source) -> None:
    """A linear pre-scan of the text before tree-sitter: brackets outside comments and preprocessor lines must
    match and nest at most :data:`MAX_BRACKET_DEPTH` deep, else a syntax error at the first bracket at fault.

    Valid GLSL always passes; junk is refused here in time proportional to its size, before the parser's error
    recovery (unbounded in time and memory on such input, and able to crash on deep mismatches) starts."""
    text, opened, position = src.text, [], 0
    while (match := _SCAN.search(text, position)) is not None:
        token, position = match.group(), match.end()
        if token == b"//":
            end = text.find(b"\n", position)
            position = len(text) if end < 0 else end
        elif token == b"/*":
            end = text.find(b"*/", position)
            if end < 0:
                raise src.error_at("syntax error: unterminated comment '/*'", match.start())
            position = end + 2
        elif token.endswith(b"#"):
            while True:  # the directive's line and its continuations (a backslash before the newline)
                end = text.find(b"\n", position)
                if end < 0 or text[end - 1:end] != b"\\":
                    position = len(text) if end < 0 else end
                    break
                position = end + 1
        elif token[0] in _CLOSES:
            if not opened or text[opened[-1]] != _CLOSES[token[0]]:
                if not opened:
                    raise src.error_at(f"syntax error: '{token.decode()}' closes nothing", match.start())
                line, column = src.place(opened[-1])
                raise src.error_at(f"syntax error: '{token.decode()}' does not close the "
                                   f"'{chr(text[opened[-1]])}' opened at {line}:{column}", match.start())
            opened.pop()
        else:
            opened.append(match.start())
            if len(opened) > MAX_BRACKET_DEPTH:
                raise src.error_at(f"brackets nested too deeply (more than {MAX_BRACKET_DEPTH} levels)", match.start())
    if opened:
        raise src.error_at(f"syntax error: '{chr(text[opened[-1]])}' is never closed", opened[-1])


def _parse_bounded(text: bytes) -> tree_sitter.Tree | None:
    """tree-sitter's parse of ``text``, or None when cancelled after the work :mod:`.limits` allows — the
    operations counted by the progress callback, and :data:`PARSE_SECONDS` of CPU time as a last resort (older
    py-tree-sitter returns None itself, newer raises ValueError).

    The parse runs in a thread with a :data:`PARSE_STACK_BYTES` stack: tree-sitter's error recovery recurses in C
    as deep as the junk is long (100 000 lines of ``{ ; ( ) }`` overflow the main thread's 8 MiB stack and kill
    the process with SIGSEGV). The progress callback is only called when the text is read through a callback.
    """
    allowed = PARSE_REPORTS + len(text) // PARSE_BYTES_PER_REPORT
    reports, cancelled, outcome = 0, threading.Event(), {}
    deadline = None  # of the parse thread's CPU time: the same work on a loaded machine is not cut shorter

    def read(offset: int, _point) -> bytes:
        return text[offset : offset + 65536]

    def progress(_offset: int, _has_error: bool) -> bool:
        nonlocal reports
        reports += 1
        if reports > allowed or cancelled.is_set() or (reports % 64 == 0 and time.thread_time() > deadline):
            cancelled.set()
            return True  # True cancels the parse
        return False

    def work() -> None:
        nonlocal deadline
        deadline = time.thread_time() + PARSE_SECONDS
        try:
            outcome["tree"] = tree_sitter.Parser(LANGUAGE).parse(read, progress_callback=progress)
        except BaseException as error:  # noqa: BLE001 — handed to the calling thread
            outcome["error"] = error

    with _STACK_LOCK:
        previous = threading.stack_size(PARSE_STACK_BYTES)
        try:
            worker = threading.Thread(target=work, name="glsl-parse", daemon=True)
            worker.start()
        except RuntimeError:  # no room for the stack (a tight address-space limit): parse here, bounded the same
            worker = None
        finally:
            threading.stack_size(previous)
    if worker is None:
        work()
        worker = threading.Thread(target=lambda: None)  # already finished: the loop below does not wait
    try:
        while worker.is_alive():
            worker.join(0.05)  # a join with a timeout keeps Ctrl-C working while the parse runs
    except BaseException:
        cancelled.set()  # the parse stops at its next progress report
        raise
    if "error" in outcome:
        if isinstance(outcome["error"], ValueError) and cancelled.is_set():
            return None  # py-tree-sitter 0.25+ raises "Parsing failed" when the callback cancels
        raise outcome["error"]
    tree = outcome.get("tree")
    return None if cancelled.is_set() else tree


def parse(source: str, path: str, first_line: int = 1, first_column: int = 1) -> tuple[tree_sitter.Tree, Source]:
    """Parse shader text; raise :class:`BrdfFileError` at the first syntax error."""
    raw = source.encode("utf-8", errors="replace")  # a lone surrogate becomes '?': a syntax error, located
    xor_offsets = frozenset(m.start() for m in re.finditer(rb"\^\^", raw))
    text = _PRECISION.sub(_blank, raw.replace(b"^^", b"||"))
    text = _CONST_IN.sub(lambda m: b"in" + m.group(1) + b"const", text)
    constructors = {m.start(): m.group(1).decode() for m in _PRIMITIVE_CONSTRUCTOR.finditer(text)}
    text = _PRIMITIVE_CONSTRUCTOR.sub(lambda m: _CONSTRUCTOR_ALIASES[m.group(1)], text)
    src = Source(text, path, first_line, first_column, xor_offsets, raw, constructors)
    if len(text) > MAX_SHADER_BYTES:
        raise src.error(f"shader too large: {len(text)} bytes (at most {MAX_SHADER_BYTES})", None)
    _check_brackets(src)
    tree = _parse_bounded(text)
    if tree is None:
        raise src.error("shader too complex to parse: the parser's work limit was reached (is this GLSL?)", None)
    bad = _first_error(tree.root_node)
    if bad is not None:
        if bad.is_missing:
            raise src.error(f"syntax error: missing '{bad.type}'", bad)
        leaves = [bad]
        while leaves[0].child_count:
            leaves = list(leaves[0].children)
        near = src.text_of(leaves[0]).strip()[:30]
        raise src.error(f"syntax error near '{near}'" if near else "syntax error", leaves[0])
    return tree, src


def parse_expression(text: str, source: Source, node: tree_sitter.Node) -> tuple[tree_sitter.Node, Source]:
    """Parse the body of an object-like ``#define`` as an expression located at ``node`` in the file."""
    line, column = source.position(node)
    prefix = "void f(){("
    # The prefix shifts the first line's columns; the macro body never spans lines (no continuation). The
    # suffix starts a new line, so that a '//' comment ending the macro's line stays a comment.
    tree, src = parse(prefix + text + "\n);}", source.path, line, column - len(prefix))
    function = tree.root_node.children[0]
    body = function.child_by_field_name("body")
    statement = body.named_children[0]
    return statement.named_children[0].named_children[0], src
