"""The global tensor rules' driver (issue 39, "one global-rule driver"): which modules run a levels loop of their
own. One numpy driver exists (``engine/machinery/global_driver.py``); the lobe-aligned coordinates
(``engine/machinery/lobe_grid.py``) and the half-vector rectangle (``engine/routes/halfvector_global.py``) are grids
it runs, not loops of their own. Beside it, the half-vector rule fused for the compiled backend
(``engine/compiled/global_rule.py``, checked against the numpy driver by test_compiled_global_rule.py) is a backend,
not a numpy driver. The tests keep a second numpy driver from appearing."""

from __future__ import annotations

import ast
from pathlib import Path

from helpers.paths import SRC

ENGINE = SRC / "brdfnorm" / "engine"
#: What a global-rule driver defines: its entry point and its per-level refinement of the grid.
DRIVER_FUNCTIONS = {"integrate_global", "_refine"}
KNOWN_DRIVERS = {"machinery/global_driver.py"}


def _drivers(root: Path) -> set[str]:
    """Modules under ``root`` defining every function of :data:`DRIVER_FUNCTIONS` (paths relative to ``root``)."""
    found = set()
    for path in root.rglob("*.py"):
        names = {node.name for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
                 if isinstance(node, ast.FunctionDef)}
        if DRIVER_FUNCTIONS <= names:
            found.add(path.relative_to(root).as_posix())
    return found


def test_no_third_global_rule_driver(tmp_path):
    assert _drivers(ENGINE) <= KNOWN_DRIVERS
    # the check can fail: a module with its own levels loop is found
    (tmp_path / "extra.py").write_text("def integrate_global():\n    pass\n\n\ndef _refine():\n    pass\n")
    assert _drivers(tmp_path) == {"extra.py"}


def test_one_global_rule_driver():
    assert _drivers(ENGINE) == KNOWN_DRIVERS
