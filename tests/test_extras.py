"""A missing optional dependency is one line naming the extra to install, exit 2, everywhere — never an
"internal error" (issue 31: `brdfnorm explore` after `make demo` said "internal error … ModuleNotFoundError:
anyio, please report this"). Each case hides the package (``sys.modules[name] = None`` makes its import fail as
if it were not installed) and runs the command in a fresh interpreter."""

from __future__ import annotations

import subprocess
import sys

import pytest

from brdfnorm.errors import BrdfnormError, MissingExtraError
from brdfnorm.extras import EXTRA_OF, require


def run_hidden(hidden: list[str], *args: str, cwd=None) -> subprocess.CompletedProcess:
    code = ("import sys\n"
            f"for name in {hidden!r}:\n    sys.modules[name] = None\n"
            "from brdfnorm.cli import main\n"
            f"sys.argv = ['brdfnorm', *{list(args)!r}]\n"
            "main()\n")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=cwd)


SLOW = pytest.mark.slow  # each case starts an interpreter (several seconds on a loaded machine)


@pytest.mark.parametrize("hidden, args, extra", [
    (["anyio"], ["explore", "--no-browser"], "explore"),
    pytest.param(["starlette"], ["explore", "--no-browser"], "explore", marks=SLOW),
    pytest.param(["uvicorn"], ["explore", "--no-browser"], "explore", marks=SLOW),
    (["flint"], ["verify", "--certified", "--claim", "phong-original"], "certified"),
    pytest.param(["flint"], ["albedo", "phong", "-p", "n=8", "--theta", "0", "--method", "certified"],
                 "certified", marks=SLOW),
    pytest.param(["OpenEXR"], ["lut", "lambert", "--axis", "mu=0.1:1:4", "-o", "E.exr"], "exr", marks=SLOW),
    pytest.param(["distributed"], ["albedo", "phong", "--theta", "0", "--scheduler", "tcp://127.0.0.1:1"], "dask",
                 marks=SLOW),
])
def test_missing_extra_is_one_line_exit_2(hidden, args, extra, tmp_path):
    result = run_hidden(hidden, *args, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ") and f"pip install 'brdfnorm[{extra}]'" in lines[0]
    assert "internal error" not in lines[0] and result.stdout == ""
    assert not (tmp_path / "E.exr").exists()


def test_require():
    import json

    assert require("json") is json
    expected = r"needs python-flint; install it with pip install 'brdfnorm\[certified\]'"
    with pytest.raises(MissingExtraError, match=expected):
        sys.modules["flint"] = None
        try:
            require("flint", where="x")
        finally:
            del sys.modules["flint"]
    error = MissingExtraError("m", where="w", module="flint")
    assert isinstance(error, BrdfnormError) and isinstance(error, ImportError) and error.module == "flint"
    assert set(EXTRA_OF.values()) <= {"explore", "exr", "certified", "dask", "gl", "spectral"}


def test_a_missing_core_module_gets_no_install_hint():
    """Only optional packages get an install hint: a core module gone missing is a bug (an internal error)."""
    from brdfnorm.extras import missing_extra

    assert missing_extra(ModuleNotFoundError("no module named 'scipy'", name="scipy")) is None
    hint = missing_extra(ModuleNotFoundError("no module named 'anyio'", name="anyio"), where="explore")
    assert str(hint) == "explore: needs anyio; install it with pip install 'brdfnorm[explore]'"
