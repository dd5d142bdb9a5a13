"""Issue 12 item 5: the ``smith:P/Q@D`` fit of GGX's E(μ, α) (height-correlated, F = 1) meets 5e-3 max abs with
≤ 16 coefficients over μ ∈ [0, 1], α ∈ [0.02, 1] — checked against the built-in albedo at points that are not in
the fitting table (μ down to 1e-6, α = 0.02 and 1) — and its emitted code evaluates to the same numbers: the
Python imported from a file, the C compiled and run, the GLSL run on Mesa's llvmpipe (compiled by
glslangValidator as well), the HLSL compiled."""

from __future__ import annotations

import importlib.util
import json
import shutil
import subprocess

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.fit import fit, parse_form
from brdfnorm.fit.codegen import emit
from brdfnorm.fit.families import SmithForm, smith_variable
from brdfnorm.lut.fitting import fit_table

GOAL = 5e-3
# The fitting table: μ graded towards the horizon (the boundary layer μ ≲ α) and even over [0.05, 1].
FIT_MU = np.unique(np.concatenate([np.geomspace(1e-4, 0.05, 14), np.linspace(0.05, 1.0, 10)]))
FIT_ALPHA = np.concatenate([np.geomspace(0.02, 0.2, 8), np.linspace(0.25, 1.0, 10)])
# Points not in the table: horizon (1e-6), inside the boundary layer of small α, midway between table nodes.
CHECK_MU = np.array([1e-6, 3e-5, 3.3e-4, 2.1e-3, 7.7e-3, 0.019, 0.033, 0.071, 0.16, 0.31, 0.47, 0.66, 0.83,
                     0.97, 1.0])
CHECK_ALPHA = np.array([0.02, 0.023, 0.041, 0.087, 0.15, 0.27, 0.44, 0.61, 0.79, 0.93, 1.0])


def _albedo(mu: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    table = lut.compute(bn.load("ggx"), {"mu": mu, "alpha": alpha}, rtol=1e-9, average=False)
    assert np.max(table["E_error"]) < 1e-6
    return table["E"]


@pytest.fixture(scope="module")
def table():
    return lut.Lut({"E": _albedo(FIT_MU, FIT_ALPHA)}, {"mu": FIT_MU, "alpha": FIT_ALPHA}, {"model": "ggx"})


@pytest.fixture(scope="module")
def check():
    return _albedo(CHECK_MU, CHECK_ALPHA)


@pytest.fixture(scope="module", params=["smith:1/1@1/2", "smith:1/1@2"])
def fitted(request, table):
    """The two forms that meet the goal: 11 coefficients (Q of degree 2 in α², N and L of degree 1) and 14."""
    return fit_table(table, form=request.param)


def _grid(mu, alpha):
    M, A = np.meshgrid(mu, alpha, indexing="ij")
    return M, A


def test_the_albedo_tends_to_one_at_the_horizon(check):
    """The form's premise E(0, α) = 1 (every reflected ray of a grazing view leaves upwards), from the
    integrator: at μ = 1e-6, 1 − E ≈ x·α²·ln(1/x) + … stays below 1e-4 for every α."""
    assert np.all(np.abs(check[0] - 1.0) < 1e-4)
    assert np.min(check) < 0.4  # and the table is not flat: E(1, 1) = 1 − ln 2


def test_goal_met_off_the_fitting_grid(fitted, check):
    result = fitted.best
    assert result.form.startswith("smith:1/1@") and len(result.coefficients) in (11, 14)
    M, A = _grid(CHECK_MU, CHECK_ALPHA)
    error = np.abs(result(M, A) - check)
    assert error.max() <= GOAL, f"max abs error {error.max():.3g} at {np.unravel_index(error.argmax(), M.shape)}"
    # at μ = 0 exactly the form is finite and 1, the albedo's limit
    at_horizon = result(np.zeros_like(CHECK_ALPHA), CHECK_ALPHA)
    assert np.all(at_horizon == 1.0)


def test_smith_variable_is_one_over_one_plus_two_lambda():
    mu, alpha = np.array([1e-3, 0.2, 0.7, 1.0]), np.array([0.02, 0.5, 1.0, 0.3])
    tan2 = (1 - mu**2) / mu**2
    lam = (-1 + np.sqrt(1 + alpha**2 * tan2)) / 2  # Heitz 2014, eq. 72
    np.testing.assert_allclose(smith_variable(mu, alpha), 1 / (1 + 2 * lam), rtol=1e-12)
    assert smith_variable(np.array([0.0]), np.array([0.0]))[0] == 0.0


@pytest.mark.slow
def test_pareto_front_smith_beats_rationals_in_sqrt_mu(table):
    """``auto`` over ≤ 9 coefficients: the front is monotone, and the smith forms beat every rational in √μ of
    the same size several times over (the goal needs 14: :func:`test_goal_met_off_the_fitting_grid`)."""
    result = fit_table(table, max_coefficients=9)
    counts = [entry["coefficients"] for entry in result.front]
    errors = [entry["max_abs_error"] for entry in result.front]
    assert counts == sorted(counts) and errors == sorted(errors, reverse=True)
    best_smith = min(e["max_abs_error"] for e in result.tried if e["form"].startswith("smith") and not e["skipped"])
    rationals = [e for e in result.tried if e["form"].startswith("rational-sqrt")]
    assert all(e["max_abs_error"] > best_smith / 0.3 for e in rationals if not e["skipped"])
    # a candidate left unfitted (pruned) is checked by the linear program for the whole family at that bound
    M, A = _grid(FIT_MU, FIT_ALPHA)
    assert all(parse_form(e["form"], two_d=True).error_exceeds(M.ravel(), A.ravel(), table["E"].ravel(),
                                                               best_smith / 0.3)
               for e in rationals if e["skipped"])
    assert result.best.form.startswith("smith") and result.best.max_abs_error == errors[-1] == best_smith
    assert result.best.warnings if best_smith > GOAL else not result.best.warnings
    # the front's errors are the fit's errors on the table
    assert np.isclose(np.max(np.abs(result.best(M, A) - table["E"])), result.best.max_abs_error, rtol=1e-9)


def test_pruned_front_equals_the_front_of_fitting_every_candidate(table):
    """``auto`` leaves unfitted the candidates proved (by a linear program) unable to enter the front; on a small
    table the front, the chosen fit and every fitted candidate equal those of fitting all of them, and every
    pruned candidate's actual fit (or pole) confirms the proof: its error exceeds the bound it was skipped for."""
    small = lut.Lut({"E": table["E"][::3, ::3]}, {"mu": FIT_MU[::3], "alpha": FIT_ALPHA[::3]}, {"model": "ggx"})
    fast = fit_table(small, max_coefficients=10)
    slow = fit_table(small, max_coefficients=10, prune=False)
    # (the same fit's last bits vary with the BLAS kernel: errors and coefficients equal to 1e-9)
    assert [(e["coefficients"], e["form"]) for e in fast.front] == [(e["coefficients"], e["form"]) for e in slow.front]
    assert np.allclose([e["max_abs_error"] for e in fast.front], [e["max_abs_error"] for e in slow.front], rtol=1e-9)
    assert fast.best.form == slow.best.form and np.allclose(fast.best.coefficients, slow.best.coefficients, rtol=1e-6)
    assert [e["form"] for e in fast.tried] == [e["form"] for e in slow.tried]
    skipped = [(f, s) for f, s in zip(fast.tried, slow.tried, strict=True) if f["skipped"]]
    assert len(skipped) >= 10 and not any(e["skipped"] for e in slow.tried)
    # Candidates outside the front are not compared fit by fit: the minimax iterations of an ill-conditioned
    # candidate amplify those last bits (one differed beyond 1e-9 in a fresh-clone run, not reproducibly), and
    # pruning never changes how a candidate is fitted, only whether it is.
    assert all(s["pole"] or s["max_abs_error"] > f["max_abs_error_above"] for f, s in skipped)


def test_the_pruning_proof_against_fits_and_least_squares(table):
    """:meth:`RationalForm.error_exceeds` (and SmithForm's) never claims a bound that a pole-free fit beats (the
    fit is a witness), and does claim one below a polynomial's least-squares RMS error, a lower bound of its
    minimax error."""
    M, A = _grid(FIT_MU, FIT_ALPHA)
    x, t, y = M.ravel(), A.ravel(), table["E"].ravel()
    witnesses = 0
    for spec in ("rational-sqrt:1/0@1", "rational-sqrt:2/0@1", "rational-sqrt:4/0@1~tau", "rational-sqrt:2/0@2",
                 "rational-sqrt:3/0@1~tau", "smith:0/0@1", "smith:1/1@1", "smith:1/1@1/2"):
        form = parse_form(spec, two_d=True)
        result = fit(x, y, t, form=form, metric="minimax-abs", names=("mu", "alpha"))
        q = form.denominator(np.asarray(result.coefficients), x, t)
        if np.all(q > 0) or np.all(q < 0):  # no pole on the samples: the fit is in the family proved about
            witnesses += 1
            assert not form.error_exceeds(x, t, y, result.max_abs_error * (1 + 1e-6))
            assert form.error_exceeds(x, t, y, result.max_abs_error * 0.5)
    assert witnesses >= 5
    poly = parse_form("poly:3", two_d=False)
    c = np.polynomial.polynomial.polyfit(x, y, 3)
    rms = np.sqrt(np.mean((np.polynomial.polynomial.polyval(x, c) - y) ** 2))
    assert poly.error_exceeds(x, None, y, 0.999 * rms)
    assert not poly.error_exceeds(x, None, y, np.max(np.abs(np.polynomial.polynomial.polyval(x, c) - y)))


def test_minimax_abs_beats_the_other_metrics_in_max_abs_error(table):
    """(Two variables: no alternation theorem to check.) The minimax-abs fit's max abs error is below that of the
    least-squares and the minimax-rel fits of the same form, by the fit's own evaluation and by this test's."""
    result = fit_table(table, form="smith:1/1@1").best
    M, A = _grid(FIT_MU, FIT_ALPHA)
    assert np.isclose(np.max(np.abs(result(M, A) - table["E"])), result.max_abs_error, rtol=1e-12)
    for metric in ("abs-lsq", "minimax-rel"):
        other = fit(M, table["E"], A, form="smith:1/1@1", metric=metric, names=("mu", "alpha"))
        assert result.max_abs_error < other.max_abs_error


def test_bad_uses_of_the_form():
    form = fit(np.array([0.5, 1.0] * 8), np.linspace(0.5, 0.9, 16), np.linspace(0.1, 1, 16), form="smith:0/0@0",
               names=("mu", "alpha"))
    assert isinstance(form.form_object, SmithForm) and len(form.coefficients) == 2
    assert parse_form("smith:1/1@1/2", two_d=True).n_coefficients == 11
    assert parse_form("smith:1/1@2/2", two_d=True).spec == "smith:1/1@2"
    for spec, message in [("smith:1/1", "@D"), ("smith:1@1", "smith:P/Q@D"), ("smith:1/1@1~tau", "~tau"),
                          ("rational-sqrt:1/1@1/2", "bad degree"), ("smith:1/1@1/x", "bad degree")]:
        with pytest.raises(ValueError, match=message):
            fit(np.ones(20), np.ones(20), np.ones(20), form=spec)
    with pytest.raises(ValueError, match="0 ≤ μ ≤ 1"):
        fit(np.full(20, 2.0), np.ones(20), np.ones(20), form="smith:1/1@1")


@pytest.mark.slow
def test_cli_prints_the_front_and_emits_code(table, tmp_path, run_cli):
    path = lut.save(table, tmp_path / "E.npz")
    code, stdout, stderr = run_cli("fit", "--lut", str(path), "--max-coefficients", "6", "--emit", "glsl")
    assert code == 0, stderr
    assert "Pareto front" in stderr and "smith:" in stderr and "chosen: smith:" in stderr
    assert stdout.startswith("// Table E of ggx: smith:") and "Pareto" not in stdout
    code, stdout, _ = run_cli("fit", "--lut", str(path), "--max-coefficients", "9", "--json")
    data = json.loads(stdout)  # every candidate listed, the pruned ones with the bound they were proved above
    skipped = [e for e in data["tried"] if e["skipped"]]
    assert code == 0 and len(data["tried"]) == len(fit_table(table, max_coefficients=9).tried) and skipped
    assert all(e["max_abs_error"] is None and e["max_abs_error_above"] > 0 for e in skipped)
    assert data["form"] == data["front"][-1]["form"] or data["max_abs_error"] <= GOAL
    other = lut.save(lut.Lut({"E": table["E"]}, {"mu": FIT_MU, "n": FIT_ALPHA}, {}), tmp_path / "n.npz")
    code, _, stderr = run_cli("fit", "--lut", str(other), "--form", "smith:1/1@1")
    assert code == 2 and stderr.count("\n") == 1 and "alpha" in stderr and "--form" in stderr


def test_fit_help_names_the_smith_forms(run_cli):
    code, stdout, _ = run_cli("fit", "--help")
    assert code == 0 and "smith:P/Q@D/DQ" in stdout and "minimax-abs" in stdout


# -- the emitted code --------------------------------------------------------------------------------------

PROBE_MU = np.array([0.0, 1e-6, 3e-4, 0.02, 0.1, 0.5, 0.9, 1.0, 0.3, 0.0])
PROBE_ALPHA = np.array([0.02, 0.02, 0.05, 0.03, 0.4, 1.0, 0.7, 1.0, 0.0, 0.0])
NAME = "brdfnorm_ggx_e"


def _emit(fitted, language: str) -> str:
    return emit(fitted.best, language, "ggx", variable="mu", second="alpha", quantity="Table E", suffix="E")


def test_python_matches_the_fit(fitted, tmp_path):
    path = tmp_path / "emitted.py"
    path.write_text(_emit(fitted, "python"))
    spec = importlib.util.spec_from_file_location("emitted", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    function = getattr(module, NAME)
    expected = fitted.best(PROBE_MU, PROBE_ALPHA)
    np.testing.assert_allclose(function(PROBE_MU, PROBE_ALPHA), expected, rtol=1e-7)
    assert function(0.5, 0.3) == pytest.approx(float(fitted.best(0.5, 0.3)), rel=1e-7)  # plain floats too
    assert expected[0] == expected[-1] == 1.0


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")
def test_c_compiles_runs_and_matches_the_fit(fitted, tmp_path):
    mus, alphas = (", ".join(repr(float(v)) for v in a) for a in (PROBE_MU, PROBE_ALPHA))
    main = (f"#include <stdio.h>\nint main(void) {{ double m[] = {{{mus}}}; double a[] = {{{alphas}}};\n"
            f"  for (int i = 0; i < {PROBE_MU.size}; ++i) printf(\"%.17g\\n\", {NAME}(m[i], a[i]));\n"
            "  return 0; }\n")
    (tmp_path / "fit.c").write_text(_emit(fitted, "c") + main)
    subprocess.run(["cc", "-std=c99", "-Wall", "-Werror", "-o", str(tmp_path / "fit"), str(tmp_path / "fit.c"),
                    "-lm"], check=True, capture_output=True)
    out = subprocess.run([str(tmp_path / "fit")], check=True, capture_output=True, text=True).stdout
    np.testing.assert_allclose([float(v) for v in out.split()], fitted.best(PROBE_MU, PROBE_ALPHA), rtol=1e-7)


GLSLANG = shutil.which("glslangValidator")


@pytest.mark.skipif(GLSLANG is None, reason="glslangValidator not installed (Debian package glslang-tools)")
def test_glsl_and_hlsl_compile(fitted, tmp_path):
    glsl = ("#version 450\nlayout(location = 0) out vec4 color;\n" + _emit(fitted, "glsl")
            + f"void main() {{ color = vec4({NAME}(gl_FragCoord.x, gl_FragCoord.y)); }}\n")
    (tmp_path / "fit.frag").write_text(glsl)
    done = subprocess.run([GLSLANG, str(tmp_path / "fit.frag")], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    hlsl = (_emit(fitted, "hlsl")
            + f"float4 main(float4 p : SV_Position) : SV_Target {{ return float4({NAME}(p.x, p.y), 0, 0, 1); }}\n")
    (tmp_path / "fit.hlsl").write_text(hlsl)
    done = subprocess.run([GLSLANG, "-D", "-V", "-e", "main", "-S", "frag", "-o", str(tmp_path / "fit.spv"),
                           str(tmp_path / "fit.hlsl")], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def test_glsl_runs_on_mesa_and_matches_the_fit(fitted):
    """The emitted GLSL in a compute shader on llvmpipe: float32 agrees with the float64 fit to 2e-6."""
    import mesa

    try:
        ctx = mesa.context()
    except mesa.MesaUnavailable as reason:
        pytest.skip(str(reason))
    source = ("#version 430\nlayout(local_size_x = 16) in;\n"
              "layout(std430, binding = 0) readonly buffer In { vec2 probes[]; };\n"
              "layout(std430, binding = 1) writeonly buffer Out { float values[]; };\n"
              + _emit(fitted, "glsl")
              + "void main() { uint i = gl_GlobalInvocationID.x; vec2 p = probes[i];\n"
              + f"  values[i] = {NAME}(p.x, p.y); }}\n")
    n = 16
    probes = np.zeros((n, 2), dtype=np.float32)
    probes[:PROBE_MU.size] = np.stack([PROBE_MU, PROBE_ALPHA], axis=1)
    inputs, outputs = ctx.buffer(probes.tobytes()), ctx.buffer(reserve=4 * n)
    inputs.bind_to_storage_buffer(0)
    outputs.bind_to_storage_buffer(1)
    ctx.compute_shader(source).run(group_x=1)
    values = np.frombuffer(outputs.read(), dtype=np.float32)[:PROBE_MU.size]
    expected = fitted.best(probes[:PROBE_MU.size, 0].astype(float), probes[:PROBE_MU.size, 1].astype(float))
    np.testing.assert_allclose(values, expected, atol=2e-6)
