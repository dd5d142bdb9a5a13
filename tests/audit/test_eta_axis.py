"""brdfnorm audit (issue 42): 3-D rough-glass tables with η as an axis — Cycles' precompute layout (η from
F0 = t⁴ at nodes, light entering; and the same seen from inside, η → 1/η), channels R + T, R and T — the
refraction's shadowing and the η parametrization searched, with the other axes pinned (each glass cell is a
quadrature of ~10 ms, so a search over every 3-D geometry would take hours on two cores).

Tables are made by ``lut.compute`` over an ``eta`` axis; each finding is checked at its worst cell by the facet
reference of tests/helpers/dielectric_reference.py (nested scipy quadrature, sharing no code with brdfnorm's
integrators)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers.dielectric_reference import albedo_part
from helpers.paths import FIXTURES

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.audit import audit

pytestmark = pytest.mark.slow
N = 5
T = np.linspace(0.0, 1.0, N)
F0 = np.clip(T, 1e-4, 0.99) ** 4
ETA = np.maximum((1 + np.sqrt(F0)) / (1 - np.sqrt(F0)), 1 + 2e-6)  # Cycles' ior_from_F0, kept off 1


def _glass(eta: np.ndarray, form: str = "reflection-form") -> dict:
    model = bn.load("ggx-dielectric", refraction_shadowing=form)
    return lut.compute(model, {"eta": eta, "alpha": np.maximum(T * T, 1e-8), "mu": np.maximum(T, 1e-4)},
                       rtol=1e-9, average=False)


def _pins() -> dict:
    return {"pins": {"axes": "eta,alpha,mu"}, "direction": "mu-node", "roughness": "r2-node"}


def test_entering_r_plus_t_names_the_eta_layout_and_the_refraction_form():
    table = _glass(ETA)["E"]
    r = audit(table, bn.load("ggx-dielectric"), dense=False, sweep=False, **_pins())
    c = r.best.convention
    assert r.passes and c.meanings == ("E_glass",) and c.f0 == "eta-cycles" and c.f0_axis == 0
    assert c.shadowing == "height-correlated/refraction=reflection-form"
    assert not r.runners_up[0].clean
    fit = r.best.channels[0]
    i, j, k = fit.worst
    exact = sum(albedo_part("ggx", max(T[k], 1e-4), max(T[j] ** 2, 1e-8), ETA[i], part, "reflection-form")
                for part in "RT")
    assert abs(table[i, j, k] - exact) < 1e-6 and fit.worst_at["eta"] == pytest.approx(ETA[i])


def test_exiting_reflection_and_transmission_channels_and_a_wrong_cell(tmp_path, run_cli):
    parts = _glass(1.0 / ETA, "correlated-beta")
    data = np.stack([parts["E_R"], parts["E_T"]], axis=-1)
    data[3, 2, 1, 1] += 0.02  # one transmitted value 2 % off
    np.savez(tmp_path / "glass.npz", lut=data)
    code, out, err = run_cli("audit", str(tmp_path / "glass.npz"), "--model", "ggx-dielectric",
                             "--as", "axes=eta,alpha,mu", "--as", "direction=mu-node", "--as", "roughness=r2-node",
                             "--as", "shadowing=height-correlated", "--no-interpolation", "--no-sweep", "--json")
    result = json.loads(out)
    c = result["best"]["convention"]
    assert code == 1 and c["f0"] == "eta-cycles-exiting" and c["channels"] == ["R_glass", "T_glass"]
    assert c["axes"] == ["eta", "roughness (alpha = r^2)", "mu"]
    assert [tuple(x["index"]) for x in result["wrong_cells"]["1"]["cells"]] == [(3, 2, 1)]
    assert "0" not in result["wrong_cells"]
    cell = result["wrong_cells"]["1"]["cells"][0]
    exact = albedo_part("ggx", T[1], T[2] ** 2, 1.0 / ETA[3], "T", "correlated-beta")
    assert abs(cell["exact"] - exact) < 1e-6 and cell["at"]["eta"] == pytest.approx(1.0 / ETA[3])


def test_cycles_glass_table_excerpt_over_eta(run_cli):
    """Blender Cycles' table_ggx_glass_E (16³ over η, μ, roughness), a 4×4×4 excerpt (tests/fixtures/engines/
    README.md): η of slices z = 1, 3, 5, 8 (η = (1 + t²)/(1 − t²), t = z/15), μ and r at y, x = 0, 5, 10, 15 of 15,
    given with --axis. The audit names the reflection's form of the refraction's shadowing (as on the 2-D slice)
    and the table fits to its printing and sampling noise but for two cells, checked here by the facet reference."""

    path = FIXTURES / "engines" / "cycles_ggx_glass_E_3d_excerpt.h"
    t = np.array([1, 3, 5, 8]) / 15
    eta = (1 + t * t) / (1 - t * t)
    grid = ",".join(repr(float(v)) for v in np.array([0, 5, 10, 15]) / 15)
    code, out, err = run_cli("audit", str(path), "--model", "ggx-dielectric", "--axis",
                             "eta=" + ",".join(repr(float(v)) for v in eta), "--axis", f"mu={grid}", "--axis",
                             f"r={grid}", "--no-sweep", "--no-interpolation", "--json")
    result = json.loads(out)
    c = result["best"]["convention"]
    assert code == 1 and result["verdict"] == "fits"
    assert c["axes"] == ["eta", "mu", "alpha"] and c["shadowing"] == "height-correlated/refraction=reflection-form"
    fit = result["best"]["channels"][0]
    assert fit["within"] >= 60 and fit["median"] < 1e-6 and fit["max"] < 1e-5
    text = path.read_text()
    table = np.array([float(v.rstrip("f")) for v in text[text.index("= {"):].replace("{", " ").replace(
        "}", " ").replace("=", " ").replace(";", " ").replace(",", " ").split()]).reshape(4, 4, 4)
    for cell in result["wrong_cells"]["0"]["cells"]:
        i, j, k = cell["index"]
        exact = sum(albedo_part("ggx", max(j * 5 / 15, 1e-4), max((k * 5 / 15) ** 2, 1e-8), eta[i], part,
                                "reflection-form") for part in "RT")
        assert abs(cell["exact"] - exact) < 1e-6 and cell["stored"] == table[i, j, k]
