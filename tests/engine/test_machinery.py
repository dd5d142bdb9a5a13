"""One integration machinery (issue 39 item 1): the engine's result class, panel pool and 1-D adaptive integrator
each have one home, ``brdfnorm/engine/machinery/``, and every route uses them; and the RouteResult itself."""

from __future__ import annotations

import ast
import copy
import pickle
from pathlib import Path

import numpy as np
import pytest
from helpers.paths import SRC

from brdfnorm.engine.machinery.result import RouteResult

PACKAGE = SRC / "brdfnorm"
MACHINERY = PACKAGE / "engine" / "machinery"
#: The public result of ``brdfnorm.albedo`` (built from a RouteResult at the front door).
PUBLIC_RESULTS = {("engine/methods.py", "AlbedoResult")}


def _classes(root: Path, suffixes: tuple[str, ...]) -> set[tuple[str, str]]:
    """(path relative to ``root``'s parent package, class name) of every class whose name ends with a suffix."""
    found = set()
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef) and node.name.endswith(suffixes):
                found.add((path.relative_to(root.parent).as_posix(), node.name))
    return found


def _machinery_violations(engine: Path) -> set[tuple[str, str]]:
    """Result or panel classes defined in ``engine`` outside its machinery (the public result excepted)."""
    return {(path, name) for path, name in _classes(engine, ("Result", "Panels"))
            if not path.startswith("engine/machinery/") and (path, name) not in PUBLIC_RESULTS}


def test_only_the_machinery_defines_result_and_panel_classes():
    assert _machinery_violations(PACKAGE / "engine") == set()
    machinery = _classes(MACHINERY, ("Result", "Panels"))
    assert {name for _, name in machinery} == {"RouteResult", "Panels"}


def test_the_check_sees_a_second_result_class_or_panel_pool(tmp_path):
    engine = tmp_path / "engine"
    (engine / "routes").mkdir(parents=True)
    (engine / "machinery").mkdir()
    (engine / "machinery" / "result.py").write_text("class RouteResult:\n    pass\n")
    (engine / "routes" / "new.py").write_text("from dataclasses import dataclass\n\n@dataclass\nclass _Panels:\n"
                                              "    case: int\n\nclass CubatureResult:\n    pass\n")
    assert _machinery_violations(engine) == {("engine/routes/new.py", "_Panels"),
                                             ("engine/routes/new.py", "CubatureResult")}


def _adaptive_integrators(root: Path) -> set[str]:
    """Modules under ``root`` (relative to its parent) that define a function named ``adaptive_…`` (the engine's
    adaptive integrators: 1-D bisection, the rectangle driver)."""
    return {path.relative_to(root.parent).as_posix() for path in root.rglob("*.py")
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
            if isinstance(node, ast.FunctionDef) and node.name.startswith("adaptive_")}


def test_adaptive_integrators_live_in_the_machinery_only():
    assert _adaptive_integrators(PACKAGE) == {"brdfnorm/engine/machinery/interval.py",
                                              "brdfnorm/engine/machinery/panels.py"}


def test_the_integrator_finder_sees_one_in_a_route(tmp_path):
    (tmp_path / "pkg" / "lut").mkdir(parents=True)
    (tmp_path / "pkg" / "lut" / "table.py").write_text("def adaptive_simpson(f):\n    return f\n")
    (tmp_path / "pkg" / "lut" / "other.py").write_text("def _average_adaptive(f):\n    return f\n")
    assert _adaptive_integrators(tmp_path / "pkg") == {"pkg/lut/table.py"}


def test_a_route_result_reads_its_extras_and_survives_copies():
    result = RouteResult(np.ones((2, 1)), np.zeros((2, 1)), np.array([3, 4]), np.array([True, False]),
                         extras={"reflected": np.full((2, 1), 0.25)})
    assert result.reflected[0, 0] == 0.25
    assert result.reasons().tolist() == ["", "budget"]
    with pytest.raises(AttributeError, match="transmitted"):
        _ = result.transmitted
    changed = result.with_(value=np.zeros((2, 1)), transmitted=np.full((2, 1), 0.75))
    assert changed.value[0, 0] == 0.0 and changed.transmitted[1, 0] == 0.75 and changed.reflected[0, 0] == 0.25
    assert result.value[0, 0] == 1.0 and "transmitted" not in result.extras
    for twin in (copy.deepcopy(changed), pickle.loads(pickle.dumps(changed))):
        assert twin.transmitted[1, 0] == 0.75 and twin.evaluations.tolist() == [3, 4]


# -- no registration by import side effect (issue 39 item 1) --------------------------------------------------

def _import_side_effects(path: Path) -> list[tuple[int, str]]:
    """(line, what) of each module-level statement of ``path`` that fills something of the package outside the
    module while it is imported: a call of a ``register…`` function or method, an assignment into an attribute or
    item of a name imported from the package (``table.ROUTES["x"] = …``, ``module.VALUE = …``); and every
    ``global`` statement (a function that rebinds a module global, as a registration hook does)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    imported = {(alias.asname or alias.name).split(".")[0] for node in tree.body
                if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("brdfnorm"))
                or isinstance(node, ast.Import) and all(a.name.startswith("brdfnorm") for a in node.names)
                for alias in node.names}
    found = [(node.lineno, "global") for node in ast.walk(tree) if isinstance(node, ast.Global)]

    def base(node: ast.AST) -> ast.AST:
        while isinstance(node, ast.Attribute | ast.Subscript):
            node = node.value
        return node

    def top_level(statements):
        for node in statements:
            if isinstance(node, ast.If | ast.Try | ast.With):  # conditional registration is registration too
                yield from top_level(node.body + getattr(node, "orelse", []))
            else:
                yield node

    for node in top_level(tree.body):
        calls = [c for c in ast.walk(node) if isinstance(c, ast.Call)] if isinstance(node, ast.Expr) else []
        for call in calls:
            name = call.func.attr if isinstance(call.func, ast.Attribute) else getattr(call.func, "id", "")
            if name.startswith("register"):
                found.append((node.lineno, f"calls {name}"))
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(
            node, ast.AugAssign | ast.AnnAssign) else []
        for target in targets:
            root = base(target)
            if target is not root and isinstance(root, ast.Name) and root.id in imported:
                found.append((node.lineno, f"writes into {root.id}"))
    return found


def test_no_module_fills_another_at_import_and_no_late_imports():
    found = {str(path.relative_to(PACKAGE)): hits for path in sorted(PACKAGE.rglob("*.py"))
             if (hits := _import_side_effects(path))}
    assert found == {}
    late = [str(path.relative_to(PACKAGE)) for path in PACKAGE.rglob("*.py")
            if "noqa: E402" in path.read_text(encoding="utf-8")]
    assert late == []


def test_the_side_effect_finder_sees_registrations(tmp_path):
    path = tmp_path / "m.py"
    path.write_text("from . import table as T\nfrom .r import REGISTRY\n\nT.ROUTES['x'] = 1\n"
                    "if 'a' not in REGISTRY:\n    REGISTRY.register('a', 1)\nregister_hook(print)\n"
                    "LOCAL = {}\nLOCAL['k'] = 2\n\ndef hook(p):\n    global LOCAL\n    LOCAL = p\n")
    assert _import_side_effects(path) == [(12, "global"), (4, "writes into T"), (6, "calls register"),
                                          (7, "calls register_hook")]
