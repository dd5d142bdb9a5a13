"""Measure Mitsuba 3's BSDFs against brdfnorm's float64 built-ins: the numbers of docs/mitsuba.md (issue 34).

    PYTHONPATH=src python benchmarks/mitsuba_findings.py            # all sections, a few minutes on one core
    PYTHONPATH=src python benchmarks/mitsuba_findings.py conductor  # one section

Sections: conductor (roughconductor, F = 1, vs ggx/beckmann with separable shadowing over a 16 × 16 (μ, α) grid),
dielectric (roughdielectric R + T vs ggx-dielectric/beckmann-dielectric, separable), plastic (roughplastic's albedo
with a white base over α), principled (the white furnace).
"""

from __future__ import annotations

import sys
import time
import warnings

import numpy as np

import brdfnorm as bn

N = 16
GRID = (np.arange(N) + 0.5) / N


def _albedo(model, theta, rtol):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # float32: rounding-limited below ~1e-6, reported in the table
        return bn.albedo(model, theta, rtol=rtol)


def conductor() -> None:
    theta = np.arccos(GRID)[None, :]
    for dist in ("ggx", "beckmann"):
        m = bn.load("mitsuba:roughconductor", distribution=dist).with_params(alpha=GRID[:, None])
        start = time.perf_counter()
        r = _albedo(m, theta, 1e-6)
        seconds = time.perf_counter() - start
        exact = bn.albedo(bn.load(dist, shadowing="separable").with_params(alpha=GRID[:, None]), theta,
                          rtol=1e-12).value[..., 0]
        diff = np.abs(r.value[..., 0] - exact)
        worst = np.unravel_index(np.argmax(diff / exact), diff.shape)
        print(f"roughconductor {dist} (eta 0, k 1: F = 1) vs {dist} -p shadowing=separable, μ, α = (i + ½)/16: "
              f"max |rel diff| {np.max(diff / exact):.3g} at α = {GRID[worst[0]]:g}, μ = {GRID[worst[1]]:g}; "
              f"median {np.median(diff / exact):.3g}; min estimate/|diff| {np.min(r.error[..., 0] / diff):.3g}; "
              f"largest relative estimate {np.max(r.error[..., 0] / r.value[..., 0]):.3g}; {seconds:.1f} s")


def dielectric() -> None:
    mu = np.array([0.1, 0.3, 0.6, 1.0])
    for eta in (1.5, 1 / 1.5):
        inside, outside = (1.5, 1.0) if eta > 1 else (1.0, 1.5)
        for dist in ("ggx", "beckmann"):
            for alpha in (0.1, 0.3, 0.7):
                m = bn.load("mitsuba:roughdielectric", distribution=dist, alpha=alpha, int_ior=inside,
                            ext_ior=outside)
                r = _albedo(m, np.arccos(mu), 1e-6)
                e = bn.albedo(bn.load(f"{dist}-dielectric", alpha=alpha, eta=eta, shadowing="separable"),
                              np.arccos(mu), rtol=1e-10)
                rel = {part: np.max(np.abs(getattr(r, part)[:, 0] - getattr(e, part)[:, 0])
                                    / np.maximum(getattr(e, part)[:, 0], 1e-300))
                       for part in ("value", "reflected", "transmitted")}
                covered = np.all(r.error[:, 0] >= np.abs(r.value[:, 0] - e.value[:, 0]))
                print(f"roughdielectric eta {eta:.4g} {dist} α {alpha}: max |rel diff| R+T {rel['value']:.2g}, "
                      f"R {rel['reflected']:.2g}, T {rel['transmitted']:.2g} over μ {mu.tolist()}; "
                      f"estimates cover: {covered}")


def plastic() -> None:
    mu = np.array([0.1, 0.3, 0.5, 0.7, 1.0])
    alphas = np.array([0.01, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0])
    for dist in ("ggx", "beckmann"):
        m = bn.load("mitsuba:roughplastic", distribution=dist, diffuse_reflectance=1.0)
        r = _albedo(m.with_params(alpha=alphas[:, None]), np.arccos(mu)[None, :], 1e-5)
        print(f"roughplastic {dist}, diffuse_reflectance 1: E (rows α {alphas.tolist()}, columns μ {mu.tolist()}); "
              f"largest estimate {r.error[..., 0].max():.2g} (at α = {alphas[np.argmax(r.error[..., 0].max(1))]})")
        print(np.array2string(r.value[..., 0], precision=4))
        smooth = bn.load("mitsuba:roughconductor", distribution=dist, specular_reflectance=1.0)
        spec = _albedo(smooth.with_params(alpha=alphas[:, None]), np.arccos(mu)[None, :], 1e-5).value[..., 0]
        print(f"  the same microfacet lobe as a perfect conductor (what the coating's specular part can lose): "
              f"1 − E at μ = 1 {np.array2string(1 - spec[:, -1], precision=3)}")


def principled() -> None:
    mu = np.array([0.1, 0.3, 0.5, 0.7, 1.0])
    rough = np.array([0.3, 0.5, 0.7, 1.0])
    for label, kw in (("base_color 1 (dielectric)", {"base_color": 1.0}),
                      ("base_color 1, metallic 1", {"base_color": 1.0, "metallic": 1.0}),
                      ("base_color 1, sheen 1", {"base_color": 1.0, "sheen": 1.0}),
                      ("base_color 1, clearcoat 1", {"base_color": 1.0, "clearcoat": 1.0}),
                      ("base_color 1, spec_trans 1", {"base_color": 1.0, "spec_trans": 1.0})):
        m = bn.load("mitsuba:principled", **kw).with_params(roughness=rough[:, None])
        r = _albedo(m, np.arccos(mu)[None, :], 1e-5)
        print(f"principled {label}: E (rows roughness {rough.tolist()}, columns μ {mu.tolist()}); max E "
              f"{r.value[..., 0].max():.5f}; largest estimate {r.error[..., 0].max():.2g}")
        print(np.array2string(r.value[..., 0], precision=4))


SECTIONS = {"conductor": conductor, "dielectric": dielectric, "plastic": plastic, "principled": principled}

if __name__ == "__main__":
    for name in sys.argv[1:] or list(SECTIONS):
        SECTIONS[name]()
