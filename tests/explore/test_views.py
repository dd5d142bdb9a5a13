"""brdfnorm explore's views beyond one lobe at φ_o = 0, without a browser: the controls the catalog assigns
(numbers per channel for η, k, f0), each model listed once, the view azimuth φ_o, the raw f beside the normalized
lobe, and a second lobe overlaid — each against an independent route (the model evaluated directly,
``brdfnorm.albedo`` at (θ_o, φ_o), ``brdfnorm.normalize``, a scalar η per channel)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers.paths import REPO

pytest.importorskip("starlette", reason="the explore extra (starlette, uvicorn, watchfiles) is not installed")
httpx = pytest.importorskip("httpx", reason="httpx is not installed")

import brdfnorm as bn  # noqa: E402
from brdfnorm.errors import ArgumentError, ParameterError  # noqa: E402
from brdfnorm.explore import Catalog, background  # noqa: E402
from brdfnorm.explore.compute import bind_parameters, evaluate_view  # noqa: E402

ROOT = REPO
GGX = ROOT / "examples" / "ggx.brdf"


@pytest.fixture(scope="module")
def server_url():
    with background(Catalog.build([str(GGX), "phong"])) as url:
        yield url


def post(url: str, path: str, body) -> httpx.Response:
    return httpx.post(url + path.lstrip("/"), content=json.dumps(body), timeout=60,
                      headers={"Content-Type": "application/json"})


def view_request(**overrides) -> dict:
    return {"model": "arg0", "params": {"roughness": 0.4}, "view": 20.0, "convention": "normal",
            "quality": "coarse", "client": "test", "generation": 1, **overrides}


def test_each_model_is_listed_once():
    """A model given on the command line (as README's ``brdfnorm explore examples/ggx.brdf``) replaces its
    example or built-in entry; a model given twice is one entry."""
    catalog = Catalog.build([str(GGX), str(GGX.parent / ".." / "examples" / GGX.name), "phong", "ggx", "phong"])
    entries = catalog.entries()
    ids = [e.id for e in entries]
    assert ids[:3] == ["arg0", "arg1", "arg2"] and "arg3" not in ids
    assert "example:ggx.brdf" not in ids and "builtin:phong" not in ids and "builtin:ggx" not in ids
    sources = [e.source for e in entries]
    assert len(sources) == len(set(sources))
    shown = [(e.group, e.label) for e in entries]
    assert len(shown) == len(set(shown))
    assert {e.source for e in Catalog.build([]).entries()} == set(sources)  # nothing lost


def test_eta_k_f0_are_numbers_per_channel_not_colours():
    from brdfnorm.explore.catalog import control_of
    from brdfnorm.explore.compute import describe_parameters
    from brdfnorm.parameters import Parameter

    controls = {p["name"]: p["control"] for p in describe_parameters(bn.load("ggx"))}
    assert [controls[n] for n in ("eta", "k", "f0", "f90")] == ["channels"] * 4
    assert controls["alpha"] == "slider" and controls["fresnel"] == "menu"
    def control(example: str, name: str) -> str:
        described = describe_parameters(bn.load(str(ROOT / "examples" / example)))
        return next(p["control"] for p in described if p["name"] == name)

    assert control("disney_diffuse.brdf", "baseColor") == "colour"  # a colour stays a colour picker
    assert control("anisotropic_ggx.brdf", "F0") == "channels"
    # A per-channel numeric kind (as parameters.py is about to declare) gets numbers, scalar or not.
    assert control_of(Parameter("eta", "channels", 1.5, 1e-3, 1e3)) == "channels"  # type: ignore[arg-type]
    assert control_of(Parameter("ms_table", "int", 32, 0, 1024)) == "slider"  # type: ignore[arg-type]
    ggx = bn.load("ggx", fresnel="dielectric")
    assert bind_parameters(ggx, {"eta": 1.5}).params["eta"] == (1.5, 1.5, 1.5)  # settable (a picker tops at 1)
    f0 = 0.0123456789
    assert bind_parameters(ggx, {"f0": [f0, 0.5, 1.0]}).params["f0"] == (f0, 0.5, 1.0)  # not 8-bit steps
    with pytest.raises(ParameterError, match="eta"):
        bind_parameters(ggx, {"eta": [1.5, 1.5]})
    with pytest.raises(ParameterError, match="eta"):
        bind_parameters(ggx, {"eta": [1.5, 0.0, 1.5]})  # below its range
    # Per channel: each channel of the readout is the albedo at that channel's η alone (a scalar η, bound as
    # the command line binds it).
    data = evaluate_view(ggx, 30.0, "normal", "coarse", params={"eta": [1.33, 1.5, 1.7]})
    readout = data["readouts"]["albedo"]
    for c, eta in enumerate((1.33, 1.5, 1.7)):
        single = bn.albedo(bn.load("ggx", fresnel="dielectric", eta=f"{eta}"), math.radians(30.0), rtol=1e-8)
        assert abs(readout["value"][c] - single.value[c]) <= readout["error"][c] + single.error[c]


def test_view_azimuth_turns_the_plane_and_the_raw_lobe_is_f():
    """φ_o: the albedo at (θ_o, φ_o) of an anisotropic lobe, and both lobes drawn in the plane of N and V."""
    model = bn.load("ggx", alpha_x=0.1, alpha_y=0.5)
    data = evaluate_view(model, 60.0, "normal", "coarse", phi_deg=90.0)
    reference = bn.albedo(model, math.radians(60.0), math.radians(90.0), rtol=1e-9)
    readout = data["readouts"]["albedo"]
    assert abs(readout["value"][0] - reference.value[0]) <= readout["error"][0] + reference.error[0]
    across = bn.albedo(model, math.radians(60.0), 0.0, rtol=1e-9).value[0]
    assert abs(across - reference.value[0]) > 100 * (readout["error"][0] + reference.error[0])  # φ_o matters
    alpha = data["readouts"]["factor_normal"]["value"][0]
    t = np.radians(np.array(data["lobe"]["t_deg"]))
    L = np.stack([np.zeros_like(t), np.sin(t), np.cos(t)], axis=-1)  # φ = 90°: the Y–N plane
    V = np.array([0.0, math.sin(math.radians(60.0)), math.cos(math.radians(60.0))])
    f = model.eval(L, V)[:, 0]
    np.testing.assert_allclose(data["lobe"]["raw"], np.where(np.cos(t) > 0, f, 0.0), rtol=1e-9, atol=1e-300)
    np.testing.assert_allclose(data["lobe"]["r"], np.where(np.cos(t) > 0, alpha * f * np.cos(t), 0.0),
                               rtol=1e-9, atol=1e-300)
    np.testing.assert_allclose(data["surface"]["view"], V, atol=1e-15)
    from brdfnorm.explore.compute import view_azimuth

    assert view_azimuth(None) == 0.0 and view_azimuth(360) == 360.0
    for bad in (400.0, -1.0, "90", float("nan")):
        with pytest.raises(ArgumentError):
            view_azimuth(bad)


def test_the_overlay_is_a_second_lobe_under_the_same_convention(server_url):
    """The overlay's lobe is α₂·f₂·(N·L) with α₂ = 1/E₂(N) from brdfnorm.normalize, in the same plane."""
    body = view_request(client="overlay", view=40.0, phi=30.0,
                        overlay={"model": "arg1", "params": {"n": 30.0}})
    response = post(server_url, "api/evaluate", body)
    assert response.status_code == 200, response.text
    data = response.json()
    second = data["overlay"]
    assert second["label"] == "phong"
    phong = bn.load("phong", n=30.0)
    alpha = float(bn.normalize(phong, at="normal", rtol=1e-10).factor[0, 0, 0])
    assert abs(second["factor"]["value"][0] - alpha) <= 1e-6 * alpha
    t = np.radians(np.array(second["lobe"]["t_deg"]))
    phi, theta = math.radians(30.0), math.radians(40.0)
    L = np.stack([np.sin(t) * math.cos(phi), np.sin(t) * math.sin(phi), np.cos(t)], axis=-1)
    V = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
    f = phong.eval(L, V)[:, 0]
    np.testing.assert_allclose(second["lobe"]["r"], np.where(np.cos(t) > 0, alpha * f * np.cos(t), 0.0),
                               rtol=1e-5, atol=1e-300)
    # The first lobe is unchanged by the overlay.
    alone = post(server_url, "api/evaluate", view_request(client="overlay", generation=2, view=40.0, phi=30.0))
    assert alone.json()["lobe"] == data["lobe"] and alone.json()["overlay"] is None
    for overlay, status in (({"model": "nope"}, 404), ({"model": "arg1", "params": {"n": -1}}, 400), ([1], 400)):
        bad = post(server_url, "api/evaluate", view_request(client="overlay", generation=3, overlay=overlay))
        assert bad.status_code == status, bad.text
    refused = post(server_url, "api/evaluate", view_request(client="overlay", generation=3,
                                                            overlay={"model": "arg1", "params": {"n": -1}}))
    assert refused.json()["error"].startswith("second lobe (phong): parameter n: ")
    assert post(server_url, "api/evaluate", view_request(client="overlay", generation=4, phi=-1)).status_code == 400
