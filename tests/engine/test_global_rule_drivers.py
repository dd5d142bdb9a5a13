"""The global tensor rules' drivers (issue 39, "one global-rule driver"): which modules run a levels loop of their
own. Today two numpy drivers exist — the lobe-aligned one (``engine/machinery/tensor_rule.py``) and the half-vector
one (``engine/routes/halfvector_global.py``) — beside the half-vector rule fused for the compiled backend
(``engine/compiled/global_rule.py``, checked against its numpy driver by test_compiled_global_rule.py). The first
test keeps a third from appearing; the second, a strict xfail, records the duplicate until the two numpy drivers
are one (it then passes, and the strict marker must go)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from helpers.paths import SRC

ENGINE = SRC / "brdfnorm" / "engine"
#: What a global-rule driver defines: its entry point and its per-level refinement of the grid.
DRIVER_FUNCTIONS = {"integrate_global", "_refine"}
KNOWN_DRIVERS = {"machinery/tensor_rule.py", "routes/halfvector_global.py"}


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


@pytest.mark.xfail(strict=True, reason="two numpy global-rule drivers remain (issue 39): see the module docstring")
def test_one_global_rule_driver():
    assert len(_drivers(ENGINE)) == 1
