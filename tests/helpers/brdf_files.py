"""Small ``.brdf`` files for the reader's and the GLSL compiler's hostile-input tests: a file around a shader body,
where a text sits in it (the tests' own expected locations), and a guard that fails a test instead of hanging it."""

from __future__ import annotations

import contextlib
import signal
from pathlib import Path

import numpy as np

#: Two (L, V) pairs: normal incidence and a 37° pair mirrored about N.
DIRECTIONS = (np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]]), np.array([[0.0, 0.0, 1.0], [-0.6, 0.0, 0.8]]))


def brdf_text(body: str, params: str = "float n 1 100 10") -> str:
    return f"analytic\n::begin parameters\n{params}\n::end parameters\n::begin shader\n{body}\n::end shader\n"


def where(text: str, needle: str, occurrence: int = 1) -> tuple[int, int]:
    """1-based (line, column) of the ``occurrence``-th ``needle`` in ``text``."""
    index = -1
    for _ in range(occurrence):
        index = text.index(needle, index + 1)
    line_start = text.rfind("\n", 0, index) + 1
    return text.count("\n", 0, index) + 1, index - line_start + 1


def write(tmp_path: Path, content: str | bytes, name: str = "case.brdf") -> Path:
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")
    return path


@contextlib.contextmanager
def hang_guard(seconds: float):
    """Fail (instead of hanging the suite) if the body runs longer than ``seconds``; not a timing assertion."""

    def expire(signum, frame):
        raise TimeoutError(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
