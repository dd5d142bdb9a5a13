"""Every code example of README.md and docs/*.md runs, so none can go stale.

A fenced ```sh block contributes its lines that start with ``brdfnorm`` (continuation lines joined), run in bash
with ``brdfnorm`` bound to ``python -m brdfnorm`` (the checkout's sources first on PYTHONPATH) in a fresh
directory that holds a link to ``examples/``; each must exit 0. ``brdfnorm explore`` starts a server that runs
until stopped: it passes when it prints the address it listens on, and is then stopped. A ```python block runs
as a script in such a directory. The README's examples are in the quick tier, the guides' (docs/) in the slow
one; the marker line ``<!-- slow -->`` right before a block puts a README example in the slow tier too;
``<!-- skip -->`` is for examples that need what a test machine does not have (a Dask cluster on other hosts),
and such skips are counted below so that they cannot grow unnoticed.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
from helpers.paths import REPO

ROOT = REPO
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^(\s*)```(\w*)\s*$")
#: Examples that need hardware the tests do not have; each is listed here, so the count is deliberate.
SKIPPED = {"docs/clusters.md:22"}


@dataclass(frozen=True)
class Example:
    page: str
    line: int
    language: str
    code: str
    marker: str  # "", "slow" or "skip"

    @property
    def id(self) -> str:
        return f"{self.page}:{self.line}"


def examples() -> list[Example]:
    found = []
    for path in PAGES:
        lines = path.read_text(encoding="utf-8").splitlines()
        i = 0
        while i < len(lines):
            match = FENCE.match(lines[i])
            if not match or not match.group(2):
                i += 1
                continue
            indent, language = match.group(1), match.group(2)
            start = i
            body = []
            i += 1
            while i < len(lines) and lines[i].strip() != "```":
                body.append(lines[i][len(indent):] if lines[i].startswith(indent) else lines[i])
                i += 1
            i += 1
            before = next((line.strip() for line in reversed(lines[:start]) if line.strip()), "")
            marker = {"<!-- slow -->": "slow", "<!-- skip -->": "skip"}.get(before, "")
            # A shell block without a brdfnorm command (make, pip, dask) is not a brdfnorm example.
            if language == "python" or (language == "sh" and commands("\n".join(body))):
                found.append(Example(str(path.relative_to(ROOT)), start + 1, language, "\n".join(body), marker))
    return found


def commands(code: str) -> list[str]:
    """The ``brdfnorm`` command lines of a shell block, continuation lines joined."""
    joined = re.sub(r"\s*\\\n\s*", " ", code)
    return [line.strip() for line in joined.splitlines() if line.strip().startswith("brdfnorm ")]


def _environment() -> dict:
    source = str(ROOT / "src")
    path = os.environ.get("PYTHONPATH", "")
    return {**os.environ, "PYTHONPATH": source + (os.pathsep + path if path else ""), "BROWSER": "true",
            "COLUMNS": "120", "PYTHONWARNINGS": "ignore"}


def _workdir(tmp_path: Path) -> Path:
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    return tmp_path


def _explore(command: str, cwd: Path) -> None:
    """Start the explorer, wait for the address it prints, stop it."""
    argv = [sys.executable, "-m", "brdfnorm", *shlex.split(command.split("#")[0])[1:]]
    process = subprocess.Popen(argv, cwd=cwd, env=_environment(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True)
    seen: list[str] = []
    reader = threading.Thread(target=lambda: seen.extend(iter(process.stdout.readline, "")), daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            if "http://127.0.0.1:" in "".join(seen):
                return
            if process.poll() is not None:
                break
            time.sleep(0.2)
        pytest.fail(f"{command}: no address printed; output: {''.join(seen)[-2000:]}")
    finally:
        process.terminate()
        process.wait(timeout=30)


_SHELL = f'brdfnorm() {{ "{sys.executable}" -m brdfnorm "$@"; }}\nset -o pipefail\n'


def _run(example: Example, tmp_path: Path) -> None:
    cwd = _workdir(tmp_path)
    timeout = 900 if example.marker == "slow" else 180
    if example.language == "python":
        script = cwd / "example.py"
        script.write_text(example.code + "\n", encoding="utf-8")
        result = subprocess.run([sys.executable, str(script)], cwd=cwd, env=_environment(), capture_output=True,
                                text=True, timeout=timeout)
        assert result.returncode == 0, f"{example.id}\n{result.stderr[-3000:]}"
        return
    for command in commands(example.code):
        if command.startswith("brdfnorm explore"):
            _explore(command, cwd)
            continue
        result = subprocess.run(["bash", "-c", _SHELL + command], cwd=cwd, env=_environment(),
                                capture_output=True, text=True, timeout=timeout)
        assert result.returncode == 0, f"{example.id}: {command}\n{result.stderr[-3000:]}"


EXAMPLES = examples()


def _param(example: Example):
    # The README's examples run in the quick tier (the first thing a user tries); the guides' in the slow one.
    slow = example.marker == "slow" or example.page != "README.md"
    marks = [pytest.mark.slow] if slow else []
    return pytest.param(example, id=example.id, marks=marks)


@pytest.mark.parametrize("example", [_param(e) for e in EXAMPLES])
def test_example_runs(example: Example, tmp_path):
    if example.marker == "skip":
        pytest.skip(f"{example.id} needs machines the tests do not have (listed in SKIPPED)")
    _run(example, tmp_path)


def test_examples_are_found_and_skips_are_counted():
    """The collector sees the README's and the docs' examples, and skips only the ones listed."""
    assert sum(e.page == "README.md" for e in EXAMPLES) >= 4
    assert {e.page for e in EXAMPLES} >= {"README.md", "docs/tables.md", "docs/python.md", "docs/cli.md"}
    assert {e.id for e in EXAMPLES if e.marker == "skip"} == SKIPPED


def test_examples_write_distinct_files():
    """Two lut commands of one page never write the same file unless they compute the same table (the README
    once fitted the Blinn-Phong table because every example wrote E.npz)."""
    for page in {e.page for e in EXAMPLES}:
        outputs: dict[str, str] = {}
        for example in (e for e in EXAMPLES if e.page == page and e.language == "sh"):
            for command in commands(example.code):
                match = re.search(r"^brdfnorm lut (.*?)-o (\S+)", command)
                if match and match.group(2) != "-":
                    table = re.sub(r"\s+", " ", match.group(1)).strip()
                    assert outputs.setdefault(match.group(2), table) == table, (page, match.group(2))


def test_collector_reads_markers(tmp_path, monkeypatch):
    page = tmp_path / "page.md"
    page.write_text("text\n\n<!-- slow -->\n```sh\nbrdfnorm models\n```\n\n  ```python\n  x = 1\n  ```\n",
                    encoding="utf-8")
    monkeypatch.setattr(sys.modules[__name__], "PAGES", [page])
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    found = examples()
    assert [(e.line, e.language, e.code, e.marker) for e in found] == [(4, "sh", "brdfnorm models", "slow"),
                                                                        (8, "python", "x = 1", "")]
    assert commands("brdfnorm a \\\n   b\nls\n") == ["brdfnorm a b"]


@pytest.mark.slow
def test_docs_build_strictly(tmp_path):
    """`make docs`: the site builds with mkdocs --strict (a broken link, a missing page or a docstring that
    mkdocstrings cannot render fails)."""
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings")
    result = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                            cwd=ROOT, env={**_environment(), "NO_MKDOCS_2_WARNING": "1"}, capture_output=True,
                            text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    assert (tmp_path / "site" / "api" / "engine" / "index.html").is_file()
    assert "Directional albedo of" in (tmp_path / "site" / "api" / "engine" / "index.html").read_text()
