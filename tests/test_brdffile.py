"""The ``.brdf`` reader, the model it builds, its albedo against built-ins, and ``brdfnorm info``.

Independent routes: the built-in numpy lobes (``blinn-phong``, ``blinn-phong-gaussian``, ``phong``) for the
example files that define the same lobes, seed 000's closed form, a plain midpoint rule on a (θ, φ) grid for
the albedo of every example, and the seed article's own text for the one-line file.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import brdfnorm as bn
from brdfnorm.brdffile import BrdfModel, load_brdf, parse_brdf, read_brdf, reciprocity_check
from brdfnorm.cli import app
from brdfnorm.engine.machinery.directions import random_hemisphere
from brdfnorm.errors import BrdfFileError, ModelNotFoundError, ParameterError
from brdfnorm.models import REGISTRY, closed_forms

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
EXAMPLE_FILES = sorted(EXAMPLES.glob("*.brdf"))
SEED_003 = next((ROOT.parent / "shared" / "seeds").glob("003_*.txt"), None)

MULTI_LINE = """analytic

# A comment line, then parameters of every kind.
::begin parameters
float n 1 512 100   # a trailing note
  # an indented comment inside the section
bool normalized 1
color tint 0.25 .5 1e0
::end parameters

::begin shader
// GLSL comments, and '#' lines (preprocessor directives), are the shader's business
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return tint * n; }
::end shader

::begin isFunc
vec3 sample(vec2 u) { return vec3(u, 1.0); }
::end isFunc
"""


@pytest.fixture
def pairs(rng):
    return random_hemisphere(rng, 2000), random_hemisphere(rng, 2000)


# -- reader ---------------------------------------------------------------------------------------------
def test_sections_kinds_and_positions():
    brdf = parse_brdf(MULTI_LINE, "mem.brdf")
    n, normalized, tint = brdf.parameters
    assert (n.name, n.kind, n.minimum, n.maximum, n.default, n.strict) == ("n", "float", 1.0, 512.0, 100.0, False)
    assert (normalized.kind, normalized.default) == ("bool", True)
    assert (tint.kind, tint.default) == ("color", (0.25, 0.5, 1.0))
    assert brdf.uniforms == {"n": "float", "normalized": "bool", "tint": "vec3"}
    # The shader starts on the line after '::begin shader' (line 11), at column 1, and keeps '#' lines.
    assert (brdf.shader.line, brdf.shader.column) == (12, 1)
    lines = MULTI_LINE.splitlines()
    assert brdf.shader.text.splitlines() == lines[11:13]
    assert brdf.is_func is not None
    assert brdf.is_func.text.strip() == lines[16]
    assert brdf.is_func.line == 17


def test_hash_lines_inside_the_shader_are_kept_verbatim():
    text = MULTI_LINE.replace("// GLSL comments", "#define SCALE 2.0\n// GLSL comments")
    assert parse_brdf(text).shader.text.startswith("#define SCALE 2.0\n")


def test_one_line_form_reads_like_the_multi_line_form():
    one = read_brdf(EXAMPLES / "blinn_phong_gaussian_oneline.brdf")
    multi = read_brdf(EXAMPLES / "blinn_phong_gaussian.brdf")
    assert one.parameters == multi.parameters
    assert one.shader.text.split() == multi.shader.text.split()
    text = (EXAMPLES / "blinn_phong_gaussian_oneline.brdf").read_text()
    assert one.shader.line == 1
    # The shader starts mid-line, right after '::begin shader'.
    assert one.shader.column == text.index("::begin shader") + len("::begin shader") + 1
    assert text[one.shader.column - 1 :].startswith(one.shader.text)


@pytest.mark.skipif(SEED_003 is None, reason="seed articles not present next to the repository")
def test_one_line_example_is_the_seed_text_verbatim():
    seed = SEED_003.read_text(encoding="utf-8")
    quoted = re.search(r"analytic .*?::end shader", seed).group()
    assert (EXAMPLES / "blinn_phong_gaussian_oneline.brdf").read_text().strip() == quoted


def test_several_declarations_per_line_and_crlf_and_bom():
    text = "\ufeffanalytic\r\n::begin parameters\r\nfloat a 0 1 0.5 bool b 0 color c 1 1 1\r\n::end parameters\r\n"
    text += "::begin shader\r\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return c; }\r\n::end shader\r\n"
    brdf = parse_brdf(text)
    assert [p.name for p in brdf.parameters] == ["a", "b", "c"]
    assert "\r" not in brdf.shader.text
    assert brdf.shader.line == 6


def test_default_outside_slider_range_warns_with_location():
    text = "analytic\n::begin parameters\nfloat n 1 10 20\n::end parameters\n::begin shader\n::end shader\n"
    with pytest.warns(UserWarning, match=r"f\.brdf:3:14: .*DEFAULT 20 outside the slider range \[1, 10\]"):
        brdf = parse_brdf(text, "f.brdf")
    assert brdf.parameters[0].default == 20.0


def test_missing_file_and_directory():
    with pytest.raises(ModelNotFoundError, match="no-such.brdf"):
        read_brdf("no-such.brdf")
    with pytest.raises(BrdfFileError, match="directory") as info:
        read_brdf(EXAMPLES)
    assert info.value.path == str(EXAMPLES)


# -- the model ------------------------------------------------------------------------------------------
def test_model_facts():
    model = load_brdf(EXAMPLES / "cook_torrance.brdf")
    assert isinstance(model, BrdfModel) and isinstance(model, bn.Model)
    assert model.name == "cook_torrance"
    assert model.channels == 3 and model.isotropic is True  # Cook-Torrance ignores X and Y
    assert [p.name for p in model.parameters] == ["m", "f0", "include_F", "include_G"]
    assert model.params == {"m": 0.3, "f0": 0.04, "include_F": True, "include_G": True}
    assert model.source_path == str(EXAMPLES / "cook_torrance.brdf")
    assert model.has_is_func is False
    assert [p.name for p in load_brdf(EXAMPLES / "ggx.brdf").parameters][0] == "roughness"
    assert bn.load(str(EXAMPLES / "ggx.brdf")).name == "ggx"


def test_is_func_is_kept_but_never_compiled(tmp_path):
    path = tmp_path / "with_is_func.brdf"
    path.write_text(MULTI_LINE.replace("vec3 sample(vec2 u)", "this is not GLSL at all {"))
    model = load_brdf(path)
    assert model.has_is_func
    np.testing.assert_array_equal(model.eval([0, 0, 1.0], [0, 0, 1.0]), [25.0, 50.0, 100.0])


def power_rtol(n: float) -> float:
    """x^n has relative condition number n: the file and the built-in round N·H differently (≤ 2 ulps)."""
    return max(1e-12, 4 * n * 2.0**-53)


@pytest.mark.parametrize("n", [1.0, 32.0, 512.0, 1e4])
def test_blinn_phong_file_equals_the_builtin(pairs, n):
    L, V = pairs
    ours = load_brdf(EXAMPLES / "blinn_phong.brdf", n=n).eval(L, V)
    builtin = REGISTRY["blinn-phong"](n=n).eval(L, V)
    np.testing.assert_allclose(ours, np.repeat(builtin, 3, axis=-1), rtol=power_rtol(n), atol=0)


@pytest.mark.parametrize("name", ["blinn_phong_gaussian.brdf", "blinn_phong_gaussian_oneline.brdf"])
@pytest.mark.parametrize("n", [1.0, 100.0, 512.0])
def test_seed_003_shader_equals_the_builtin_gaussian(pairs, name, n):
    # exp(-x²) has relative condition number 2x², in the hundreds where the lobe is below 1e-100 of its
    # peak: there the comparison is absolute, at 1e-12 of the peak.
    L, V = pairs
    builtin = np.repeat(REGISTRY["blinn-phong-gaussian"](n=n).eval(L, V), 3, axis=-1)
    plain = load_brdf(EXAMPLES / name, n=n, normalized=0).eval(L, V)
    np.testing.assert_allclose(plain, builtin, rtol=1e-12, atol=1e-12 * builtin.max())
    scaled = load_brdf(EXAMPLES / name, n=n).eval(L, V)  # normalized=1 by default: the seed's linear fit
    factor = 0.17287429 + 0.01388682 * n
    np.testing.assert_allclose(scaled, builtin * factor, rtol=1e-12, atol=1e-12 * builtin.max() * factor)


def test_one_line_and_multi_line_files_evaluate_identically(pairs):
    L, V = pairs
    one = load_brdf(EXAMPLES / "blinn_phong_gaussian_oneline.brdf", n=37.5).eval(L, V)
    multi = load_brdf(EXAMPLES / "blinn_phong_gaussian.brdf", n=37.5).eval(L, V)
    np.testing.assert_array_equal(one, multi)


def test_overrides_bool_and_colour_like_the_command_line(pairs):
    L, V = pairs
    path = EXAMPLES / "disney_diffuse.brdf"
    default = load_brdf(path)
    assert default.params["baseColor"] == (0.82, 0.67, 0.16)
    grey = bn.load(str(path), baseColor="0.5,0.5,0.5").eval(L, V)
    # The lobe is linear in baseColor: every channel of the grey version is half the default's over its colour.
    expected = default.eval(L, V) / np.array([0.82, 0.67, 0.16]) * 0.5
    np.testing.assert_allclose(grey, expected, rtol=1e-13)
    assert load_brdf(path, baseColor=0.5).params["baseColor"] == (0.5, 0.5, 0.5)
    gaussian = EXAMPLES / "blinn_phong_gaussian.brdf"
    for off in (0, "0", False, "false"):
        assert load_brdf(gaussian, normalized=off).params["normalized"] is False


def test_values_outside_the_slider_range_warn_and_still_evaluate(pairs):
    L, V = pairs
    with pytest.warns(UserWarning, match="parameter n: value 20000 outside \\[1, 10000\\].*slider range"):
        model = load_brdf(EXAMPLES / "blinn_phong.brdf", n=20000.0)
    builtin = REGISTRY["blinn-phong"](n=20000.0).eval(L, V)
    np.testing.assert_allclose(model.eval(L, V)[..., :1], builtin, rtol=power_rtol(20000.0), atol=0)


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("n", "abc", "expected a number"),
        ("n", [1.0, np.nan], "must be finite"),
        ("normalized", 0.5, "expected 0 or 1"),
        ("normalized", "maybe", "expected 0 or 1"),
        ("undeclared", 1.0, "unknown parameter 'undeclared'"),
    ],
)
def test_wrong_parameter_types_are_refused(name, value, message):
    with pytest.raises(ParameterError, match=message):
        load_brdf(EXAMPLES / "blinn_phong_gaussian.brdf", **{name: value})


def test_wrong_colour_shape_is_refused():
    with pytest.raises(ParameterError, match="3 components"):
        load_brdf(EXAMPLES / "disney_diffuse.brdf", baseColor=(0.1, 0.2))


def test_parameter_arrays_broadcast_against_the_direction_batch(rng):
    # A sweep: float values (S, 1) against directions (S, T, 3), and colours (S, 1, 3), in one call.
    L = random_hemisphere(rng, 12).reshape(3, 4, 3)
    V = random_hemisphere(rng, 12).reshape(3, 4, 3)
    model = load_brdf(EXAMPLES / "disney_diffuse.brdf")
    roughness = np.array([0.0, 0.5, 1.0])[:, None]
    colours = np.array([[0.1, 0.2, 0.3], [1.0, 1.0, 1.0], [0.5, 0.0, 0.25]])[:, None, :]
    swept = model.evaluate(L, V, {"baseColor": colours, "roughness": roughness})
    assert swept.shape == (3, 4, 3)
    for s in range(3):
        one = model.with_params(roughness=float(roughness[s, 0]), baseColor=tuple(colours[s, 0])).eval(L[s], V[s])
        np.testing.assert_allclose(swept[s], one, rtol=1e-15)


def test_constant_shader_broadcasts_to_the_batch(rng):
    model = load_brdf(EXAMPLES / "lambert.brdf", reflectance=0.5)
    L = random_hemisphere(rng, 7)
    np.testing.assert_allclose(model.eval(L, L[::-1]), np.full((7, 3), 0.5 / np.pi), rtol=1e-15)
    swept = model.evaluate(L[None], L[None], {"reflectance": np.array([[0.25], [1.0]])})
    np.testing.assert_allclose(swept[:, 0, 0], [0.25 / np.pi, 1.0 / np.pi], rtol=1e-15)


def test_reciprocity_check_against_the_builtin_lobes():
    # The .brdf and the numpy built-in go through the same random pairs: same verdict, same number.
    phong_file = reciprocity_check(load_brdf(EXAMPLES / "phong.brdf", n=32), samples=2000, seed=3)
    phong_builtin = reciprocity_check(REGISTRY["phong"](n=32), samples=2000, seed=3)
    assert not phong_file.reciprocal
    assert phong_file.max_relative == pytest.approx(phong_builtin.max_relative, rel=1e-9)
    # f(L,V)/f(V,L) = (N·V)/(N·L) for the original Phong: the asymmetry is 1 - min/max of the cosines.
    L, V = phong_file.L, phong_file.V
    assert phong_file.max_relative == pytest.approx(1 - min(L[2], V[2]) / max(L[2], V[2]), rel=1e-9)
    assert reciprocity_check(load_brdf(EXAMPLES / "blinn_phong.brdf"), samples=2000).max_relative <= 1e-12
    assert reciprocity_check(load_brdf(EXAMPLES / "cook_torrance.brdf"), samples=2000).reciprocal


# -- albedo ---------------------------------------------------------------------------------------------
def _midpoint_albedo(model: bn.Model, theta: float, cells: int = 240) -> np.ndarray:
    """E(V) by a plain midpoint rule on a (θ_L, φ_L) grid: crude, but shares nothing with the integrator."""
    t = (np.arange(cells) + 0.5) * (np.pi / 2) / cells
    p = (np.arange(2 * cells) + 0.5) * (2 * np.pi) / (2 * cells)
    T, P = np.meshgrid(t, p, indexing="ij")
    L = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    V = np.array([np.sin(theta), 0.0, np.cos(theta)])
    f = model.eval(L, V)
    weight = (np.cos(T) * np.sin(T))[..., None] * (np.pi / 2 / cells) * (np.pi / cells)
    return np.sum(f * weight, axis=(0, 1))


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=[p.stem for p in EXAMPLE_FILES])
def test_every_example_integrates(path):
    model = load_brdf(path)
    result = bn.albedo(model, np.radians([0.0, 60.0]), rtol=1e-6)
    assert result.value.shape == (2, 3)
    assert np.all(np.isfinite(result.value)) and result.converged.all()
    for i, theta in enumerate(np.radians([0.0, 60.0])):
        # Discontinuous lobes (banded_specular) and the sharpest ones limit the crude rule to ~1e-3.
        np.testing.assert_allclose(result.value[i], _midpoint_albedo(model, theta), rtol=3e-3, atol=1e-6)


def test_blinn_phong_file_albedo_equals_the_builtin_to_1e_12():
    model = load_brdf(EXAMPLES / "blinn_phong.brdf")
    n = model.params["n"]
    at_normal = bn.albedo(model, 0.0, rtol=1e-12)
    assert at_normal.method == "quadrature"
    exact = float(closed_forms.blinn_phong_albedo_normal(n))
    np.testing.assert_allclose(at_normal.value[0], exact, rtol=1e-12)
    theta = np.radians([30.0, 60.0])
    ours = bn.albedo(model, theta, rtol=1e-12).value
    builtin = REGISTRY["blinn-phong"](n=n)
    for method in ("quadrature", "series"):  # the series is seed 002's form: no quadrature on the sphere
        expected = bn.albedo(builtin, theta, rtol=1e-12, method=method).value
        np.testing.assert_allclose(ours, np.repeat(expected, 3, axis=-1), rtol=1e-12)


@pytest.mark.parametrize("name", ["blinn_phong_gaussian.brdf", "blinn_phong_gaussian_oneline.brdf"])
def test_seed_003_albedo_at_normal_equals_the_builtin_to_1e_12(name):
    ours = bn.albedo(load_brdf(EXAMPLES / name, n=100, normalized=0), 0.0, rtol=1e-12)
    builtin = bn.albedo(REGISTRY["blinn-phong-gaussian"](n=100), 0.0, rtol=1e-12)
    np.testing.assert_allclose(ours.value[0], np.repeat(builtin.value[0], 3), rtol=1e-12)


# -- brdfnorm info --------------------------------------------------------------------------------------
runner = CliRunner()


def test_info_json_matches_the_file():
    path = EXAMPLES / "blinn_phong_gaussian.brdf"
    result = runner.invoke(app, ["info", str(path), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    declared = read_brdf(path).parameters
    assert [(p["name"], p["kind"], p["min"], p["max"], p["default"]) for p in data["parameters"]] == [
        (p.name, p.kind, p.minimum, p.maximum, p.default) for p in declared
    ]
    assert data["channels"] == 3 and data["isFunc"] is False
    assert data["reciprocity"]["reciprocal"] is True
    assert data["reciprocity"]["max_relative_asymmetry"] <= 1e-12


def test_info_reports_a_non_reciprocal_lobe_and_an_isfunc_section(tmp_path):
    result = runner.invoke(app, ["info", str(EXAMPLES / "phong.brdf"), "--json", "-p", "n=10"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["reciprocity"]["reciprocal"] is False
    assert data["parameters"][0]["value"] == 10.0
    worst_L, worst_V = np.array(data["reciprocity"]["worst_L"]), np.array(data["reciprocity"]["worst_V"])
    expected = 1 - min(worst_L[2], worst_V[2]) / max(worst_L[2], worst_V[2])
    assert data["reciprocity"]["max_relative_asymmetry"] == pytest.approx(expected, rel=1e-9)
    path = tmp_path / "sampled.brdf"
    path.write_text(MULTI_LINE)
    text = runner.invoke(app, ["info", str(path)])
    assert text.exit_code == 0, text.output
    assert "isFunc section: yes" in text.stdout
    assert "normalized" in text.stdout and "tint" in text.stdout and "reciprocal: yes" in text.stdout


def test_info_on_a_broken_file_is_one_line_with_the_location(tmp_path):
    path = tmp_path / "broken.brdf"
    path.write_text("analytic\n::begin parameters\nfloat n 1 2\n::end parameters\n")
    result = runner.invoke(app, ["info", str(path)])
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        f"error: {path}:3:1: malformed float parameter: expected 'float NAME MIN MAX DEFAULT', got 'float n 1 2'"
    ]


def test_info_with_warnings_for_out_of_range_values():
    result = runner.invoke(app, ["info", str(EXAMPLES / "blinn_phong.brdf"), "-p", "n=1e5"])
    assert result.exit_code == 0, result.output
    assert "warning: parameter n: value 100000 outside [1, 10000]" in result.stderr


def test_isotropy_is_detected_from_the_shader_at_the_bound_parameters():
    ward = bn.load(str(EXAMPLES / "ward_anisotropic.brdf"))
    assert not ward.isotropic
    assert ward.with_params(alpha_x=0.3, alpha_y=0.3).isotropic
    assert bn.load(str(EXAMPLES / "ggx.brdf")).isotropic
    # An isotropic file's albedo really is independent of φ (so the max search may skip φ).
    ggx = bn.load(str(EXAMPLES / "ggx.brdf"))
    values = bn.albedo(ggx, np.radians(50.0), np.radians([0.0, 77.0, 200.0]), rtol=1e-10).value[:, 0]
    np.testing.assert_allclose(values, values[0], rtol=1e-9)
