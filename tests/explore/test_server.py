"""brdfnorm explore without a browser: the numbers it computes (against independent routes), the server's
behaviour under malformed requests, live reload of a watched file, and the command line (Ctrl-C included)."""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
from helpers.paths import REPO

pytest.importorskip("starlette", reason="the explore extra (starlette, uvicorn, watchfiles) is not installed")
httpx = pytest.importorskip("httpx", reason="httpx is not installed")

from helpers.references import phong_like_reference  # noqa: E402

import brdfnorm as bn  # noqa: E402
from brdfnorm.errors import ArgumentError, ParameterError  # noqa: E402
from brdfnorm.explore import Catalog, background  # noqa: E402
from brdfnorm.explore.compute import (  # noqa: E402
    Superseded,
    Verdicts,
    bind_parameters,
    cancellable,
    energy_check,
    evaluate_view,
    factor_bound,
    fit_factor,
    format_with_error,
)
from brdfnorm.output.formats import format_error, round_up  # noqa: E402

ROOT = REPO
GGX = ROOT / "examples" / "ggx.brdf"


def shown_value_and_unit(text: str) -> tuple[float, float]:
    """The number before ' ± ' and the unit of its last digit."""
    number = text.split(" ± ")[0]
    return float(number), float(10.0 ** Decimal(number).as_tuple().exponent)


# -- numbers as text ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("value, error, expected", [
    (0.0396320723966, 2.5e-11, "0.03963207240 ± 3e-11"),  # digits down to the error's first one (1e-11)
    (25.23209302, 6.1e-10, "25.2320930200 ± 7e-10"),  # trailing zeros are digits shown
    (1.0, 0.0, "1"),
    (1.0, 0.04, "1.00 ± 0.04"),
    (1.306817421213e-5, 1e-17, "1.306817421213e-05 ± 1e-17"),
    (0.5, 0.3, "0.5 ± 0.3"),
])
def test_format_with_error(value, error, expected):
    assert format_with_error(value, error) == expected


@pytest.mark.parametrize("error", [2.5e-11, 1e-3, 9.99e-7, 1.0000001e-5, 3e-300])
def test_shown_error_is_never_smaller_than_the_estimate(error):
    shown = round_up(error)
    assert shown >= error and shown <= 10 * error
    assert float(f"{shown:.1g}") >= error


@pytest.mark.parametrize("error, digits, expected", [
    (2.46e-9, 1, "3e-09"), (1.111e-10, 2, "1.2e-10"), (3e-10, 1, "3e-10"), (1.2345e-9, 3, "1.24e-09"),
    (9.981e-7, 3, "9.99e-07"), (9.991e-7, 3, "1e-06"), (5.0, 3, "5"),
])
def test_errors_are_shortened_upwards(error, digits, expected):
    assert format_error(error, digits) == expected
    assert float(format_error(error, digits)) >= error * (1 - 1e-15)


def test_factor_error_bound_holds_over_the_whole_interval():
    E, err = np.array([0.04, 0.5, 1.0]), np.array([1e-3, 1e-2, 0.3])
    factor, bound = factor_bound(E, err)
    for true_E in (E - err, E + err, E - 0.5 * err):
        assert np.all(np.abs(1.0 / true_E - factor) <= bound * (1 + 1e-12))
    assert np.isinf(factor_bound(np.array([0.1]), np.array([0.2]))[1][0])


# -- the view's numbers against independent routes -------------------------------------------------------------

def test_blinn_phong_readouts_match_the_closed_form_at_normal_incidence():
    n = 64.0
    data = evaluate_view(bn.load("blinn-phong", n=n), 0.0, "normal", "fine")
    closed = 8 * math.pi * (2 ** (-n / 2) + n) / ((n + 2) * (n + 4))  # seed 000, at L = N
    value, unit = shown_value_and_unit(data["readouts"]["albedo"]["text"])
    assert abs(value - closed) <= unit
    factor, unit = shown_value_and_unit(data["readouts"]["factor_normal"]["text"])
    assert abs(factor - 1 / closed) <= unit
    assert data["readouts"]["energy"]["verdict"] == "conserves energy"


@pytest.mark.parametrize("quality", ["coarse", "fine"])
def test_phong_albedo_at_the_view_matches_a_one_dimensional_reference(quality):
    n, view = 20.0, 40.0
    data = evaluate_view(bn.load("modified-phong", n=n), view, "max", quality)
    reference = phong_like_reference(n, math.radians(view), original=False)
    readout = data["readouts"]["albedo"]
    assert abs(readout["value"][0] - reference) <= readout["error"][0] + 1e-14
    value, unit = shown_value_and_unit(readout["text"])
    assert abs(value - reference) <= unit + readout["error"][0]
    # The curve's band holds the reference at its own grid points too.
    curve = data["curve"]
    for theta, E, err in list(zip(curve["theta_deg"], curve["value"][0], curve["error"][0], strict=True))[::10]:
        assert abs(E - phong_like_reference(n, math.radians(theta), original=False)) <= err + 1e-14


@pytest.mark.slow
def test_coarse_max_factor_is_an_upper_bound_and_the_fine_one_is_searched():
    model = bn.load(str(GGX), roughness=0.3)
    coarse = evaluate_view(model, 30.0, "max", "coarse")
    fine = evaluate_view(model, 30.0, "max", "fine")
    reference = bn.normalize(model, at="max", rtol=1e-9)
    true_factor = float(reference.factor[0, 0, 0])
    assert coarse["readouts"]["factor_max"]["text"].startswith("≤ ")
    assert float(coarse["readouts"]["factor_max"]["text"].split()[1]) >= true_factor * (1 - 1e-6)
    value, unit = shown_value_and_unit(fine["readouts"]["factor_max"]["text"])
    assert abs(value - true_factor) <= unit + fine["readouts"]["factor_max"]["error"][0]
    # The normalized curve under 'max' never exceeds 1 beyond its error: that is what the factor means.
    assert max(fine["curve"]["normalized"][0]) <= 1 + 1e-7


def test_lobe_plot_is_the_normalized_projected_brdf():
    model = bn.load("blinn-phong", n=1e4)  # a lobe about half a degree wide
    data = evaluate_view(model, 50.0, "normal", "coarse")
    alpha = data["readouts"]["factor_normal"]["value"][0]
    t = np.radians(np.array(data["lobe"]["t_deg"]))
    L = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
    V = np.array([math.sin(math.radians(50)), 0.0, math.cos(math.radians(50))])
    expected = alpha * model.eval(L, V)[:, 0] * np.cos(t)
    np.testing.assert_allclose(data["lobe"]["r"], expected, rtol=1e-9, atol=0)  # t went through degrees
    # The peak (at the mirror direction, t = −50°) is sampled: the plotted maximum is within 1e-3 of it.
    peak = alpha * model.eval(np.array([-V[0], 0, V[2]]), V)[0] * V[2]
    assert max(data["lobe"]["r"]) >= peak * (1 - 1e-3)


def test_cancellation_stops_a_running_view_at_the_next_integrand_batch():
    calls = []

    def check():
        calls.append(1)
        if len(calls) > 3:
            raise Superseded

    with pytest.raises(Superseded):
        evaluate_view(bn.load(str(GGX)), 30.0, "max", "fine", check)
    assert len(calls) == 4  # no evaluation after the check failed


def test_cancellation_reaches_into_the_energy_check():
    """The check searches copies of the page's model (``with_params``): they keep the cancellation hook."""
    calls = []

    def check():
        calls.append(1)
        if len(calls) > 5:
            raise Superseded

    with pytest.raises(Superseded):
        energy_check(cancellable(bn.load(str(GGX)), check), str(GGX))
    assert len(calls) == 6


def shown_check(text: str) -> tuple[str, float, float, str]:
    """(status, max E, its error, direction text) from the energy readout's text."""
    status, rest = text.split(" — ", 1)
    numbers = rest.split("max E = ", 1)[1]
    value, error_and_where = numbers.split(" ± ", 1)
    error, where = error_and_where.split(" at ", 1)
    return status, value, float(error), where.split(";")[0]


@pytest.mark.slow
@pytest.mark.parametrize("path, params, expected_status", [
    (GGX, {"roughness": 0.3}, "pass"),
    (ROOT / "examples" / "blinn_phong_gaussian.brdf", {"n": 100.0, "normalized": True}, "fail"),  # ~0.66 % gained
    (ROOT / "examples" / "anisotropic_ggx.brdf", {"alpha_x": 0.2}, "pass"),  # φ searched too
])
def test_energy_readout_is_what_brdfnorm_check_prints(path, params, expected_status, run_cli):
    """The fine pass's energy readout against the command line's ``check --json`` (arguments built here, not
    taken from the page): same verdict, max E to the digits shown, an error never smaller, the same direction."""
    model = bn.load(str(path))
    fine = evaluate_view(model, 30.0, "normal", "fine", params=params, source=str(path))["readouts"]["energy"]
    bound = model.with_params(**params)
    held = []
    for p in bound.parameters:
        value = bound.params[p.name]
        text = (("1" if value else "0") if p.kind == "bool" else
                ",".join(repr(float(c)) for c in value) if p.kind == "color" else repr(float(value)))
        held += ["-p", f"{p.name}={text}"]
    argv = ["check", str(path), "--only", "energy", *held, "--budget", "2e7evals"]
    assert fine["command"] == " ".join(["brdfnorm", *argv])
    code, out, err = run_cli(*argv, "--json")
    assert code == (1 if expected_status == "fail" else 0), err
    cli = json.loads(out)["reports"][0]["checks"]["energy"]
    status, value, error, where = shown_check(fine["text"])
    assert status == fine["status"] == cli["status"] == expected_status
    assert abs(Decimal(value) - Decimal(repr(cli["value"]))) <= Decimal(10) ** Decimal(value).as_tuple().exponent / 2
    assert cli["error_estimate"] <= error <= 10 * cli["error_estimate"]
    assert where.startswith(f"θ_o = {cli['theta_deg']:.4g}°")
    assert ("φ_o" in where) == (not model.isotropic)
    if not model.isotropic:
        assert where.endswith(f"φ_o = {cli['phi_deg']:.4g}°")
    # The coarse pass only says what the albedo grid shows: a pending verdict (certain only when it gains).
    coarse = evaluate_view(model, 30.0, "normal", "coarse", params=params)["readouts"]["energy"]
    assert coarse["source"] == "grid" and coarse["status"] is None
    assert coarse["verdict"] == ("gains energy" if expected_status == "fail" else "pending")


def test_a_view_angle_move_reuses_the_energy_verdict_of_the_same_lobe(monkeypatch):
    import brdfnorm.explore.compute as compute

    runs = []
    real = compute.check_model
    monkeypatch.setattr(compute, "check_model", lambda *args, **kwargs: runs.append(1) or real(*args, **kwargs))
    verdicts, model = Verdicts(), bn.load("blinn-phong")
    first = evaluate_view(model, 10.0, "normal", "fine", params={"n": 40.0}, verdicts=verdicts, model_key=("m", 0))
    again = evaluate_view(model, 70.0, "max", "fine", params={"n": 40.0}, verdicts=verdicts, model_key=("m", 0))
    assert len(runs) == 1 and again["readouts"]["energy"]["cached"] and not first["readouts"]["energy"]["cached"]
    assert again["readouts"]["energy"]["text"] == first["readouts"]["energy"]["text"]
    evaluate_view(model, 70.0, "max", "fine", params={"n": 41.0}, verdicts=verdicts, model_key=("m", 0))
    evaluate_view(model, 70.0, "max", "fine", params={"n": 40.0}, verdicts=verdicts, model_key=("m", 1))  # reloaded
    assert len(runs) == 3


def test_parameters_from_the_page_are_checked_by_kind():
    ggx = bn.load(str(GGX))
    with pytest.raises(ParameterError, match="roughness"):
        bind_parameters(ggx, {"roughness": "0.5"})
    with pytest.raises(ParameterError, match="unknown parameter"):
        bind_parameters(ggx, {"nope": 1})
    with pytest.raises(ParameterError):
        bind_parameters(ggx, {"roughness": 10**400})
    with pytest.raises(ParameterError):
        bind_parameters(bn.load("blinn-phong"), {"n": -1.0})  # a hard range
    with pytest.raises(ArgumentError):
        bind_parameters(ggx, [1, 2])
    assert bind_parameters(ggx, {"roughness": 0.5}).params["roughness"] == 0.5


def test_choice_parameters_become_menus_and_are_checked():
    from brdfnorm.explore.compute import describe_parameters

    model = bn.load("ggx")
    described = {p["name"]: p for p in describe_parameters(model)}
    assert described["fresnel"]["kind"] == "choice" and "schlick" in described["fresnel"]["choices"]
    slider = described["alpha"]["slider"]
    assert slider["log"] and slider["high"] == 100.0 and slider["low"] == pytest.approx(1e-4)
    schlick = bind_parameters(model, {"fresnel": "schlick", "f0": [0.5, 0.5, 0.5]})
    assert schlick.params["fresnel"] == "schlick"
    with pytest.raises(ParameterError, match="fresnel"):
        bind_parameters(model, {"fresnel": "glass"})
    with pytest.raises(ParameterError, match="fresnel"):
        bind_parameters(model, {"fresnel": 1})
    data = evaluate_view(model, 30.0, "normal", "coarse", params={"fresnel": "schlick", "f0": [0.5, 0.5, 0.5]})
    reference = bn.albedo(schlick, math.radians(30.0), rtol=1e-6)
    readout = data["readouts"]["albedo"]
    assert abs(readout["value"][0] - reference.value[0]) <= readout["error"][0] + reference.error[0]


def test_fit_panel_code_reproduces_the_exact_factor():
    model = bn.load("blinn-phong-gaussian")
    result = fit_factor(model, "n", 10.0, 200.0, 12, "normal", "glsl", "log")
    assert "float brdfnorm_blinn_phong_gaussian_norm(float n)" in result["code"]
    exact = 1.0 / bn.albedo(model.with_params(n=57.0), 0.0).value[0]
    # The same formula through the Python emitter, evaluated away from the samples.
    from brdfnorm.fit import fit
    from brdfnorm.fit.codegen import emit

    values = np.geomspace(10.0, 200.0, 12)
    factors = 1.0 / bn.albedo(model.with_params(n=values), 0.0).value[:, 0]
    fitted = fit(values, factors, form=result["form"], metric="minimax-rel", names=("n", "t"))
    namespace: dict = {}
    exec(emit(fitted, "python", "m"), namespace)  # noqa: S102 — our own emitted code
    assert abs(namespace["brdfnorm_m_norm"](57.0) / exact - 1) < 5 * result["max_rel_error"] + 1e-3
    with pytest.raises(ArgumentError):
        fit_factor(model, "n", 10.0, 200.0, 1000, "normal", "glsl")


# -- the server --------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def server_url():
    with background(Catalog.build([str(GGX), "phong"])) as url:
        yield url


def post(url: str, path: str, body) -> httpx.Response:
    data = body if isinstance(body, (bytes, str)) else json.dumps(body)
    return httpx.post(url + path.lstrip("/"), content=data, timeout=60, headers={"Content-Type": "application/json"})


def view_request(**overrides) -> dict:
    return {"model": "arg0", "params": {"roughness": 0.4}, "view": 20.0, "convention": "normal",
            "quality": "coarse", "client": "test", "generation": 1, **overrides}


def test_catalog_names_models_by_id_only(server_url):
    catalog = httpx.get(server_url + "api/models").json()["models"]
    ids = [m["id"] for m in catalog]
    assert ids[:2] == ["arg0", "arg1"] and "builtin:lambert" in ids
    assert "example:ggx.brdf" not in ids and "builtin:phong" not in ids  # given: listed once, as given
    assert catalog[0]["watched"] and not catalog[1]["watched"]
    for bad in ("../../etc/passwd", "/etc/passwd", str(GGX)):
        response = post(server_url, "api/evaluate", view_request(model=bad))
        assert response.status_code == 404 and "unknown model id" in response.json()["error"]
    assert httpx.get(server_url + "static/..%2F..%2Fcatalog.py").status_code == 404
    assert httpx.get(server_url + "static/catalog.py").status_code == 404


def test_server_survives_malformed_requests(server_url):
    generation = iter(range(100, 10_000))

    def bad(**overrides) -> str:
        return json.dumps(view_request(**{"generation": next(generation), **overrides}))

    cases = [
        (b"{not json", 400), (b"[1, 2]", 400), (b"\xff\xfe", 400), (b"9" * 5000, 400),
        (bad(view=1e300), 400), (bad(view="30"), 400), (bad(params={"roughness": 1e308}), 400),
        (bad(params={"roughness": [0.1] * 10}), 400), (bad(params={"f0": {"$ne": 1}}), 400),
        (bad(convention="sideways"), 400), (bad(quality="best"), 400), (bad(generation="x"), 400),
        (bad(client=""), 400), (b"[" * 100_000 + b"]" * 100_000, 413),
    ]
    for body, status in cases:
        response = post(server_url, "api/evaluate", body)
        assert response.status_code == status, (body[:80], response.text)
        assert "error" in response.json()
    fits = [{"parameter": "roughness", "low": 0.1, "high": 1.0, "samples": 10**9, "at": "normal", "language": "glsl"},
            {"parameter": "roughness", "low": 1.0, "high": 0.1, "samples": 8, "at": "normal", "language": "glsl"},
            {"parameter": "roughness", "low": 0.1, "high": 1.0, "samples": 8, "at": "max", "language": "rust"},
            {"parameter": "roughness", "low": 0.1, "high": 1.0, "samples": 8, "at": "normal", "language": "glsl",
             "form": "x" * 1000},
            {"parameter": "../f0", "low": 0.1, "high": 1.0, "samples": 8, "at": "normal", "language": "glsl"}]
    for fit in fits:
        response = post(server_url, "api/fit", {"model": "arg0", "client": "c", "generation": next(generation), **fit})
        assert response.status_code == 400 and "error" in response.json(), (fit, response.text)
    # Raw junk on the socket, and a request cut off mid-body.
    host, port = server_url.split("//")[1].rstrip("/").split(":")
    for junk in (b"\x00\x01\x02 garbage\r\n\r\n", b"POST /api/evaluate HTTP/1.1\r\nContent-Length: 500\r\n\r\n{\"a"):
        with socket.create_connection((host, int(port)), timeout=5) as raw:
            raw.sendall(junk)
    response = post(server_url, "api/evaluate", view_request(generation=next(generation)))
    assert response.status_code == 200 and response.json()["readouts"]["albedo"]["text"]


def test_a_client_that_disconnects_mid_update_does_not_hurt(server_url):
    host, port = server_url.split("//")[1].rstrip("/").split(":")
    body = json.dumps(view_request(quality="fine", client="leaver", params={"roughness": 0.05})).encode()
    head = f"POST /api/evaluate HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n" \
           f"Content-Length: {len(body)}\r\n\r\n".encode()
    with socket.create_connection((host, int(port)), timeout=5) as raw:
        raw.sendall(head + body)
        time.sleep(0.2)  # the fine pass is running
    response = post(server_url, "api/evaluate", view_request(client="stayer"))
    assert response.status_code == 200


def test_a_newer_generation_supersedes_the_running_one(server_url):
    import concurrent.futures

    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        slow = pool.submit(post, server_url, "api/evaluate",
                           view_request(client="mover", generation=1, quality="fine", convention="max",
                                        params={"roughness": 0.02}))
        time.sleep(0.3)
        # Another tab's coarse pass does not queue behind this refinement (it runs in its own lane).
        other = post(server_url, "api/evaluate", view_request(client="other tab", generation=1))
        assert other.status_code == 200 and not slow.done()
        fast = pool.submit(post, server_url, "api/evaluate", view_request(client="mover", generation=2))
        assert fast.result().status_code == 200
        assert slow.result().status_code == 409 and slow.result().json() == {"stale": True}
    assert post(server_url, "api/evaluate", view_request(client="mover", generation=1)).status_code == 409


def test_server_energy_verdict_is_the_checks_and_kept_across_view_moves(server_url):
    def energy(generation: int, view: float, **params) -> dict:
        response = post(server_url, "api/evaluate", view_request(
            model="arg1", client="verdicts", generation=generation, quality="fine", view=view, params=params))
        assert response.status_code == 200, response.text
        return response.json()["readouts"]["energy"]

    first, moved = energy(1, 20.0, n=20.0), energy(2, 60.0, n=20.0)
    assert first["source"] == "check" and not first["cached"] and moved["cached"]
    assert moved["text"] == first["text"] and moved["value"] == first["value"]
    from brdfnorm.check import Budget, check

    expected = check(bn.load("phong", n=20.0), checks=("energy",), fixed="all",
                     budget=Budget(seconds=None, evaluations=20_000_000)).results["energy"]
    assert first["value"] == [expected.value] and first["error"] == [expected.error]
    assert first["status"] == expected.status == "pass"
    assert not energy(3, 60.0, n=21.0)["cached"]


def test_only_loopback_addresses_count_as_local():
    from brdfnorm.explore.server import is_loopback

    assert all(is_loopback(h) for h in ("127.0.0.1", "localhost", "::1", "[::1]", "127.0.0.2"))
    assert not any(is_loopback(h) for h in ("0.0.0.0", "::", "192.168.1.2", "example.com"))


def test_other_sites_cannot_make_the_server_compute(server_url):
    body = json.dumps(view_request(client="site", generation=1))
    as_form = httpx.post(server_url + "api/evaluate", content=body, headers={"Content-Type": "text/plain"})
    assert as_form.status_code == 415  # what a cross-site page can send without a preflight
    foreign = httpx.post(server_url + "api/evaluate", content=body,
                         headers={"Content-Type": "application/json", "Origin": "https://attacker.example"})
    assert foreign.status_code == 403
    own = httpx.post(server_url + "api/evaluate", content=body,
                     headers={"Content-Type": "application/json", "Origin": server_url.rstrip("/")})
    assert own.status_code == 200


def test_dns_rebinding_is_refused(server_url):
    assert httpx.get(server_url, headers={"Host": "attacker.example"}).status_code == 400
    page = httpx.get(server_url)
    assert page.status_code == 200 and 'data-testid="view-angle"' in page.text
    assert "script-src 'self'" in page.headers["content-security-policy"]
    assert httpx.get(server_url + "static/plotly-basic.min.js").status_code == 200


def test_assets_are_gzipped_hashed_and_cached(server_url):
    """The page names each asset by its content hash; the asset comes gzipped (decompressing to the file on
    disk), cached for a year under that hash, revalidated by ETag otherwise."""
    import gzip
    import hashlib
    import re

    static = ROOT / "src" / "brdfnorm" / "explore" / "static"
    page = httpx.get(server_url).text
    first = httpx.get(server_url + "api/models").json()["models"][0]["id"]
    assert f'data-first-model="{first}"' in page  # the page asks for its first view before the catalog comes
    for name in ("app.js", "plots.js", "style.css", "plotly-basic.min.js"):
        on_disk = (static / name).read_bytes()
        tag = re.search(rf'"/static/{re.escape(name)}\?v=([0-9a-f]+)"', page).group(1)
        assert hashlib.sha256(on_disk).hexdigest().startswith(tag)
        url = f"{server_url}static/{name}?v={tag}"
        with httpx.stream("GET", url, headers={"Accept-Encoding": "gzip"}) as raw:
            sent = b"".join(raw.iter_raw())  # as sent: httpx would decompress .content
        assert raw.headers["content-encoding"] == "gzip" and "immutable" in raw.headers["cache-control"]
        assert gzip.decompress(sent) == on_disk and len(sent) < len(on_disk)
        plain = httpx.get(url, headers={"Accept-Encoding": "gzip;q=0, identity"})
        assert "content-encoding" not in plain.headers and plain.content == on_disk
        unversioned = httpx.get(f"{server_url}static/{name}")
        assert unversioned.headers["cache-control"] == "no-cache"
        again = httpx.get(url, headers={"If-None-Match": raw.headers["etag"]})
        assert again.status_code == 304 and again.content == b""
        assert httpx.get(url, headers={"If-None-Match": 'W/"0123456789abcdef"'}).status_code == 200


def test_vendored_plotly_bundle_is_the_recorded_one():
    """static/VENDORED.md records the npm package, version and sha256 of the vendored bundle."""
    import hashlib

    static = ROOT / "src" / "brdfnorm" / "explore" / "static"
    bundle = (static / "plotly-basic.min.js").read_bytes()
    record = (static / "VENDORED.md").read_text()
    assert f"`{hashlib.sha256(bundle).hexdigest()}`" in record
    header = bundle[:80].decode().splitlines()[1]
    assert header.startswith("* plotly.js (basic - minified) v")
    assert f"`plotly.js-basic-dist-min@{header.rsplit(' v', 1)[1]}`" in record
    assert "MIT License" in (static / "plotly-basic.LICENSE").read_text()


def test_saving_the_watched_file_reloads_it_and_a_bad_save_reports_the_line(tmp_path):
    path = tmp_path / "lobe.brdf"
    text = GGX.read_text()
    path.write_text(text)
    with background(Catalog.build([str(path)])) as url, httpx.Client(timeout=30) as client:
        def version() -> dict:
            return client.get(url + "api/models/arg0").json()

        before = version()
        path.write_text(text.replace("float f0 0 1 0.04", "float f0 0 1 0.04\nfloat sheen 0 1 0.5"))
        deadline = time.monotonic() + 5
        while version()["version"] == before["version"] and time.monotonic() < deadline:
            time.sleep(0.05)
        reloaded = version()
        assert [p["name"] for p in reloaded["parameters"]] == ["roughness", "f0", "sheen"]
        assert reloaded["error"] is None
        broken = text.replace("return a2 / (PI * d * d);", "return a2 / (PI * d * d)")
        path.write_text(broken)
        deadline = time.monotonic() + 5
        while version()["error"] is None and time.monotonic() < deadline:
            time.sleep(0.05)
        error = version()["error"]
        line = 1 + broken[: broken.index("return a2 / (PI * d * d)")].count("\n")
        assert error["file"] == str(path) and error["line"] in (line, line + 1), error
        assert f"{path}:{error['line']}:" in error["text"]
        # The last good model still answers.
        response = client.post(url + "api/evaluate", json=view_request(params={"sheen": 0.2}))
        assert response.status_code == 200


# -- the command line --------------------------------------------------------------------------------------------

def test_command_line_refuses_bad_input_in_one_line(tmp_path, run_cli):
    bad = tmp_path / "bad.brdf"
    bad.write_text("analytic\n::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return 1 }\n"
                   "::end shader\n")
    code, out, err = run_cli("explore", str(bad), "--no-browser")
    assert code == 2 and out == "" and err.startswith(f"error: {bad}:") and len(err.strip().splitlines()) == 1
    code, _, err = run_cli("explore", "no-such-model", "--no-browser")
    assert code == 2 and "no-such-model" in err and "Traceback" not in err
    code, _, err = run_cli("explore", "--port", "70000", "--no-browser")
    assert code == 2 and "--port" in err
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        code, _, err = run_cli("explore", "--port", str(taken.getsockname()[1]), "--no-browser")
        assert code == 2 and err.startswith("error: --port: cannot listen")


def test_command_line_warns_beyond_localhost_and_opens_the_browser(monkeypatch, run_cli):
    import threading
    import webbrowser

    import brdfnorm.explore

    opened, served = [], []
    done = threading.Event()
    monkeypatch.setattr(webbrowser, "open", lambda url: (opened.append(url), done.set()))

    def serve(catalog, sock):  # instead of serving: what the server would be started with
        served.append(([entry.id for entry in catalog.entries()], sock.getsockname()))
        sock.close()

    monkeypatch.setattr(brdfnorm.explore, "serve", serve)
    code, out, err = run_cli("explore", str(GGX), "phong", "--host", "0.0.0.0")
    assert code == 0 and out == ""
    lines = err.splitlines()
    assert lines[0].startswith("warning: listening on 0.0.0.0") and "anyone" in lines[0]
    (ids, (host, port)), = served
    assert ids[:2] == ["arg0", "arg1"] and host == "0.0.0.0" and port > 0
    assert f"http://0.0.0.0:{port}/" in lines[1] and lines[-1].endswith("stopped")
    assert done.wait(5) and opened == [f"http://0.0.0.0:{port}/"]
    code, _, err = run_cli("explore", "--no-browser")
    assert code == 0 and not err.startswith("warning") and len(opened) == 1


@pytest.mark.skipif(os.name != "posix", reason="sends SIGINT")
def test_ctrl_c_stops_the_server_cleanly():
    env = {**os.environ, "PYTHONPATH": str(Path(bn.__file__).resolve().parents[1])}
    process = subprocess.Popen([sys.executable, "-c", "from brdfnorm.cli import main; main()", "explore", "phong",
                                "--no-browser", "--host", "127.0.0.2"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        url = process.stderr.readline().split()[2]  # "brdfnorm explore: URL  (Ctrl-C stops)"
        assert url.startswith("http://127.0.0.2:")
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            try:
                if httpx.get(url + "api/models", timeout=2).status_code == 200:
                    break
            except httpx.TransportError:
                time.sleep(0.1)
        with httpx.stream("GET", url + "api/events", timeout=10) as events:  # an open page's event stream
            next(events.iter_lines())
            process.send_signal(signal.SIGINT)
            out, err = process.communicate(timeout=15)
    finally:
        process.kill()
    assert process.returncode == 0, err
    assert out == "" and "Traceback" not in err and "ERROR" not in err and "stopped" in err
