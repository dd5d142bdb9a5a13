"""brdfnorm audit (issue 29), slow tier: tables that engines really ship (tests/fixtures/engines/, sources and
licences in its README.md), audited end to end through the command line in a subprocess.

What each audit must find is what the table's own generator says (its fitting or baking code, cited in the
README): the convention is named, and the error it reports at the worst cell is checked against an independent
route — the exact value there by composite Gauss-Legendre over the half vector (tests.conftest), which shares no
code with brdfnorm's integrators — minus the table's value read back independently (numpy, not brdfnorm's reader).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.lut.table import split_sum_models
from tests.conftest import half_vector_gauss_legendre

pytestmark = pytest.mark.slow
ENGINES = Path(__file__).parent / "fixtures" / "engines"
GGX = bn.load("ggx")


def _audit(*argv: str) -> tuple[int, dict, str]:
    """``python -m brdfnorm audit ARGV --json`` in a subprocess (a fresh interpreter, as a user runs it)."""
    env = dict(os.environ)
    src = str(Path(__file__).parents[1] / "src")
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


def test_ltc_magnitude_table_64_js():
    """selfshadow/ltc_code's fit/results/ltc.js g_ltc_2 (the table three.js ships as LTC_MAT_2): channel 0 is the
    GGX albedo ("norm") that fitLTC.cpp integrates by 32×32 stratified samples per cell, at rows t = i/63,
    cos θ = 1 − t², θ ≤ 1.57 and columns r = a/63, α = max(r², 1e-5), height-correlated Smith (brdf_ggx.h)."""
    path = ENGINES / "ltc_2.js"
    code, r, _ = _audit(str(path), "--model", "ggx", "--shape", "64,64,4", "--channel", "0", "--no-sweep")
    best = r["best"]
    c = best["convention"]
    assert code == 1 and r["verdict"] == "no hypothesis fits"  # the albedo is off far beyond its storage step
    assert (c["direction"], c["roughness"], c["axes"][0], c["flipped"], c["shadowing"]) == (
        "ltc", "r2-node", "mu", [False, False], "height-correlated")
    (fit,) = best["channels"]
    assert fit["meaning"] == "E" and fit["worst_at"]["mu"] <= 1e-3  # the worst cell is at grazing
    assert 0.05 < fit["max"] < 0.13 and fit["median"] < 1e-3
    # the clamps of the fitting code pinned: the grazing row is still off by 6.5e-2 (the issue's ~6e-2)
    code, pinned, _ = _audit(str(path), "--model", "ggx", "--shape", "64,64,4", "--channel", "0", "--no-sweep",
                             "--as", f"mu_floor={float(np.cos(1.57))!r}", "--as", "alpha_floor=1e-5")
    (fit,) = pinned["best"]["channels"]
    assert code == 1 and pinned["best"]["convention"]["direction"] == "ltc"
    assert 0.06 < fit["max"] < 0.07 and fit["worst_cell"][0] == 63 and fit["median"] < 1e-3
    # independent route: the table's value at the worst cell minus the exact albedo there
    t, a = fit["worst_cell"]
    table = _numbers(path.read_text()).reshape(64, 64, 4)
    mu, alpha = max(1.0 - (t / 63) ** 2, np.cos(1.57)), max((a / 63) ** 2, 1e-5)
    assert fit["worst_at"]["mu"] == pytest.approx(mu) and fit["worst_at"]["alpha"] == pytest.approx(alpha)
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
    assert code == 1 and r["verdict"] == "no hypothesis fits"
    assert (c["axes"][0], c["direction"], c["roughness"], c["flipped"], c["shadowing"], c["channels"]) == (
        "mu", "mu-texel", "r2-texel", [False, False], "height-correlated", ["DFG_f0", "DFG_f90"])
    scale, bias = r["best"]["channels"]
    assert 0.01 < scale["max"] < 0.02 and scale["worst_at"]["mu"] < 0.05
    assert 3e-4 < bias["max"] < 1e-3 and bias["median"] < 2e-5
    assert r["interpolation"] and r["runners_up"] and not r["runners_up"][0]["fits"]
    table = _numbers(path.read_text()).reshape(16, 16, 2)
    models = split_sum_models(GGX)[0]
    for k, (fit, meaning) in enumerate(((scale, "DFG_f0"), (bias, "DFG_f90"))):
        i, j = fit["worst_cell"]
        mu, alpha = (i + 0.5) / 16, ((j + 0.5) / 16) ** 2
        assert fit["worst_at"]["mu"] == pytest.approx(mu) and fit["worst_at"]["alpha"] == pytest.approx(alpha)
        exact, error = _exact(models[meaning].with_params(alpha=alpha), mu)
        assert abs(table[i, j, k] - exact) == pytest.approx(fit["max"], abs=error + 2e-6)
