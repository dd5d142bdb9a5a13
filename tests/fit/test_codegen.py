"""brdfnorm.fit.codegen: the emitted GLSL/HLSL compile (glslangValidator), the C compiles, runs and agrees with the
fit, and the Python (imported from a file) agrees with the fit."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess

import numpy as np
import pytest
from helpers.paths import EXAMPLES

from brdfnorm.errors import ArgumentError
from brdfnorm.fit import fit
from brdfnorm.fit.codegen import emit, function_name, identifier, literal
from brdfnorm.models.closed_forms import blinn_phong_albedo_normal

N = np.linspace(1.0, 512.0, 200)
ALPHA = 1.0 / blinn_phong_albedo_normal(N)


def _fits():
    x, t = np.meshgrid(np.geomspace(1, 1000, 12), np.linspace(0.1, 1.0, 6))
    y = (2.0 + 0.3 * t + 0.1 * np.sqrt(x) * (1 + t)) / (1.0 + 0.02 * t * np.sqrt(x))
    return {
        "linear": fit(N, ALPHA, form="linear", names=("n", "t")),
        "hyperbola": fit(N, ALPHA, form="hyperbola", names=("n", "t")),
        "rational": fit(N, ALPHA, form="rational:3/2", names=("n", "t")),
        "rational-sqrt": fit(N, ALPHA, form="rational-sqrt:2/2", names=("n", "t")),
        "two-d": fit(x, y, t, form="rational-sqrt:1/1@1", metric="rel-lsq", names=("n", "cos_theta_o")),
        "two-d-tau": fit(x, y, t, form="rational-sqrt:2/1@1~tau", metric="rel-lsq", names=("n", "cos_theta_o")),
    }


FITS = _fits()
NAME = function_name("blinn-phong")
PROBE_X = np.array([1.0, 2.5, 17.0, 100.0, 333.3, 512.0])
PROBE_T = np.array([0.1, 0.35, 0.5, 0.8, 0.95, 1.0])


def test_names_and_literals():
    assert function_name("blinn-phong-gaussian") == "brdfnorm_blinn_phong_gaussian_norm"
    assert identifier("3 weird/name") == "_3_weird_name"
    assert literal(1.0, "glsl") == "1.0" and literal(1e-5, "glsl") == "1.0e-05"
    assert float(literal(0.123456789123, "c")) == pytest.approx(0.123456789, abs=1e-12)
    with pytest.raises(ArgumentError, match="^language: unknown language .rust."):
        emit(FITS["linear"], "rust", "blinn-phong")


def _import(tmp_path, source: str):
    path = tmp_path / "emitted.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("emitted", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return getattr(module, NAME)


@pytest.mark.parametrize("key", list(FITS))
def test_python_matches_the_fit(tmp_path, key):
    result = FITS[key]
    function = _import(tmp_path, emit(result, "python", "blinn-phong"))
    args = (PROBE_X, PROBE_T) if result.form_object.two_d else (PROBE_X,)
    # 9 significant digits per coefficient: agreement to ~1e-8 relative (more where coefficients cancel).
    np.testing.assert_allclose(function(*args), result(*args), rtol=1e-7)
    assert f"{result.max_rel_error:.3g}" in emit(result, "python", "blinn-phong")


def _compile_and_run_c(tmp_path, source: str, two_d: bool) -> np.ndarray:
    args = "x[i], t[i]" if two_d else "x[i]"
    xs = ", ".join(repr(float(v)) for v in PROBE_X)
    ts = ", ".join(repr(float(v)) for v in PROBE_T)
    main = (f"#include <stdio.h>\nint main(void) {{ double x[] = {{{xs}}}; double t[] = {{{ts}}}; (void)t;\n"
            f"  for (int i = 0; i < {PROBE_X.size}; ++i) printf(\"%.17g\\n\", {NAME}({args}));\n  return 0; }}\n")
    (tmp_path / "fit.c").write_text(source + main)
    exe = tmp_path / "fit"
    subprocess.run(["cc", "-std=c99", "-Wall", "-Werror", "-o", str(exe), str(tmp_path / "fit.c"), "-lm"],
                   check=True, capture_output=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    return np.array([float(v) for v in out.split()])


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")
@pytest.mark.parametrize("key", list(FITS))
def test_c_compiles_runs_and_matches_the_fit(tmp_path, key):
    result = FITS[key]
    two_d = result.form_object.two_d
    values = _compile_and_run_c(tmp_path, emit(result, "c", "blinn-phong"), two_d)
    expected = result(PROBE_X, PROBE_T) if two_d else result(PROBE_X)
    np.testing.assert_allclose(values, expected, rtol=1e-7)


GLSLANG = shutil.which("glslangValidator")


@pytest.mark.skipif(GLSLANG is None, reason="glslangValidator not installed (Debian package glslang-tools)")
@pytest.mark.parametrize("key", list(FITS))
def test_glsl_compiles(tmp_path, key):
    result = FITS[key]
    call = f"{NAME}(gl_FragCoord.x, gl_FragCoord.y)" if result.form_object.two_d else f"{NAME}(gl_FragCoord.x)"
    source = ("#version 450\nlayout(location = 0) out vec4 color;\n" + emit(result, "glsl", "blinn-phong")
              + f"void main() {{ color = vec4({call}); }}\n")
    path = tmp_path / "fit.frag"
    path.write_text(source)
    done = subprocess.run([GLSLANG, str(path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.skipif(GLSLANG is None, reason="glslangValidator not installed (Debian package glslang-tools)")
@pytest.mark.parametrize("key", list(FITS))
def test_hlsl_compiles(tmp_path, key):
    result = FITS[key]
    call = f"{NAME}(p.x, p.y)" if result.form_object.two_d else f"{NAME}(p.x)"
    source = (emit(result, "hlsl", "blinn-phong")
              + f"float4 main(float4 p : SV_Position) : SV_Target {{ return float4({call}, 0, 0, 1); }}\n")
    path = tmp_path / "fit.hlsl"
    path.write_text(source)
    done = subprocess.run([GLSLANG, "-D", "-V", "-e", "main", "-S", "frag", "-o", str(tmp_path / "fit.spv"),
                           str(path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.skipif(GLSLANG is None, reason="glslangValidator not installed (Debian package glslang-tools)")
def test_glsl_rejects_a_broken_function(tmp_path):
    """The compile tests can fail: a mangled emitted function is refused by the same invocation."""
    broken = emit(FITS["rational"], "glsl", "blinn-phong").replace("return p / q;", "return p / ;")
    path = tmp_path / "broken.frag"
    path.write_text("#version 450\nlayout(location = 0) out vec4 color;\n" + broken
                    + f"void main() {{ color = vec4({NAME}(gl_FragCoord.x)); }}\n")
    assert subprocess.run([GLSLANG, str(path)], capture_output=True).returncode != 0


# -- comments in the user's terms, signs folded (issue 43) -----------------------------------------------------


def test_signs_are_folded_into_the_operator():
    # a cubic with a negative coefficient and a hyperbola whose centre is negative
    x = np.linspace(0.05, 1.0, 12)
    cubic = fit(x, 25.1 - 2.7 * x + 41.3 * x**2 + 17.7 * x**3, form="poly:3", names=("alpha", "t"))
    hyperbola = fit(x, 0.2 - 0.01 * np.sqrt((x + 1.5) ** 2 + 2.0), form="hyperbola", names=("alpha", "t"))
    for fitted in (cubic, hyperbola):
        for language in ("glsl", "hlsl", "c", "python"):
            code = emit(fitted, language, "ggx")
            assert "+ -" not in code and "- -" not in code, code
    assert "- 2.7" in emit(cubic, "glsl", "ggx")
    namespace: dict = {}
    exec(emit(hyperbola, "python", "m"), namespace)  # noqa: S102 - our own emitted code
    np.testing.assert_allclose(namespace["brdfnorm_m_norm"](x), hyperbola(x), rtol=1e-7)


def test_comments_state_lobe_convention_domain_and_held_parameters():
    import brdfnorm as bn
    from brdfnorm.explore.compute import fit_factor

    model = bn.load("ggx", fresnel="schlick")
    code = fit_factor(model, "alpha", 0.05, 1.0, 8, "normal", "glsl", params={"f0": 0.04})["code"]
    comment = " ".join(line[3:] for line in code.splitlines() if line.startswith("//"))
    assert "seed" not in comment.lower(), comment
    assert "Lobe: f = D G2 F / (4 N.L N.V)" in comment, comment
    assert "Convention: 1/E" in comment and "at V = N" in comment, comment
    assert "Fitted over alpha in [0.05, 1]" in comment, comment
    assert "f0 = 0.04" in comment and "fresnel = schlick" in comment, comment
    assert all(" " <= c <= "~" for c in comment), comment  # ASCII only: every shader compiler reads it


def test_a_brdf_file_is_named_without_the_users_path(tmp_path):
    import brdfnorm as bn
    from brdfnorm.fit.codegen import fit_context

    path = tmp_path / "private" / "ggx.brdf"
    path.parent.mkdir()
    shutil.copy(EXAMPLES / "ggx.brdf", path)
    lines = fit_context(bn.load(str(path)), "roughness")
    assert "ggx.brdf" in lines[0] and "private" not in " ".join(lines), lines
