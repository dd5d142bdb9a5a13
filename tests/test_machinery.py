"""One integration machinery (issue 39 item 1): the engine's result class, panel pool and 1-D adaptive integrator
each have one home, ``brdfnorm/engine/machinery/``, and every route uses them; and the RouteResult itself."""

from __future__ import annotations

import ast
import copy
import pickle
from pathlib import Path

import numpy as np
import pytest

from brdfnorm.engine.machinery.result import RouteResult

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "brdfnorm"
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
