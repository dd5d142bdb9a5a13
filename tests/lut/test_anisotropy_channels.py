"""Anisotropic tables, issue #45 item 2: ``--channels dfg`` — the split-sum pair DFG_f0 = ∫ f cos (1 − (1 − V·H)⁵),
DFG_f90 = ∫ f cos (1 − V·H)⁵ of the compiled kernel against independent computations: brdfnorm's generic
microfacet route (numpy, the model's own Schlick Fresnel with (f0, f90) = (1, 0) and (0, 1)) at views, a seeded
Monte Carlo of the view-azimuth average, and the identity DFG_f0 + DFG_f90 = E; then every format and layout."""

from __future__ import annotations

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.engine.routes import anisotropic as kernel
from brdfnorm.errors import ArgumentError
from brdfnorm.lut import anisotropy, formats


@pytest.mark.parametrize(("mu", "phi_v", "ax", "ay"), [(0.5, 0.7, 1.0, 0.1), (0.2, 1.3, 0.2, 0.6),
                                                       (1.0, 0.0, 0.3, 0.05)])
def test_split_sum_terms_at_views_match_the_generic_route(mu, phi_v, ax, ay):
    white = kernel.albedo("ggx", "height-correlated", mu, ax, ay, phi_v, rtol=1e-9)
    for weight, (f0, f90) in (("f0", (1.0, 0.0)), ("f90", (0.0, 1.0))):
        value, error, _, converged = kernel.albedo("ggx", "height-correlated", mu, ax, ay, phi_v, rtol=1e-9,
                                                   weight=weight)
        model = bn.load("ggx").with_params(alpha_x=ax, alpha_y=ay, fresnel="schlick", f0=f0, f90=f90)
        reference = bn.albedo(model, np.arccos(mu), phi=phi_v, rtol=1e-9)
        assert converged[0] and 0 < value[0] < white[0][0]
        assert abs(value[0] - reference.value[0]) <= error[0] + reference.error[0], (weight, value, reference.value)
        assert error[0] <= 1e-9 * value[0] + 1e-15
    f0_part = kernel.albedo("ggx", "height-correlated", mu, ax, ay, phi_v, rtol=1e-9, weight="f0")
    f90_part = kernel.albedo("ggx", "height-correlated", mu, ax, ay, phi_v, rtol=1e-9, weight="f90")
    assert abs(f0_part[0][0] + f90_part[0][0] - white[0][0]) <= f0_part[1][0] + f90_part[1][0] + white[1][0]


def test_averaged_f90_term_against_seeded_monte_carlo():
    """φ_v ~ U[0, 2π), slopes from the Beckmann distribution, weight G2 (V·H)(1 − V·H)⁵/(V_z H_z); 5σ."""
    rng = np.random.default_rng(4545)
    mu, ax, ay, n = 0.3, 0.8, 0.15, 400_000
    phi_v = rng.uniform(0.0, 2 * np.pi, n)
    s, phi = np.sqrt(-np.log1p(-rng.uniform(0.0, 1.0, n))), rng.uniform(0.0, 2 * np.pi, n)
    H = np.stack([ax * s * np.cos(phi), ay * s * np.sin(phi), np.ones(n)], axis=-1)
    H /= np.linalg.norm(H, axis=-1, keepdims=True)
    V = np.stack([np.sqrt(1 - mu * mu) * np.cos(phi_v), np.sqrt(1 - mu * mu) * np.sin(phi_v), np.full(n, mu)], -1)
    vh = np.sum(V * H, axis=-1)
    L = 2 * vh[:, None] * H - V
    model = bn.load("beckmann").with_params(alpha_x=ax, alpha_y=ay)
    from brdfnorm.models.microfacet import shadowing_masking, smith_a2

    lam = model.distribution.smith_lambda
    with np.errstate(divide="ignore", invalid="ignore"):
        g2 = shadowing_masking("height-correlated", lam(smith_a2(L, ax, ay)), lam(smith_a2(V, ax, ay)))
        w = np.where(L[:, 2] > 0, g2 * vh * (1 - vh) ** 5 / (mu * H[:, 2]), 0.0)
    mean, sigma = w.mean(), w.std() / np.sqrt(n)
    value, error, _, converged = kernel.albedo("beckmann", "height-correlated", mu, ax, ay, rtol=1e-7, weight="f90")
    assert converged[0] and abs(value[0] - mean) <= 5 * sigma + error[0], (value[0], mean, sigma)
    assert sigma < 0.02 * mean  # the interval is tight enough to see a wrong weight (f90 is ~10% of E here)


@pytest.fixture(scope="module")
def dfg_table():
    axes = {"mu": [0.25, 1.0], "roughness": [0.5, 0.8], "anisotropy": [0.0, 0.8]}
    return anisotropy.compute(bn.load("ggx"), axes, anisotropy="burley", rtol=1e-5, channels=["dfg"])


def test_table_channels_are_the_kernels_and_sum_to_E(dfg_table):
    t = dfg_table
    for name in ("DFG_f0", "DFG_f90"):
        assert t[name].shape == t["E"].shape == (2, 2, 2) and t.table_axes[name] == ("mu", "roughness", "anisotropy")
    assert np.all(np.abs(t["DFG_f0"] + t["DFG_f90"] - t["E"]) <= t["DFG_f0_error"] + t["DFG_f90_error"]
                  + t["E_error"])
    ax, ay = anisotropy.PARAMETERIZATIONS["burley"](0.8 ** 2, 0.8)
    direct = kernel.albedo("ggx", "height-correlated", 0.25, ax, ay, rtol=1e-5, weight="f90")
    assert t["DFG_f90"][0, 1, 1] == direct[0][0]
    assert "averaged over phi_v" in t.meta["dfg"] and t.meta["unconverged"] == 0
    with pytest.raises(ArgumentError, match="channel"):
        anisotropy.compute(bn.load("ggx"), {"mu": [1.0], "alpha": [0.3], "anisotropy": [0.5]}, channels=["rgb"])


@pytest.mark.parametrize("fmt", ["npz", "json", "csv", "exr", "png", "h", "glsl", "hlsl"])
def test_every_format_reads_back(dfg_table, fmt, tmp_path):
    tables = ["E", "DFG_f0", "DFG_f90"]
    if fmt == "exr":
        pytest.importorskip("OpenEXR")
    path = lut.save(dfg_table, tmp_path / f"t.{fmt}", tables=tables)
    back = lut.load(path)
    for name in tables:
        if fmt == "png":
            tolerance = np.ptp(dfg_table[name]) / 131070 * (1 + 1e-9)
        else:
            tolerance = 0.0 if fmt in ("npz", "json", "csv") else 6e-8 * np.max(np.abs(dfg_table[name]))
        assert back[name].shape == dfg_table[name].shape
        assert np.max(np.abs(back[name] - dfg_table[name])) <= tolerance, (fmt, name)


def test_layouts_and_channel_names(dfg_table, tmp_path):
    pytest.importorskip("OpenEXR")
    for layout in ("axes", "x=roughness,y=mu,v=up", "x=mu,y=anisotropy"):
        spec = formats.layouts.parse(layout)
        back = lut.load(lut.save(dfg_table, tmp_path / "l.exr", layout=spec, channel_names="brdfnorm",
                                 tables=["E", "E_avg", "DFG_f0", "DFG_f90", "DFG_f90_error"]))
        assert np.max(np.abs(back["DFG_f90"] - dfg_table["DFG_f90"])) <= 6e-8, layout
        assert back["E_avg"].shape == dfg_table["E_avg"].shape


def test_cli_dfg_channels(run_cli, tmp_path):
    out = tmp_path / "dfg.exr"
    pytest.importorskip("OpenEXR")
    code, _, err = run_cli("lut", "ggx", "--anisotropy", "aspect", "--axis", "mu=0.5,1", "--axis", "alpha=0.4",
                    "--axis", "aspect=0.5,1", "--channels", "dfg", "--rtol", "1e-5", "-o", str(out))
    assert code == 0, err
    back = lut.load(out)
    direct = kernel.albedo("ggx", "height-correlated", 0.5, 0.8, 0.2, rtol=1e-5, weight="f0")
    assert abs(back["DFG_f0"][0, 0, 0] - direct[0][0]) <= 6e-8
    assert list(back) == ["E", "E_avg", "DFG_f0", "DFG_f90"]  # what an engine samples: R, G, B and E_avg's part
