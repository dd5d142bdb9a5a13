"""The package's shape (issue 11): no import cycles in src/ (lazy imports inside functions included), no module
over ~600 lines, and no module shadowed by a function of the same name exported by its package."""

from __future__ import annotations

import ast
import importlib
import pkgutil
from pathlib import Path

import pytest

import brdfnorm

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "brdfnorm"
MAX_LINES = 600


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(path): path for path in PACKAGE.rglob("*.py")}


def _from_module(name: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute module a ``from … import`` in module ``name`` reads from (relative levels resolved)."""
    if not node.level:
        return node.module or ""
    base = name.split(".") if is_package else name.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _imports(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """The package modules ``name`` imports, anywhere in its body; ``from P import N`` counts as P.N where
    P.N is a module (a submodule), else as P."""
    is_package = path.name == "__init__.py"
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            prefix = _from_module(name, is_package, node)
            targets = [f"{prefix}.{alias.name}" if f"{prefix}.{alias.name}" in known else prefix
                       for alias in node.names]
        else:
            continue
        found.update(t for t in targets if t in known and t != name)
    return found


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(graph[node]):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                on_stack.discard(top)
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                components.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return components


def _graph() -> dict[str, set[str]]:
    known = _modules()
    return {name: _imports(name, path, known) for name, path in known.items()}


def test_the_import_graph_of_src_has_no_cycles():
    graph = _graph()
    assert graph["brdfnorm.cli.common"] >= {"brdfnorm.output.formats"}  # the parser sees real imports
    assert _cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_module_is_longer_than_600_lines():
    long = {str(path.relative_to(SRC)): n for path in PACKAGE.rglob("*.py")
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert long == {}


@pytest.mark.parametrize("module", sorted(m.name for m in pkgutil.walk_packages(brdfnorm.__path__, "brdfnorm.")
                                          if m.name != "brdfnorm.__main__"))
def test_every_module_imports_as_a_module(module):
    """``import brdfnorm.X`` gives the module X, never a function that the package re-exports under its name."""
    imported = importlib.import_module(module)
    parent, _, leaf = module.rpartition(".")
    assert getattr(importlib.import_module(parent), leaf) is imported


MAX_TOP_LEVEL = 12


def _top_level_modules(package: Path) -> list[str]:
    """The modules directly in ``package`` (``__init__`` and ``__main__`` included); a subpackage counts as one."""
    files = [path.name for path in package.glob("*.py")]
    packages = [path.name + "/" for path in package.iterdir() if (path / "__init__.py").is_file()]
    return sorted(files) + sorted(packages)


def test_src_brdfnorm_has_at_most_12_top_level_modules_besides_its_packages():
    """Issue 40: an idea with several modules gets a package (``fit/``, ``claims/``), so the top level stays a
    short list of foundations; the files directly in ``src/brdfnorm`` are at most 12."""
    modules = [name for name in _top_level_modules(PACKAGE) if not name.endswith("/")]
    assert len(modules) <= MAX_TOP_LEVEL, modules
    assert {"fit/", "claims/", "models/"} <= set(_top_level_modules(PACKAGE))


def test_the_top_level_counter_counts_files_and_not_package_contents(tmp_path):
    (tmp_path / "a.py").write_text("")
    (tmp_path / "__init__.py").write_text("")
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text("")
    (tmp_path / "pkg" / "b.py").write_text("")
    (tmp_path / "data").mkdir()  # not a package
    assert _top_level_modules(tmp_path) == ["__init__.py", "a.py", "pkg/"]


def test_the_fit_package_keeps_the_public_names_of_the_former_module():
    """``from brdfnorm.fit import fit`` (README, docs/fitting.md) works, and the package's names are the driver's."""
    from brdfnorm import fit as package
    from brdfnorm.fit import codegen, exact, families, fitting

    assert package.fit is fitting.fit and package.FitResult is fitting.FitResult
    assert set(package.__all__) <= set(dir(package))
    assert families.Form is package.Form and exact.ExactForm.__mro__[1] is families.Form
    assert codegen.emit.__module__ == "brdfnorm.fit.codegen"


#: Private names still imported from another module (issue 40, item 5), in the areas being rewritten by other
#: work: each should become public or stay inside its module; this list may only shrink.
PRIVATE_CROSSINGS_LEFT = {
    ("brdfnorm.engine.routes.halfvector_global", "brdfnorm.engine.machinery.tensor_rule._FLOOR"),
    ("brdfnorm.engine.routes.halfvector_global", "brdfnorm.engine.machinery.tensor_rule._doublings"),
    ("brdfnorm.engine.routes.halfvector_global", "brdfnorm.engine.machinery.tensor_rule._normalized"),
    ("brdfnorm.engine.routes.halfvector_global", "brdfnorm.engine.machinery.tensor_rule._sums"),
}


def _private_crossings(name: str, path: Path, known: dict[str, Path]) -> set[tuple[str, str]]:
    """(module, other module's private name) for each ``from M import _x`` and each ``m._x`` where ``m`` is an
    imported module of the package (dunder names and ``as _alias`` of public names are not private crossings)."""
    is_package = path.name == "__init__.py"
    modules: dict[str, str] = {}
    found: set[tuple[str, str]] = set()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            prefix = _from_module(name, is_package, node)
            for alias in node.names:
                if f"{prefix}.{alias.name}" in known:
                    modules[alias.asname or alias.name] = f"{prefix}.{alias.name}"
                elif prefix in known and alias.name.startswith("_") and not alias.name.startswith("__"):
                    found.add((name, f"{prefix}.{alias.name}"))
        elif isinstance(node, ast.Import):
            modules.update({alias.asname or alias.name: alias.name for alias in node.names if alias.name in known})
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in modules
                and node.attr.startswith("_") and not node.attr.startswith("__")):
            found.add((name, f"{modules[node.value.id]}.{node.attr}"))
    return found


def test_no_new_private_name_crosses_a_module_boundary():
    known = _modules()
    crossings = set().union(*(_private_crossings(name, path, known) for name, path in known.items()))
    assert crossings - PRIVATE_CROSSINGS_LEFT == set()


def test_the_private_name_finder_sees_imports_and_attributes(tmp_path):
    path = tmp_path / "b.py"
    path.write_text("from .a import _x, y\nfrom . import a\nfrom .a import z as _z\na._w\na.__name__\n")
    known = {"p": tmp_path / "__init__.py", "p.a": tmp_path / "a.py", "p.b": path}
    assert _private_crossings("p.b", path, known) == {("p.b", "p.a._x"), ("p.b", "p.a._w")}


def _flag_wheres(path: Path) -> list[tuple[int, str]]:
    """(line, text) of each ``where=`` keyword or ``where`` parameter default that spells a command-line flag (a
    string or f-string starting with ``-``): the library names API arguments; only ``cli/`` maps them to flags."""
    def flag(node) -> str | None:
        if isinstance(node, ast.JoinedStr) and node.values:
            node = node.values[0]
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.lstrip().startswith("-"):
            return node.value
        return None

    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        pairs = []
        if isinstance(node, ast.Call):
            pairs = [(k.arg, k.value) for k in node.keywords]
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            positional = node.args.posonlyargs + node.args.args
            pairs = list(zip([a.arg for a in positional[len(positional) - len(node.args.defaults):]],
                             node.args.defaults, strict=True))
            pairs += [(a.arg, d) for a, d in zip(node.args.kwonlyargs, node.args.kw_defaults, strict=True) if d]
        found += [(value.lineno, text) for name, value in pairs if name == "where" and (text := flag(value))]
    return found


def test_library_errors_name_api_arguments_not_command_line_flags():
    cli = PACKAGE / "cli"
    bad = {f"{path.relative_to(SRC)}:{line}: where={text!r}" for path in PACKAGE.rglob("*.py")
           if cli not in path.parents for line, text in _flag_wheres(path)}
    assert bad == set()


def test_the_flag_finder_sees_keywords_f_strings_and_defaults(tmp_path):
    path = tmp_path / "m.py"
    path.write_text('E(1, where="--axis")\nE(where=f"--{x}")\nE(where="axes")\nE(where=name)\n'
                    'def f(a, where="-p"): pass\ndef g(*, where="--as"): pass\ndef h(where="table"): pass\n')
    assert sorted(_flag_wheres(path)) == [(1, "--axis"), (2, "--"), (5, "-p"), (6, "--as")]



def _literal_defaults(path: Path, names: dict[str, float]) -> list[tuple[int, str]]:
    """(line, parameter) of each parameter in ``names`` whose default is written as the literal value its named
    default constant holds (it should name the constant)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            positional = node.args.posonlyargs + node.args.args
            pairs = list(zip(positional[len(positional) - len(node.args.defaults):], node.args.defaults, strict=True))
            pairs += [(a, d) for a, d in zip(node.args.kwonlyargs, node.args.kw_defaults, strict=True) if d]
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value is not None:
            pairs = [(ast.arg(arg=node.target.id), node.value)]  # a dataclass field
        else:
            continue
        found += [(value.lineno, a.arg) for a, value in pairs if a.arg in names and isinstance(value, ast.Constant)
                  and value.value == names[a.arg]]
    return found


def test_the_default_tolerance_and_budget_have_one_home():
    from brdfnorm.validate import DEFAULT_MAX_EVALUATIONS, DEFAULT_RTOL

    names = {"rtol": DEFAULT_RTOL, "max_evaluations": DEFAULT_MAX_EVALUATIONS}
    bad = {f"{path.relative_to(SRC)}:{line}: {name}" for path in PACKAGE.rglob("*.py")
           for line, name in _literal_defaults(path, names)}
    assert bad == set()


def test_the_literal_default_finder_sees_parameters_and_fields(tmp_path):
    path = tmp_path / "m.py"
    path.write_text("def f(rtol=1e-10, *, max_evaluations=20_000_000): pass\nclass J:\n    rtol: float = 1e-10\n"
                    "def g(rtol=1e-8, max_evaluations=RTOL): pass\n")
    assert sorted(_literal_defaults(path, {"rtol": 1e-10, "max_evaluations": 20_000_000})) == [
        (1, "max_evaluations"), (1, "rtol"), (3, "rtol")]


def _word_lists(path: Path, words: set[str]) -> list[tuple[int, tuple[str, ...]]]:
    """(line, words) of each literal tuple, list or set — or dict's keys — of two or more strings, all in
    ``words``: a second home of a word list."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            elements = node.elts
        elif isinstance(node, ast.Dict):
            elements = node.keys
        else:
            continue
        texts = tuple(e.value for e in elements if isinstance(e, ast.Constant) and isinstance(e.value, str))
        if len(texts) >= 2 and len(texts) == len(elements) and set(texts) <= words:
            found.append((node.lineno, texts))
    return found


@pytest.mark.parametrize("home, name", [("models/fresnel.py", "KINDS"), ("models/microfacet.py", "SHADOWING")])
def test_each_word_list_has_one_home(home, name):
    """Issue 40, item 3: the Fresnel factors' names (and the codes the compiled kernels take) are spelled out in
    ``models/fresnel.py`` only, the Smith shadowing choices in ``models/microfacet.py`` only; every other module
    names their constants."""
    from brdfnorm.models import fresnel

    module = importlib.import_module("brdfnorm." + home.removesuffix(".py").replace("/", "."))
    bad = {f"{path.relative_to(SRC)}:{line}: {texts}" for path in PACKAGE.rglob("*.py") if path != PACKAGE / home
           for line, texts in _word_lists(path, set(getattr(module, name)))}
    assert bad == set()
    assert [fresnel.KERNEL_CODES[kind] for kind in fresnel.MICROFACET_KINDS] == [0, 1, 2, 3]


def test_the_word_list_finder_sees_tuples_lists_sets_and_dict_keys(tmp_path):
    path = tmp_path / "m.py"
    path.write_text('a = ("none", "schlick")\nb = ["schlick", x]\nc = {"none": 0, "conductor": 3}\n'
                    'd = {"dielectric", "exact"}\ne = ("schlick",)\nf = {"none", "dielectric"}\n')
    assert _word_lists(path, {"none", "schlick", "conductor", "dielectric"}) == [
        (1, ("none", "schlick")), (3, ("none", "conductor")), (6, ("none", "dielectric"))]


TESTS = Path(__file__).resolve().parent
#: Test folders that are not a package of src/brdfnorm: the pages of docs/, the cross-package hostile-input suite,
#: the shared reference mathematics.
TEST_FOLDERS_BESIDES_PACKAGES = {"docs", "hostile", "helpers"}


def test_the_tests_mirror_the_packages_and_share_by_fixture_or_helper():
    """Issue 40, item 6 (docs/architecture.md, "Where tests go"): each folder of tests/ is a package of
    src/brdfnorm (or docs/, hostile/, helpers/) with an ``__init__.py``; nothing imports from ``conftest`` (shared
    code is a fixture or a ``helpers`` function), and below tests/ no path is built from ``__file__`` but in
    ``helpers/paths.py``."""
    packages = {path.name for path in PACKAGE.iterdir() if (path / "__init__.py").is_file()}
    folders = {path.parent for path in TESTS.rglob("*.py") if path.parent != TESTS}
    assert {f.relative_to(TESTS).parts[0] for f in folders} <= packages | TEST_FOLDERS_BESIDES_PACKAGES
    assert [str(f) for f in folders if not (f / "__init__.py").is_file()] == []
    bad = []
    for path in TESTS.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[-1] == "conftest" or \
                    isinstance(node, ast.Import) and any(a.name.split(".")[-1] == "conftest" for a in node.names):
                bad.append(f"{path.relative_to(TESTS)}:{node.lineno}: imports conftest")
            if (isinstance(node, ast.Name) and node.id == "__file__" and path.parent != TESTS
                    and path != TESTS / "helpers" / "paths.py"):
                bad.append(f"{path.relative_to(TESTS)}:{node.lineno}: a path from __file__ (use helpers.paths)")
    assert bad == []
