"""Issue 39, the kernel cache: brdfnorm.engine.compiled.staleness drops Numba's cached kernels of the package where a
source compiled into them changed (Numba compares only each kernel's own file), and nothing else."""

from __future__ import annotations

import ast
import os
import threading
from pathlib import Path

import pytest

from brdfnorm.engine.compiled import backend, staleness


def _cache_files(directory: Path) -> dict[str, str]:
    """Numba-like entries of module ``a`` (the cached one) and of ``other``, a .pyc and a stranger's file."""
    files = {"a.kernel-12.py311.nbi": "index", "a.kernel-12.py311.1.nbc": "code", "a._helper-30.py311.2.nbc": "code",
             "a.cpython-311.pyc": "bytecode", "other.kernel-5.py311.nbi": "index", "notes.txt": "mine"}
    directory.mkdir(exist_ok=True)
    for name, text in files.items():
        (directory / name).write_text(text)
    return files


@pytest.fixture
def package(tmp_path):
    """A module ``a.py`` whose kernels are cached, importing ``b.py``; their cache in ``__pycache__`` beside them."""
    (tmp_path / "a.py").write_text("from b import helper\n")
    (tmp_path / "b.py").write_text("def helper(x):\n    return x\n")
    cache = tmp_path / "__pycache__"
    _cache_files(cache)

    def refresh():
        removed = staleness.refresh([tmp_path / "a.py", tmp_path / "b.py"], [tmp_path / "a.py"],
                                    locate=lambda source: source.parent / "__pycache__")
        return sorted(path.name for path in removed)

    return tmp_path, cache, refresh


A_ENTRIES = ["a._helper-30.py311.2.nbc", "a.kernel-12.py311.1.nbc", "a.kernel-12.py311.nbi"]
KEPT = ["a.cpython-311.pyc", "notes.txt", "other.kernel-5.py311.nbi"]


def test_an_edited_import_removes_the_cached_modules_entries_and_nothing_else(package):
    root, cache, refresh = package
    assert refresh() == A_ENTRIES  # no stamp yet: whatever is cached may be stale
    _cache_files(cache)
    assert refresh() == []  # the stamp matches: nothing removed
    (root / "b.py").write_text("def helper(x):\n    return 2 * x\n")  # what a's kernels inline
    assert refresh() == A_ENTRIES
    assert sorted(p.name for p in cache.iterdir() if not p.name.startswith("brdfnorm-")) == KEPT
    assert (cache / "notes.txt").read_text() == "mine"


def test_an_unchanged_source_with_a_new_time_removes_nothing(package):
    root, cache, refresh = package
    refresh()
    _cache_files(cache)
    later = (root / "b.py").stat().st_mtime_ns + 5_000_000_000
    os.utime(root / "b.py", ns=(later, later))  # a checkout that rewrote the file as it was
    assert refresh() == []
    assert refresh() == []  # and the stamp took the new time (the fast path)
    assert sorted(p.name for p in cache.iterdir() if p.name.startswith("a.")) == sorted(A_ENTRIES + KEPT[:1])


def test_two_refreshes_at_once_remove_each_entry_once(package):
    root, cache, refresh = package
    refresh()
    _cache_files(cache)
    (root / "b.py").write_text("def helper(x):\n    return 3 * x\n")
    results = []
    threads = [threading.Thread(target=lambda: results.append(refresh())) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert sorted(results) == [[], A_ENTRIES]  # one removes (under the lock), the other finds the new stamp


def test_the_stamp_lives_where_numba_caches_the_package_and_a_numba_cache_dir(monkeypatch, tmp_path):
    numba = pytest.importorskip("numba")
    from brdfnorm.engine.compiled import global_rule

    assert staleness.numba_cache_directory(Path(global_rule.__file__)) == Path(
        global_rule.fused_global._cache._cache_path)
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))  # what $NUMBA_CACHE_DIR sets
    from numba.core.caching import FunctionCache

    where = Path(FunctionCache(global_rule.fused_global.py_func)._cache_path)  # where Numba would cache it now
    assert staleness.numba_cache_directory(Path(global_rule.__file__)) == where
    assert where.parent == tmp_path


def test_the_compiled_backend_refreshes_once_when_it_loads(monkeypatch):
    pytest.importorskip("numba")
    calls = []
    monkeypatch.setattr(staleness, "refresh", lambda: calls.append(1) or [])
    backend.numba_available.cache_clear()
    try:
        assert backend.numba_available() and backend.numba_available()
    finally:
        backend.numba_available.cache_clear()
    assert calls == [1]


def _caches(tree: ast.AST) -> bool:
    return any(isinstance(node, ast.keyword) and node.arg == "cache" and isinstance(node.value, ast.Constant)
               and node.value.value is True for node in ast.walk(tree))


def _package_imports(path: Path, tree: ast.AST) -> set[str]:
    """The package's modules (paths relative to it) that the module at ``path`` imports from."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = path.parent
                for _ in range(node.level - 1):
                    base = base.parent
                target = base.joinpath(*(node.module or "").split("."))
            elif (node.module or "").startswith("brdfnorm."):
                target = staleness.PACKAGE.joinpath(*node.module.split(".")[1:])
            else:
                continue
            for candidate in (target.with_suffix(".py"), *(target / f"{a.name}.py" for a in node.names)):
                if candidate.is_file():
                    out.add(candidate.relative_to(staleness.PACKAGE).as_posix())
    return out


def test_the_stamp_covers_every_cached_module_and_what_each_imports():
    cached, imported = set(), set()
    for path in staleness.PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        if _caches(tree):
            cached.add(path.relative_to(staleness.PACKAGE).as_posix())
            imported |= _package_imports(path, tree)
    assert cached == set(staleness.CACHED)
    assert cached | imported == set(staleness.SOURCES)


KERNEL = """from numba import njit

from helper import twice


@njit(cache=True)
def kernel(x):
    return twice(x)
"""
RUN = """import sys
from pathlib import Path
sys.path.insert(0, {root!r})
from brdfnorm.engine.compiled import staleness
if {refresh}:
    staleness.refresh([Path({root!r}) / "kernel.py", Path({root!r}) / "helper.py"], [Path({root!r}) / "kernel.py"])
import kernel
print(kernel.kernel(1.0))
"""


@pytest.mark.slow  # three processes that import Numba and compile a small kernel: ~3 s of CPU
@pytest.mark.parametrize("refresh", [False, True])
def test_an_edited_inlined_helper_reaches_the_cached_kernel_only_after_a_refresh(tmp_path, refresh):
    numba = pytest.importorskip("numba")
    import subprocess
    import sys

    (tmp_path / "kernel.py").write_text(KERNEL)
    helper = "from numba import njit\n\n\n@njit(inline='always')\ndef twice(x):\n    return {} * x\n"
    (tmp_path / "helper.py").write_text(helper.format(2.0))
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path), "NUMBA_CACHE_DIR": ""}

    def run() -> str:
        code = RUN.format(root=str(tmp_path), refresh=refresh)
        return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                              env=environment).stdout.strip()

    assert run() == "2.0"  # compiled and cached
    assert list((tmp_path / "__pycache__").glob("kernel.kernel-*.nbi"))
    (tmp_path / "helper.py").write_text(helper.format(3.0))
    # Numba alone (refresh False) loads the cached kernel with the old helper inside: the bug this module fixes.
    assert run() == ("3.0" if refresh else "2.0"), numba.__version__


def test_the_anisotropic_route_refreshes_before_its_kernels_load():
    """routes/anisotropic.py loads its cached kernels without the compiled backend's loading: its import refreshes."""
    pytest.importorskip("numba")
    import subprocess
    import sys

    script = ("import brdfnorm.engine.compiled.staleness as s\ncalls = []\ns.refresh = lambda: calls.append(1) or []\n"
              "import brdfnorm.engine.routes.anisotropic\nprint(len(calls))")
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                          env=environment)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["1"]
