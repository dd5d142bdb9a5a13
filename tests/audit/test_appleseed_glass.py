"""appleseed's glass albedo tables (``g_glass_ggx_albedo_table``, ``g_glass_ggx_rcp_eta_albedo_table`` of
``renderer/modeling/bsdf/energycompensationtables.cpp``), an excerpt in tests/fixtures/engines/ (see the README there),
audited end to end through the command line in the layout appleseed's ``AlbedoTable3D`` reads them in
(``--as f0=eta-appleseed`` / ``eta-appleseed-exiting``).

What the generator (``GlassAlbedoTable`` in ``glassbsdf.cpp``) computes, per cell (η, roughness r = y/15, cos θ =
x/15): α = max(r², 0.001); 512 Hammersley points (i/512, radical inverse base 2) mapped to GGX visible normals
(Heitz 2017's sampling routine), each adding F·G2/G1 for the reflected and (1 − F)·G2/G1 for the refracted
direction, G2 = 1/(1 + Λ_V + Λ_L) for both; the mean clamped to 1; cos θ = 0 stored as 1. The averages are
min(2 Σ_x E_x (x/15) / 16, 1).

The findings, each checked by an independent route: the facet-normal quadrature of
tests/helpers/dielectric_reference.py (R + T, refraction shadowing in the reflection's form), and a numpy
re-expression of the generator's estimator written here from the description above (no brdfnorm code), which
reproduces the stored values to their printing and converges to the quadrature as its sample count grows — so the
deviations found are the generator's 512-sample error, not another lobe."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from helpers.dielectric_reference import albedo_part
from helpers.paths import FIXTURES

from brdfnorm.audit.conventions import Convention, role_value

FIXTURE = FIXTURES / "engines" / "appleseed_glass_ggx_albedo_excerpt.h"
#: the excerpt's slices, rows and columns: index 0, 5, 10, 15 of 16 (unit positions 0, 1/3, 2/3, 1); x all 16.
T = np.array([0, 5, 10, 15]) / 15
ETA_IN = 1.01 + T * (3.0 - 1.01)  # lerp(MinEta, MaxEta, z/15)
ETA_OUT = 1 / 3.0 + T * (1 / 1.01 - 1 / 3.0)  # lerp(1/MaxEta, 1/MinEta, z/15)
PINS = ("--as", "axes=eta,alpha,mu", "--as", "direction=mu-node", "--as", "roughness=r2-node",
        "--as", "alpha_floor=0.001")


def _array(name: str) -> np.ndarray:
    """The numbers of one initializer of the fixture, read with a regular expression (not brdfnorm's reader)."""
    text = FIXTURE.read_text()
    body = text[text.index(name + "["):]
    body = re.sub(r"//[^\n]*", "", body[body.index("{"):body.index("};")])
    return np.array([float(v) for v in re.findall(r"([0-9.]+)f", body)])


def _exact(mu: float, alpha: float, eta: float) -> float:
    return albedo_part("ggx", mu, alpha, eta, "R") + albedo_part("ggx", mu, alpha, eta, "T", "reflection-form")


def _lam(cos: np.ndarray, alpha: float) -> np.ndarray:
    c2 = cos * cos
    return (np.sqrt(1.0 + alpha * alpha * np.maximum(0.0, 1.0 - c2) / c2) - 1.0) / 2.0


def _estimate(eta: float, alpha: float, mu: float, n: int = 512) -> float:
    """appleseed's estimator of R + T (y up, V in the xy plane), in float64."""
    i = np.arange(n, dtype=np.uint64)
    s1 = np.zeros(n)
    for bit in range(32):  # the base-2 radical inverse
        s1 += ((i >> np.uint64(bit)) & np.uint64(1)) * 0.5 ** (bit + 1)
    s0 = i / n
    v = np.array([np.sqrt(1.0 - mu * mu), mu, 0.0])
    s = np.array([v[0] * alpha, v[1], 0.0])
    s /= np.linalg.norm(s)
    t1 = np.cross(s, [0.0, 1.0, 0.0]) if mu < 0.9999 else np.array([1.0, 0.0, 0.0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(t1, s)
    a = 1.0 / (1.0 + s[1])
    lower = s1 < a
    phi = np.where(lower, s1 / a * np.pi, np.pi + (s1 - a) / (1.0 - a) * np.pi)
    p1 = np.sqrt(s0) * np.cos(phi)
    p2 = np.sqrt(s0) * np.sin(phi) * np.where(lower, 1.0, s[1])
    h = p1[:, None] * t1 + p2[:, None] * t2 + np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))[:, None] * s
    m = np.stack([h[:, 0] * alpha, np.maximum(0.0, h[:, 1]), h[:, 2] * alpha], axis=1)
    m /= np.linalg.norm(m, axis=1)[:, None]
    c = np.clip(m @ v, -1.0, 1.0)
    rcp = 1.0 / eta
    sin2 = (1.0 - c * c) * rcp * rcp
    tir = sin2 > 1.0
    ct = np.where(tir, 0.0, np.sqrt(np.maximum(0.0, 1.0 - sin2)))
    rs = ((rcp * c - ct) / (rcp * c + ct)) ** 2
    rp = ((c - rcp * ct) / (c + rcp * ct)) ** 2
    F = np.where(tir, 1.0, (rs + rp) / 2.0)
    lv = _lam(np.array(mu), alpha)
    reflected = 2.0 * c[:, None] * m - v
    r = np.where(reflected[:, 1] > 0.0, F * (1.0 + lv) / (1.0 + lv + _lam(reflected[:, 1], alpha)), 0.0)
    refracted = (rcp * c - ct)[:, None] * m - rcp * v
    refracted /= np.linalg.norm(refracted, axis=1)[:, None]
    t = np.where(refracted[:, 1] <= 0.0, (1.0 - F) * (1.0 + lv) / (1.0 + lv + _lam(refracted[:, 1], alpha)), 0.0)
    return min(float(r.sum() + t.sum()) / n, 1.0)


def _audit(run_cli, array: str, layout: str) -> dict:
    code, out, err = run_cli("audit", str(FIXTURE), "--model", "ggx-dielectric", "--array", array, *PINS,
                             "--as", f"f0={layout}", "--no-sweep", "--no-interpolation", "--json")
    assert code == 1, err  # neither table passes
    return json.loads(out)


def test_appleseed_eta_layouts():
    """lerp(MinEta, MaxEta, t) entering; the rcp-eta table's own lerp(1/MaxEta, 1/MinEta, t), not 1/η of those."""
    t = np.array([0.0, 1 / 3, 2 / 3, 1.0])
    assert np.allclose(role_value(Convention(f0="eta-appleseed"), "eta", t), ETA_IN, rtol=1e-15)
    exiting = role_value(Convention(f0="eta-appleseed-exiting"), "eta", t)
    assert np.allclose(exiting, ETA_OUT, rtol=1e-15)
    assert exiting[0] == pytest.approx(1 / 3) and exiting[-1] == pytest.approx(1 / 1.01)
    assert abs(exiting[1] - 1 / ETA_IN[1]) > 0.04  # 0.5523 against 1/1.6733 = 0.5976


def test_stored_averages_follow_appleseeds_rule():
    """Every average of the excerpt is min(2 Σ_x E_x (x/15) / 16, 1) of its stored row, to the 6-decimal printing
    (this also checks the excerpt's transcription, row by row)."""
    x = np.arange(16) / 15
    for name, avg_name in (("g_glass_ggx_albedo_excerpt", "g_glass_ggx_average_albedo_excerpt"),
                           ("g_glass_ggx_rcp_eta_albedo_excerpt", "g_glass_ggx_rcp_eta_average_albedo_excerpt")):
        rows = _array(name).reshape(4, 4, 16)
        stored = _array(avg_name).reshape(4, 16)[:, [0, 5, 10, 15]]
        rule = np.minimum(2.0 * (rows * x).sum(-1) / 16, 1.0)
        assert np.abs(rule - stored).max() < 6e-7


@pytest.mark.slow
def test_entering_table_is_the_reflection_form_glass_with_its_512_sample_error(run_cli):
    result = _audit(run_cli, "g_glass_ggx_albedo_excerpt", "eta-appleseed")
    c = result["best"]["convention"]
    assert result["verdict"] == "no hypothesis fits"
    assert c["f0"] == "eta-appleseed" and c["channels"] == ["E_glass"]
    assert c["shadowing"] == "height-correlated/refraction=reflection-form"
    assert c["axes"] == ["eta", "roughness (alpha = r^2)", "mu"]
    fit = result["best"]["channels"][0]
    assert 80 <= fit["within"] <= 110 and 3e-4 < fit["median"] < 5e-4 and 1.0e-3 < fit["max"] < 1.3e-3
    assert result["runners_up"][0]["median"] > 2 * fit["median"]  # refraction G1·G1: 8.6e-4
    i, j, k = fit["worst_cell"]
    assert (i, j, k) == (2, 2, 1)
    stored = _array("g_glass_ggx_albedo_excerpt").reshape(4, 4, 16)[i, j, k]
    eta, alpha, mu = ETA_IN[i], T[j] ** 2, k / 15
    exact = _exact(mu, alpha, eta)
    assert stored - exact == pytest.approx(fit["max"], abs=2e-6)
    assert abs(_estimate(eta, alpha, mu) - stored) < 2e-6  # the generator's own estimate, as printed
    assert abs(_estimate(eta, alpha, mu, 65536) - exact) < 3e-5  # and it converges to the quadrature


@pytest.mark.slow
def test_exiting_table_fits_but_for_its_cos_theta_zero_column_and_two_noisy_cells(run_cli):
    result = _audit(run_cli, "g_glass_ggx_rcp_eta_albedo_excerpt", "eta-appleseed-exiting")
    c = result["best"]["convention"]
    assert result["verdict"] == "fits" and c["f0"] == "eta-appleseed-exiting"
    assert c["shadowing"] == "height-correlated/refraction=reflection-form" and c["channels"] == ["E_glass"]
    table = _array("g_glass_ggx_rcp_eta_albedo_excerpt").reshape(4, 4, 16)
    cells = {tuple(cell["index"]): cell for cell in result["wrong_cells"]["0"]["cells"]}
    grazing = {key for key in cells if key[2] == 0}
    assert len(grazing) == 13 and set(cells) - grazing == {(2, 1, 4), (2, 1, 7)}
    assert all(cells[key]["stored"] == 1.0 == table[key] for key in grazing)  # glassbsdf.cpp: cos θ = 0 → 1
    floor = c["mu_floor"]
    worst = cells[(3, 3, 0)]  # η = 1/1.01, r = 1: R + T at grazing is 0.023
    assert worst["exact"] == pytest.approx(_exact(floor, 1.0, ETA_OUT[3]), abs=1e-6) and worst["exact"] < 0.03
    for key in ((2, 1, 4), (2, 1, 7)):
        i, j, k = key
        exact = _exact(k / 15, T[j] ** 2, ETA_OUT[i])
        assert cells[key]["exact"] == pytest.approx(exact, abs=1e-6)
        assert 3.5e-3 < table[key] - exact < 5.5e-3
        assert abs(_estimate(ETA_OUT[i], T[j] ** 2, k / 15) - table[key]) < 2e-6
        assert abs(_estimate(ETA_OUT[i], T[j] ** 2, k / 15, 65536) - exact) < 5e-5


@pytest.mark.slow
def test_stored_average_albedo_is_high_by_its_quadrature_rule():
    """At η = 1.01 and 1/1.01, r = 1, the stored E_avg is 0.011 above 2∫E μ dμ (Gauss-Legendre over the facet
    quadrature); appleseed's rule applied to the exact E at its 16 nodes (E(0) = 1) accounts for all but ~5e-4."""
    x, w = np.polynomial.legendre.leggauss(24)
    mu, w = (x + 1) / 2, w / 2
    nodes = np.arange(16) / 15
    for eta, avg_name, z, expected in ((ETA_IN[0], "g_glass_ggx_average_albedo_excerpt", 0, 0.0109),
                                       (ETA_OUT[3], "g_glass_ggx_rcp_eta_average_albedo_excerpt", 3, 0.0110)):
        stored = _array(avg_name).reshape(4, 16)[z, 15]
        exact_avg = 2.0 * sum(wi * m * _exact(m, 1.0, eta) for m, wi in zip(mu, w, strict=True))
        assert stored - exact_avg == pytest.approx(expected, abs=3e-4)
        e = np.array([1.0] + [_exact(m, 1.0, eta) for m in nodes[1:]])
        rule = min(2.0 * float((e * nodes).sum()) / 16, 1.0)
        assert 0.0 < stored - rule < 7e-4 and rule - exact_avg > 0.0095


@pytest.mark.slow
def test_a_table_made_in_appleseeds_exiting_layout_is_named_in_it(tmp_path, run_cli):
    """R + T made by ``brdfnorm lut`` at appleseed's rcp-eta nodes (5 η, 3 roughness, 4 cos θ; α ≥ 1e-3), one cell
    made 1 % high: with ``f0=eta-appleseed-exiting`` pinned the table is named and exactly that cell listed (its
    exact value checked by the facet quadrature); pinned to the entering layout it does not fit."""
    import brdfnorm as bn
    from brdfnorm import lut

    t_eta, t_r, t_mu = np.linspace(0, 1, 5), np.linspace(0, 1, 3), np.linspace(0, 1, 4)
    eta = 1 / 3.0 + t_eta * (1 / 1.01 - 1 / 3.0)
    model = bn.load("ggx-dielectric", refraction_shadowing="reflection-form")
    table = lut.compute(model, {"eta": eta, "alpha": np.maximum(t_r**2, 1e-3), "mu": np.maximum(t_mu, 1e-4)},
                        rtol=1e-9, average=False)["E"]
    table[3, 1, 2] *= 1.01
    np.savez(tmp_path / "glass.npz", lut=table.astype(np.float32))
    runs = {}
    for layout in ("eta-appleseed-exiting", "eta-appleseed"):
        code, out, err = run_cli("audit", str(tmp_path / "glass.npz"), "--model", "ggx-dielectric", *PINS,
                                 "--as", "shadowing=height-correlated/refraction=reflection-form",
                                 "--as", f"f0={layout}", "--no-sweep", "--no-interpolation", "--json")
        runs[layout] = (code, json.loads(out))
    code, result = runs["eta-appleseed-exiting"]
    assert code == 1 and result["verdict"] == "fits"
    cells = result["wrong_cells"]["0"]["cells"]
    assert [tuple(c["index"]) for c in cells] == [(3, 1, 2)]
    exact = _exact(2 / 3, 0.25, eta[3])
    assert cells[0]["exact"] == pytest.approx(exact, abs=1e-6) and cells[0]["at"]["eta"] == pytest.approx(eta[3])
    code, result = runs["eta-appleseed"]
    assert code == 1 and result["verdict"] == "no hypothesis fits"
