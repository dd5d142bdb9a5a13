"""brdfnorm audit (issue 29), slow tier: tables that engines really ship (tests/fixtures/engines/, sources and
licences in its README.md), audited end to end through the command line in a subprocess.

What each audit must find is what the table's own generator says (its fitting or baking code, cited in the
README): the convention is named, and the error it reports at the worst cell is checked against an independent
route — the exact value there by composite Gauss-Legendre over the half vector (helpers/references.py), which shares no
code with brdfnorm's integrators — minus the table's value (the text tables read back by numpy, not brdfnorm's
reader; the PNG by brdfnorm's reader).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from helpers.paths import FIXTURES, SRC
from helpers.references import half_vector_gauss_legendre

import brdfnorm as bn
from brdfnorm.lut.table import split_sum_models

pytestmark = pytest.mark.slow
ENGINES = FIXTURES / "engines"
GGX = bn.load("ggx")


def _audit(*argv: str) -> tuple[int, dict, str]:
    """``python -m brdfnorm audit ARGV --json`` in a subprocess (a fresh interpreter, as a user runs it)."""
    env = dict(os.environ)
    src = str(SRC)
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    done = subprocess.run([sys.executable, "-m", "brdfnorm", "audit", *argv, "--json"], capture_output=True,
                          text=True, env=env, timeout=600)
    assert done.returncode in (0, 1), done.stderr
    return done.returncode, json.loads(done.stdout), done.stderr


def _numbers(text: str) -> np.ndarray:
    """The numbers of the (only) array literal in ``text``, parsed by a regular expression and numpy."""
    body = text[text.index("[") + 1:text.rindex("]")]
    body = re.sub(r"//[^\n]*", "", body)
    tokens = [t for t in re.split(r"[\s,]+", body) if t]
    if tokens[0].startswith("0x"):
        return np.array([int(t, 16) for t in tokens], dtype=np.uint16).view(np.float16).astype(float)
    return np.array([float(t) for t in tokens])


def _exact(model, mu: float) -> tuple[float, float]:
    """The value at μ and an error estimate: the change from the next coarser rule (grazing cells converge
    slowly)."""
    V = np.array([np.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    fine = float(half_vector_gauss_legendre(model, V, 64, 256))
    return fine, abs(fine - float(half_vector_gauss_legendre(model, V, 48, 128)))


def test_ltc_magnitude_table_js():
    """selfshadow/ltc_code's fit/results/ltc.js g_ltc_2 (the table three.js ships as LTC_MAT_2), kept as an
    excerpt: every 7th row and column of the 64×64×4 table (tests/fixtures/engines/README.md), itself an LTC
    layout of 10 nodes. Channel 0 is the GGX albedo ("norm") that fitLTC.cpp integrates by 32×32 stratified samples
    per cell, at rows t = i/63, cos θ = 1 − t², θ ≤ 1.57 and columns r = a/63, α = max(r², 1e-5), height-correlated
    Smith (brdf_ggx.h)."""
    path = ENGINES / "ltc_2_excerpt.js"
    code, r, _ = _audit(str(path), "--model", "ggx", "--shape", "10,10,4", "--channel", "0", "--no-sweep")
    best = r["best"]
    c = best["convention"]
    # the albedo is off far beyond its storage step at grazing cells: named from the others, those cells listed
    assert code == 1 and r["verdict"] == "fits" and not r["passes"]
    listed = {tuple(c["index"]) for c in r["wrong_cells"]["0"]["cells"]}
    assert {(9, a) for a in range(1, 10)} <= listed  # the grazing row (θ = 1.57), every roughness but α = 0
    assert tuple(best["channels"][0]["worst_cell"]) in listed
    assert (c["direction"], c["roughness"], c["axes"][0], c["flipped"], c["shadowing"]) == (
        "ltc", "r2-node", "mu", [False, False], "height-correlated")
    (fit,) = best["channels"]
    assert fit["meaning"] == "E" and fit["worst_at"]["mu"] <= 1e-3  # the worst cell is at grazing
    assert 0.04 < fit["max"] < 0.13 and fit["median"] < 1e-3
    # the clamps of the fitting code pinned: the grazing row is still off by 6.5e-2 (the issue's ~6e-2)
    code, pinned, _ = _audit(str(path), "--model", "ggx", "--shape", "10,10,4", "--channel", "0", "--no-sweep",
                             "--as", f"mu_floor={float(np.cos(1.57))!r}", "--as", "alpha_floor=1e-5")
    (fit,) = pinned["best"]["channels"]
    assert code == 1 and pinned["best"]["convention"]["direction"] == "ltc"
    assert 0.06 < fit["max"] < 0.07 and fit["worst_cell"][0] == 9 and fit["median"] < 1e-3
    # independent route: the table's value at the worst cell minus the exact albedo there
    t, a = fit["worst_cell"]
    table = _numbers(path.read_text()).reshape(10, 10, 4)
    mu, alpha = max(1.0 - (t / 9) ** 2, np.cos(1.57)), max((a / 9) ** 2, 1e-5)
    # the position as the table stores it: cos θ = 1 − (t/9)² (before the θ ≤ 1.57 clamp) and r = a/9
    assert fit["worst_at"]["mu"] == pytest.approx(1.0 - (t / 9) ** 2) and fit["worst_at"]["r"] == pytest.approx(a / 9)
    exact, error = _exact(GGX.with_params(alpha=alpha), mu)
    assert abs(table[t, a, 0] - exact) == pytest.approx(fit["max"], abs=error + 1e-6)


def test_three_dfg_lut_16_half_js():
    """three.js's DFGLUTData.js: a 16×16 RG16F table (scale, bias), 4 096 samples per texel, stored as half-float
    bit patterns in a Uint16Array. The audit names its convention — rows μ and columns roughness at texel centres,
    α = r², height-correlated Smith, channels (DFG_f0, DFG_f90) — and measures its error: the scale is off by
    1.4e-2 at grazing, beyond its half-float step and its sampling noise, so nothing fits."""
    path = ENGINES / "three_dfg_lut.js"
    code, r, _ = _audit(str(path), "--model", "ggx", "--dtype", "float16", "--shape", "16,16,2", "--no-sweep")
    c = r["best"]["convention"]
    assert code == 1 and r["verdict"] == "fits" and not r["passes"]  # named; its grazing cells listed
    assert (c["axes"][0], c["direction"], c["roughness"], c["flipped"], c["shadowing"], c["channels"]) == (
        "mu", "mu-texel", "r2-texel", [False, False], "height-correlated", ["DFG_f0", "DFG_f90"])
    assert tuple(r["best"]["channels"][0]["worst_cell"]) in {tuple(x["index"]) for x in r["wrong_cells"]["0"]["cells"]}
    scale, bias = r["best"]["channels"]
    assert 0.01 < scale["max"] < 0.02 and scale["worst_at"]["mu"] < 0.05
    assert 3e-4 < bias["max"] < 1e-3 and bias["median"] < 2e-5
    assert r["interpolation"] and r["runners_up"] and r["runners_up"][0]["within"] < r["best"]["within"]
    table = _numbers(path.read_text()).reshape(16, 16, 2)
    models = split_sum_models(GGX)[0]
    for k, (fit, meaning) in enumerate(((scale, "DFG_f0"), (bias, "DFG_f90"))):
        i, j = fit["worst_cell"]
        mu, alpha = (i + 0.5) / 16, ((j + 0.5) / 16) ** 2
        assert fit["worst_at"]["mu"] == pytest.approx(mu) and fit["worst_at"]["r"] ** 2 == pytest.approx(alpha)
        exact, error = _exact(models[meaning].with_params(alpha=alpha), mu)
        assert abs(table[i, j, k] - exact) == pytest.approx(fit["max"], abs=error + 2e-6)


def _ue4_estimate(mu: float, r: float, n: int = 400_000) -> tuple[float, float]:
    """(scale, bias) by brdfgen.jl's estimator (UE4's IBL: GGX importance sampling with α = r², Schlick-GGX
    G1 = c/(c(1 − k) + k), k = α/2, separable), with many more samples than the table's 1 000."""
    a, k = r * r, r * r / 2
    u1, u2 = (np.arange(n) + 0.5) / n, np.random.default_rng(1).random(n)
    phi, ct = 2 * np.pi * u1, np.sqrt((1 - u2) / (1 + (a * a - 1) * u2))
    st = np.sqrt(1 - ct * ct)
    H = np.stack([st * np.cos(phi), st * np.sin(phi), ct], -1)
    V = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
    vh = H @ V
    nl = (2 * vh[:, None] * H - V)[:, 2]
    g1 = lambda c: c / (c * (1 - k) + k)  # noqa: E731
    weight = np.where(nl > 0, g1(mu) * g1(np.maximum(nl, 1e-12)) * vh / (ct * mu), 0.0)
    fc = (1 - vh) ** 5
    return float(np.mean((1 - fc) * weight)), float(np.mean(fc * weight))


def test_brdfgen_png_lut_excerpt():
    """4DA/brdfgen's brdfLUT.png (512×512 RGB, 16-bit; R scale, G bias, B 0; rows roughness r, columns μ, both at
    texel centres of 512): every 32nd texel from the 16th, so its axes are given with --axis. The table is UE4's
    split sum with Schlick-GGX shadowing k = α/2, which is none of brdfnorm's Smith forms: the audit says no
    hypothesis fits, names the axes (rows roughness) and the closest shadowing, separable (what k = α/2
    approximates), and the error it measures is the table's; the table itself is the generator's estimator (checked
    here with 400× its samples), so the misfit is the shadowing's, not the reading's."""
    path = ENGINES / "brdfgen_lut_excerpt.png"
    grid = "0.0302734375:0.9677734375:16"  # (32 i + 15.5)/512, i = 0..15
    code, r, _ = _audit(str(path), "--model", "ggx", "--axis", f"r={grid}", "--axis", f"mu={grid}", "--as",
                        "channels=DFG_f0,DFG_f90,-", "--no-sweep")
    best = r["best"]
    c = best["convention"]
    assert code == 1 and r["verdict"] == "no hypothesis fits"
    assert c["axes"][0] == "alpha" and c["shadowing"] == "separable" and c["channels"][:2] == ["DFG_f0", "DFG_f90"]
    scale, bias = best["channels"]
    assert 0.1 < scale["max"] < 0.2 and 0.1 < bias["max"] < 0.25
    from brdfnorm.audit.readers import read_table

    values = read_table(path).values
    for fit, k in ((scale, 0), (bias, 1)):
        i, j = fit["worst_cell"]
        rough, mu = (32 * i + 15.5) / 512, (32 * j + 15.5) / 512
        assert fit["worst_at"]["mu"] == pytest.approx(mu) and fit["worst_at"]["alpha"] == pytest.approx(rough**2)
        separable = split_sum_models(GGX.with_params(shadowing="separable"))[0]
        exact, error = _exact(separable["DFG_f0" if k == 0 else "DFG_f90"].with_params(alpha=rough**2), mu)
        assert abs(values[i, j, k] - exact) == pytest.approx(fit["max"], abs=error + 1e-5)
        assert values[i, j, k] == pytest.approx(_ue4_estimate(mu, rough)[k], abs=1e-2)


def test_cycles_ggx_albedo_c_header_32():
    """Blender Cycles' table_ggx_E (shader.tables, a C header of 32×32 floats printed to 6 decimals): the audit
    names μ at nodes i/31 and roughness at nodes with α = r², height-correlated Smith, and it fits to the printing:
    max 9.9e-7 (half the last printed digit is 5e-7, plus the reference's error). A C header of a real engine,
    though 2-D and float: no 32³ uint16 header was found (docs/audit.md)."""
    path = ENGINES / "cycles_ggx_E.h"
    code, r, _ = _audit(str(path), "--model", "ggx", "--shape", "32,32", "--no-sweep")
    c = r["best"]["convention"]
    assert code == 0 and r["verdict"] == "fits" and not r["ambiguous"]
    assert (c["axes"][0], c["direction"], c["roughness"], c["flipped"], c["shadowing"], c["channels"]) == (
        "mu", "mu-node", "r2-node", [False, False], "height-correlated", ["E"])
    (fit,) = r["best"]["channels"]
    assert fit["max"] < 1.5e-6 and not r["runners_up"][0]["fits"]
    text = path.read_text()
    body = text[text.index("{") + 1:text.rindex("}")]
    table = np.array([float(t.rstrip("f")) for t in re.split(r"[\s,]+", body) if t]).reshape(32, 32)
    i, j = fit["worst_cell"]
    mu, alpha = max(i / 31, 1e-4), max((j / 31) ** 2, 1e-8)
    assert fit["worst_at"]["mu"] == pytest.approx(i / 31) and fit["worst_at"]["r"] == pytest.approx(j / 31)
    exact, error = _exact(GGX.with_params(alpha=alpha), mu)
    assert abs(table[i, j] - exact) == pytest.approx(fit["max"], abs=error + 1e-8)
    assert abs(table[i, j] - exact) <= 5e-7 + 5e-7  # the printing's half digit and the reference's share


#: Cycles' glass slice z = 8 of 16: ior = ior_from_F0((8/15)⁴) (cycles_precompute.cpp).
CYCLES_ETA = (1 + (8 / 15) ** 2) / (1 - (8 / 15) ** 2)


def test_cycles_glass_slice_names_the_reflection_form_of_refraction_shadowing():
    """One η slice of Blender Cycles' table_ggx_glass_E (E = R + T of its GGX glass, 2²³ samples a cell): with
    η given and the sample positions pinned to its generator's (μ and roughness at nodes i/15, α = r²), the audit
    finds the refraction's shadowing to be the reflection's 1/(1 + Λ_V + Λ_L) — the form the issue says Cycles'
    glass uses — and the table fits to its sampling noise; with Heitz's Beta form (brdfnorm's default) pinned, the
    closest hypothesis (ranked by its median) misses by 0.86."""
    path = ENGINES / "cycles_ggx_glass_E_slice.h"
    common = (str(path), "--model", "ggx-dielectric", "-p", f"eta={CYCLES_ETA!r}", "--shape", "16,16", "--as",
              "direction=mu-node", "--as", "roughness=r2-node", "--no-sweep", "--no-interpolation")
    code, r, _ = _audit(*common)
    c = r["best"]["convention"]
    assert code == 0 and (c["axes"][0], c["flipped"], c["shadowing"]) == (
        "mu", [False, False], "height-correlated/refraction=reflection-form")
    (fit,) = r["best"]["channels"]
    assert fit["max"] < 2e-5 and fit["median"] < 2e-6
    code, beta, _ = _audit(*common, "--as", "shadowing=height-correlated")
    assert code == 1 and 0.6 < beta["best"]["channels"][0]["max"] < 0.9
    # independent route at the worst cell of the Beta form: the facet reference's R + T (nested scipy quad)
    from helpers.dielectric_reference import albedo_part

    text = path.read_text()
    body = text[text.index("{") + 1:text.rindex("}")]
    table = np.array([float(t.rstrip("f")) for t in re.split(r"[\s,]+", body) if t]).reshape(16, 16)
    worst = beta["best"]["channels"][0]
    y, x = worst["worst_cell"]  # array indices; worst_at: where the Beta form's best geometry puts that cell
    at = worst["worst_at"]  # as the table stores it: r (α = r²) or α
    alpha = at["alpha"] if "alpha" in at else max(at["r"] ** 2, 1e-8)
    exact = sum(albedo_part("ggx", max(at["mu"], 1e-4), alpha, CYCLES_ETA, part) for part in "RT")
    assert abs(table[y, x] - exact) == pytest.approx(worst["max"], abs=1e-6)
    # and at the reflection form's worst cell (rows μ = y/15, columns α = (x/15)², floors 1e-4 and 1e-8)
    y, x = fit["worst_cell"]
    mu, alpha = max(y / 15, 1e-4), max((x / 15) ** 2, 1e-8)
    exact = sum(albedo_part("ggx", mu, alpha, CYCLES_ETA, part, refraction="reflection-form") for part in "RT")
    assert abs(table[y, x] - exact) == pytest.approx(fit["max"], abs=1e-7)


def _moonray(name: str) -> np.ndarray:
    """Array ``name`` of the MoonRay excerpt, read by a regular expression and numpy (rows roughness, 33 × 33)."""
    text = (ENGINES / "moonray_reflection_albedo.h").read_text()
    start = text.index(f"::{name}[")
    body = text[text.index("{", start) + 1:text.index("};", start)]
    return np.array([float(t.rstrip("f")) for t in re.split(r"[\s,]+", body) if t])


@pytest.mark.parametrize("array, model", [("mGGXE", "ggx"), ("mBeckmannE", "beckmann")])
def test_moonray_reflection_albedo_c_header(array, model):
    """DreamWorks MoonRay's ReflectionAlbedo.h (Apache-2.0): E(cos θ, roughness) of its Cook-Torrance lobes, 33×33
    floats (5 decimals) declared ``const float ReflectionAlbedo::mGGXE[COMP*COMP]`` (a qualified name and a size
    expression: the shape is given). Its accessor reads row ⌊r·32⌋ and column ⌈cos θ·32⌉, so rows are the roughness
    and columns μ = j/32. The audit names rows r with α = r², columns μ at nodes, separable Smith, E — ranked by the
    median residual, as the table is Monte-Carlo noise at most cells but zero in its whole μ = 0 column (the exact
    albedo there is 0.6 to 1) and biased at μ = 1/32. Both findings are checked by Gauss-Legendre."""
    lobe = bn.load(model).with_params(shadowing="separable")
    code, r, _ = _audit(str(ENGINES / "moonray_reflection_albedo.h"), "--array", array, "--shape", "33,33",
                        "--model", model, "--no-sweep", "--no-interpolation")
    c = r["best"]["convention"]
    assert code == 1 and r["verdict"] == "no hypothesis fits"
    assert (c["axes"], c["flipped"], c["direction"], c["roughness"], c["shadowing"], c["channels"]) == (
        ["roughness (alpha = r^2)", "mu"], [False, False], "mu-node", "r2-node", "separable", ["E"])
    (fit,) = r["best"]["channels"]
    assert fit["median"] < 5e-3 and fit["max"] == pytest.approx(1.0, abs=1e-6) and fit["worst_cell"][1] == 0
    table = _moonray(array).reshape(33, 33)
    assert np.all(table[:, 0] == 0.0)
    # the zeroed column: the exact albedo at grazing views (μ = 1e-4, the convention's clamp) is above 0.6 on every
    # row (0.61 for GGX at α = 1 with separable shadowing, 0.93 at α = 1/16)
    for row in (8, 16, 32):
        exact, error = _exact(lobe.with_params(alpha=(row / 32) ** 2), 1e-4)
        assert exact > 0.6 and error < 1e-3
    # the bias at μ = 1/32: GGX's worst cell off the zeroed column (row 10, α = (10/32)²) is low by 0.089
    if model == "ggx":
        exact, error = _exact(lobe.with_params(alpha=(10 / 32) ** 2), 1 / 32)
        assert 0.08 < exact - table[10, 1] < 0.1 and error < 1e-4
