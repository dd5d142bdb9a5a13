"""brdfnorm audit (issue 29) of rough-glass tables (``ggx-dielectric``): the refraction's shadowing is part of the
searched convention — Heitz's Beta form, the reflection's form (Blender Cycles' glass), G1·G1 for refraction, or
separable for both. Tables are made by ``brdfnorm lut`` with each form (the model's ``refraction_shadowing``, itself
tested against nested quadrature in tests/models/test_dielectric.py) and audited with the form left open."""

from __future__ import annotations

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.audit import audit

pytestmark = pytest.mark.slow
T = (np.arange(8) + 0.5) / 8


def _glass(**params) -> np.ndarray:
    m = bn.load("ggx-dielectric", eta=1.5, **params)
    return lut.compute(m, {"mu": T, "alpha": T * T}, rtol=1e-8, average=False)["E"]


def test_cycles_form_is_named_with_the_geometry_open():
    r = audit(_glass(refraction_shadowing="reflection-form"), bn.load("ggx-dielectric", eta=1.5), dense=False,
              sweep=False)
    c = r.best.convention
    assert r.fits and (c.direction, c.roughness, c.shadowing) == (
        "mu-texel", "r2-texel", "height-correlated/refraction=reflection-form")
    assert r.best.channels[0].max < 1e-9 and not r.runners_up[0].fits


@pytest.mark.parametrize("params, named", [
    ({}, "height-correlated"),
    ({"refraction_shadowing": "separable"}, "height-correlated/refraction=separable"),
    ({"shadowing": "separable"}, "separable"),
])
def test_each_form_is_named(params, named):
    r = audit(_glass(**params), bn.load("ggx-dielectric", eta=1.5), dense=False, sweep=False,
              direction="mu-texel", roughness="r2-texel")
    assert r.fits and r.best.convention.shadowing == named and r.best.channels[0].max < 1e-9
    assert not any(h.fits for h in r.runners_up if h.convention.shadowing != named)


def test_cli_pins_the_form_and_a_given_form_is_not_searched(tmp_path, run_cli):
    np.save(tmp_path / "g.npy", _glass(refraction_shadowing="reflection-form"))
    np.savez(tmp_path / "g.npz", E=_glass(refraction_shadowing="reflection-form"))
    code, out, err = run_cli("audit", str(tmp_path / "g.npz"), "--model", "ggx-dielectric", "-p", "eta=1.5",
                             "--as", "shadowing=height-correlated/refraction=reflection-form", "--as",
                             "direction=mu-texel", "--as", "roughness=r2-texel", "--no-sweep", "--no-interpolation")
    assert code == 0, err
    assert "refraction=reflection-form" in out
    # the model given with its refraction's form: only Smith's two forms are searched, and the table fits
    r = audit(tmp_path / "g.npz", bn.load("ggx-dielectric", eta=1.5, refraction_shadowing="reflection-form"),
              dense=False, sweep=False, direction="mu-texel", roughness="r2-texel")
    assert r.fits and r.best.convention.shadowing == "height-correlated"
    code, out, err = run_cli("audit", str(tmp_path / "g.npz"), "--model", "ggx", "--as",
                             "shadowing=height-correlated/refraction=reflection-form")
    assert code == 2 and err.count("\n") == 1 and "shadowing" in err
