"""The API pages in one style (issue 43): Sphinx roles in docstrings render as links or code, doctest lines as
code blocks, and a strict docs build fails on a raw role (docs_support/roles.py)."""

from __future__ import annotations

import importlib.util
import logging
import subprocess
import sys

import pytest
from helpers.paths import REPO

ROOT = REPO


@pytest.fixture(scope="module")
def roles():
    pytest.importorskip("griffe")
    spec = importlib.util.spec_from_file_location("docs_roles", ROOT / "docs_support" / "roles.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_roles_become_optional_references(roles):
    text = roles.rewrite("See :mod:`brdfnorm.lut`, :class:`~brdfnorm.errors.ParameterError` and :func:`f`.")
    assert ":mod:" not in text and ":class:" not in text and ":func:" not in text
    assert '<autoref identifier="brdfnorm.lut" optional><code>brdfnorm.lut</code></autoref>' in text
    assert '<autoref identifier="brdfnorm.errors.ParameterError" optional><code>ParameterError</code>' in text
    assert '<autoref identifier="f" optional><code>f</code></autoref>' in text


def test_doctest_lines_become_a_code_block(roles):
    text = roles.rewrite("An example:\n>>> import brdfnorm as bn\n>>> bn.load('ggx')\nggx\n\nAfter.")
    assert text.splitlines() == ["An example:", "", "```python", ">>> import brdfnorm as bn",
                                 ">>> bn.load('ggx')", "ggx", "```", "", "", "After."]


def test_a_raw_role_on_a_page_is_a_warning(roles, caplog):
    page = type("Page", (), {"file": type("File", (), {"src_path": "api/x.md"})()})()
    with caplog.at_level(logging.WARNING, logger="mkdocs.plugins.brdfnorm_roles"):
        roles.on_post_page("<p>see :mod:<code>brdfnorm.lut</code></p><pre>:mod:`ok in code`</pre>", page, None)
    assert len(caplog.records) == 1 and "api/x.md" in caplog.records[0].getMessage()


def test_strict_build_fails_on_a_raw_role(tmp_path):
    pytest.importorskip("mkdocs")
    pytest.importorskip("material")
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.md").write_text("# Page\n\nThe :data:`brdfnorm.AUTO_ORDER` list.\n", encoding="utf-8")
    (tmp_path / "mkdocs.yml").write_text(
        "site_name: t\ntheme:\n  name: material\nhooks:\n  - " + str(ROOT / "docs_support" / "roles.py") + "\n",
        encoding="utf-8")
    result = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "s")],
                            cwd=tmp_path, capture_output=True, text=True, timeout=300,
                            env={"PATH": "/usr/bin:/bin", "NO_MKDOCS_2_WARNING": "1"})
    assert result.returncode != 0 and "raw Sphinx role" in result.stderr, result.stderr[-2000:]
