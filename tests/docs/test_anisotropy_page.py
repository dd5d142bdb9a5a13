"""The numbers docs/anisotropy.md prints: cells of the geometric-mean audit recomputed (its exact side by the view
albedo's trapezoid over φ_v from brdfnorm's numpy half-vector route — another integrator), and the fitted α_eff:
its emitted code runs and agrees with the fit, and its stated maximum error is what the validation grid gives."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from helpers.paths import REPO

import brdfnorm as bn
from brdfnorm.engine.routes import anisotropic as kernel
from brdfnorm.lut import anisotropy_audit, anisotropy_fix

DOC = REPO / "docs" / "anisotropy.md"


def audit_rows(lobe: str) -> dict[tuple[float, float], list[str]]:
    text = DOC.read_text().split(f"**{lobe}**", 1)[1].split("\n\n", 2)[1]
    rows = {}
    for line in text.splitlines()[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows[(float(cells[0]), float(cells[1]))] = cells[2:]
    return rows


@pytest.mark.parametrize(("lobe", "aspect", "alpha"), [("ggx, height-correlated", 0.316, 0.3),
                                                       ("beckmann, separable", 0.5, 0.6),
                                                       ("ggx, separable", 0.1, 1.0)])
def test_audit_cells(lobe, aspect, alpha):
    name, shadowing = lobe.split(", ")
    a = math.sqrt(0.1) if aspect == 0.316 else aspect
    printed = audit_rows(lobe)[(aspect, alpha)]
    (row,) = anisotropy_audit.geometric_mean_audit(name, shadowing, [0.5], [a], [alpha], rtol=1e-7)
    assert abs(row.error - float(printed[1])) <= 6e-4
    low, high = (float(v) for v in printed[5].split("–"))
    assert abs(row.spread[0] - low) <= 6e-4 and abs(row.spread[1] - high) <= 6e-4
    (one,) = anisotropy_audit.geometric_mean_audit(name, shadowing, [1.0], [a], [alpha], rtol=1e-7)
    assert abs(one.turquin - float(printed[3])) <= 6e-4 and abs(one.kulla_conty - float(printed[4])) <= 6e-4
    # Ē at μ = 0.5 from the numpy half-vector route: 33 views, trapezoid in φ_v (E is smooth and periodic in it)
    model = bn.load(name).with_params(alpha_x=alpha / a, alpha_y=alpha * a, shadowing=shadowing)
    phi = np.linspace(0.0, np.pi / 2, 33)
    views = bn.albedo(model, np.full(phi.size, np.arccos(0.5)), phi, rtol=1e-8, method="microfacet").value[:, 0]
    mean = (views[0] / 2 + views[1:-1].sum() + views[-1] / 2) / 32
    assert abs(mean - row.exact) <= 1e-6


def test_the_issues_claim():
    (row,) = anisotropy_audit.geometric_mean_audit("ggx", "height-correlated", [1.0], [math.sqrt(0.1)],
                                                   [math.sqrt(0.1)], rtol=1e-9)
    assert abs(row.exact - 0.529432698036) < 1e-8 and abs(row.lookup - 0.8636884478) < 1e-8
    text = DOC.read_text()
    assert "0.864" in text and "0.529" in text and "0.613" in text and "0.666" in text
    assert round(row.turquin, 3) == 0.613 and round(row.kulla_conty, 3) == 0.666


def test_alpha_fix_small_grid_code_runs():
    fix = anisotropy_fix.fit_alpha_fix("ggx", degree=1, counts=(4, 4, 3), validation_counts=(5, 4, 3), rtol=1e-6)
    assert fix.max_error < fix.geometric_mean_error  # the fit improves on the geometric mean where it was fitted
    namespace: dict = {}
    exec(fix.emit("python"), namespace)  # noqa: S102 — our own generated code
    function = namespace["brdfnorm_ggx_alpha_eff"]
    mu, ax, ay = 0.4, 0.5, 0.1
    assert abs(function(mu, ax, ay) - float(fix(mu, ax, ay))) < 1e-12 * float(fix(mu, ax, ay)) + 1e-7
    for language in ("glsl", "hlsl", "c"):
        code = fix.emit(language)
        assert "brdfnorm_ggx_alpha_eff(" in code and f"{fix.max_error:.2g}" in code
    # The stated maximum: one validation point recomputed here
    at = fix.validation["worst_at"]
    ax, ay = at["alpha"] * math.exp(at["log_aspect"] / 2), at["alpha"] * math.exp(-at["log_aspect"] / 2)
    exact = kernel.albedo("ggx", "height-correlated", at["mu"], ax, ay, rtol=1e-8)[0][0]
    a_eff = float(fix(at["mu"], ax, ay))
    read = kernel.albedo("ggx", "height-correlated", at["mu"], a_eff, a_eff, 0.0, rtol=1e-8)[0][0]
    assert abs(abs(read - exact) - fix.max_error) <= 2e-6


def test_documented_fix_matches_its_code():
    text = DOC.read_text()
    block = re.search(r"```glsl\n(.*?)```", text, re.S).group(1)
    stated = float(re.search(r"Max \|E_iso\(mu, alpha_eff\) - E_avg_over_phi_v\| = ([0-9.e-]+)", block).group(1))
    assert f"max |ΔE| = {stated:g}" in text.replace("\u2009", "")  # the prose states the code's number
    assert "float brdfnorm_ggx_alpha_eff(float mu, float alpha_x, float alpha_y)" in block


@pytest.mark.slow
def test_cli_fit_anisotropic_fix(tmp_path, run_cli):
    out = tmp_path / "fix.hlsl"
    code, _, err = run_cli("fit", "beckmann", "--anisotropic-fix", "--emit", "hlsl", "-o", str(out))
    assert code == 0, err
    assert "alpha_eff" in err and "geometric mean" in err
    assert "brdfnorm_beckmann_alpha_eff" in out.read_text()
    code, _, err = run_cli("fit", "ggx", "-p", "fresnel=schlick", "--anisotropic-fix")
    assert code == 2 and "white" in err
