"""stdout carries machine output alone (issue 11, item 2): each command's stdout is fed to its consumer —
json.loads, the csv module, glslangValidator (GLSL, and HLSL through its HLSL front end), cc, a Python import —
while summaries, progress and messages for people go to stderr."""

from __future__ import annotations

import csv
import importlib.util
import io
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
from helpers.paths import REPO

from brdfnorm.fit.codegen import function_name

ROOT = REPO
GLSLANG = shutil.which("glslangValidator")
CC = shutil.which("cc")
needs_glslang = pytest.mark.skipif(GLSLANG is None, reason="glslangValidator not installed (glslang-tools)")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc)")
FIT = ["fit", "blinn-phong", "--sweep", "n=1:100:24", "--form", "rational:2/1"]
NAME = function_name("blinn-phong")


def _ok(run_cli, *argv: str) -> tuple[str, str]:
    code, out, err = run_cli(*argv)
    assert code == 0, err
    return out, err


@pytest.mark.parametrize("argv", [
    ["albedo", "blinn-phong", "-p", "n=64", "--theta", "0,30", "--json"],
    ["normalize", "phong", "--sweep", "n=1,10", "--json"],
    ["info", str(ROOT / "examples" / "ggx.brdf"), "--samples", "64", "--json"],
    ["verify", "--json", "--n", "2", "--claim", "phong-modified"],
    [*FIT, "--json"],
    [*FIT, "--json", "--emit", "glsl"],
])
def test_json_output_is_one_object_on_stdout(argv, run_cli):
    out, _ = _ok(run_cli, *argv)
    data = json.loads(out)
    assert isinstance(data, dict) and data


def test_csv_output_parses_with_the_csv_module(run_cli):
    out, err = _ok(run_cli, "normalize", "blinn-phong", "--sweep", "n=8,64,512", "--csv")
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [float(r["n"]) for r in rows] == [8.0, 64.0, 512.0]
    assert all(float(r["factor"]) * float(r["albedo"]) == pytest.approx(1.0, rel=1e-12) for r in rows)


def test_a_table_asked_for_is_on_stdout_and_nothing_else_is(run_cli):
    out, err = _ok(run_cli, "albedo", "lambert", "--theta", "0")
    assert "albedo" in out and err == ""
    out, _ = _ok(run_cli, "models")
    assert "blinn-phong-gaussian" in out


@pytest.mark.parametrize("language", ["glsl", "hlsl", "c", "python"])
def test_emitted_code_alone_on_stdout_and_the_summary_on_stderr(language, run_cli):
    out, err = _ok(run_cli, *FIT, "--emit", language)
    assert out.lstrip().startswith(("//", "#", "def")) and "max relative error" in err
    assert "α ≈" not in out and "α ≈" in err


def test_dash_output_is_stdout_with_the_summary_on_stderr(run_cli):
    out, err = _ok(run_cli, *FIT, "--emit", "c", "-o", "-")
    assert out.startswith("#include <math.h>") and "α ≈" in err and "code written" not in err
    code, out, err = run_cli(*FIT, "--emit", "c", "-o", "-", "--json")
    assert code == 2 and out == "" and "--output" in err


@pytest.fixture(scope="module")
def emitted() -> dict[str, str]:
    """Each language's stdout of the same fit, from the real command line."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    code = {}
    for language in ("glsl", "hlsl", "c", "python"):
        done = subprocess.run([sys.executable, "-m", "brdfnorm", *FIT, "--emit", language], capture_output=True,
                              text=True, env=env, timeout=120)
        assert done.returncode == 0, done.stderr
        code[language] = done.stdout
    return code


@pytest.mark.slow
@needs_glslang
def test_stdout_glsl_compiles_as_it_stands_and_defines_the_function(tmp_path, emitted):
    path = tmp_path / "f.glsl"
    path.write_text(emitted["glsl"])
    done = subprocess.run([GLSLANG, "-d", "-S", "frag", str(path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout
    shader = tmp_path / "use.frag"
    shader.write_text("#version 450\nlayout(location = 0) out vec4 color;\n" + emitted["glsl"]
                      + f"void main() {{ color = vec4({NAME}(gl_FragCoord.x)); }}\n")
    done = subprocess.run([GLSLANG, str(shader)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout


@pytest.mark.slow
@needs_glslang
def test_stdout_hlsl_compiles_with_glslangs_hlsl_front_end(tmp_path, emitted):
    shader = tmp_path / "use.hlsl"
    shader.write_text(emitted["hlsl"] + f"float4 main(float4 p : SV_Position) : SV_Target "
                      f"{{ return float4({NAME}(p.x), 0, 0, 1); }}\n")
    done = subprocess.run([GLSLANG, "-D", "-V", "-e", "main", "-S", "frag", "-o", str(tmp_path / "f.spv"),
                           str(shader)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout


@pytest.mark.slow
@needs_cc
def test_stdout_c_compiles(tmp_path, emitted):
    path = tmp_path / "f.c"
    path.write_text(emitted["c"])
    done = subprocess.run([CC, "-std=c99", "-Wall", "-Werror", "-c", str(path), "-o", str(tmp_path / "f.o")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


@pytest.mark.slow
def test_stdout_python_imports_and_evaluates(tmp_path, emitted):
    path = tmp_path / "f.py"
    path.write_text(emitted["python"])
    spec = importlib.util.spec_from_file_location("f", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    value = getattr(module, NAME)(np.array([1.0, 50.0]))
    assert np.all(np.isfinite(value)) and np.all(value > 0)


@pytest.mark.slow
@pytest.mark.parametrize("language", ["glsl", "hlsl", "c", "python"])
def test_issue_done_when_command_redirected_to_a_file_compiles(tmp_path, language):
    """`brdfnorm fit blinn-phong-gaussian --sweep n=1:512:512 --form auto --emit LANG > f.LANG` compiles as it
    stands (GLSL, HLSL: glslangValidator; C: cc -c) or imports (Python)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    suffix = {"glsl": "glsl", "hlsl": "hlsl", "c": "c", "python": "py"}[language]
    command = (f"{sys.executable} -m brdfnorm fit blinn-phong-gaussian --sweep n=1:512:512 --form auto "
               f"--emit {language} -v > f.{suffix}")  # -v: the forms tried, on stderr
    done = subprocess.run(command, shell=True, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    path = tmp_path / f"f.{suffix}"
    assert "brdfnorm_blinn_phong_gaussian_norm(" in path.read_text() and "forms tried" in done.stderr
    if language == "python":
        spec = importlib.util.spec_from_file_location("f", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        assert 0 < module.brdfnorm_blinn_phong_gaussian_norm(1.0) < 1.0
        return
    if language == "c":
        if CC is None:
            pytest.skip("no C compiler (cc)")
        argv = [CC, "-std=c99", "-Wall", "-Werror", "-c", str(path), "-o", str(tmp_path / "f.o")]
    else:
        if GLSLANG is None:
            pytest.skip("glslangValidator not installed (glslang-tools)")
        # A lone function is a valid translation unit; HLSL goes through glslang's HLSL front end (no DXC here).
        argv = [GLSLANG, "-d", "-S", "frag", str(path)] if language == "glsl" else [
            GLSLANG, "-D", "-V", "-S", "frag", "-e", "brdfnorm_blinn_phong_gaussian_norm", "-o",
            str(tmp_path / "f.spv"), str(path)]
    compiled = subprocess.run(argv, capture_output=True, text=True)
    assert compiled.returncode == 0, compiled.stdout + compiled.stderr


@pytest.mark.slow
def test_report_prints_nothing_on_stdout(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    done = subprocess.run([sys.executable, "-m", "brdfnorm", "report", "lambert", "--sweep", "reflectance=0.5,1",
                           "-o", "out"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "" and "wrote" in done.stderr


@pytest.mark.slow
def test_info_piped_into_head_exits_0(tmp_path):
    """A closed pipe (`brdfnorm info FILE | head -1`) ends quietly with exit 0, not a BrokenPipeError; `true`
    exits before the table is written, so the write always meets a closed pipe."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    command = (f"{sys.executable} -m brdfnorm info {ROOT / 'examples' / 'ggx.brdf'} --samples 64 | true; "
               "echo status=${PIPESTATUS[0]}")
    done = subprocess.run(["bash", "-c", command], env=env, capture_output=True, text=True, timeout=120)
    assert "status=0" in done.stdout, done.stdout + done.stderr
    assert "Traceback" not in done.stderr and "Error" not in done.stderr
