"""A grid of albedo results across every route of the engine, recorded bit for bit (issue 32).

The albedo engine was moved into one package (:mod:`brdfnorm.engine`); ``tests/fixtures/engine_grid.json`` was written
by this module (then ``python tests/engine_grid.py``; now ``cd tests && python -m helpers.engine_grid``) *before* the
move, and ``tests/engine/test_engine_grid.py`` recomputes it and compares every value, error estimate, evaluation count,
convergence flag, reason and method exactly (floats as ``float.hex``). Each route is reached at least once: the
hemisphere quadrature (lobe-aligned and half-vector routes of the generic engine, a BSDF's two hemispheres), the series,
the azimuthal, microfacet and dielectric routes, the certified enclosures, the closed forms, and E_avg's μ-average
(Clenshaw–Curtis and adaptive stages, the glass 3-D route).
"""

from __future__ import annotations

import json
import sys

import numpy as np

import brdfnorm as bn
from brdfnorm import lut
from helpers.paths import FIXTURES, REPO

ROOT = REPO
FIXTURE = FIXTURES / "engine_grid.json"

#: (label, model, params, theta (radians), albedo keywords)
ALBEDO_CASES = [
    ("lambert quadrature", "lambert", {}, [0.0, 0.7, 1.5], {"method": "quadrature", "rtol": 1e-8}),
    ("phong quadrature", "phong", {"n": 20.0}, [0.0, 0.6, 1.4], {"method": "quadrature", "rtol": 1e-8}),
    ("modified-phong over view", "modified-phong", {"n": 8.0}, [0.3, 1.2],
     {"method": "quadrature", "rtol": 1e-7, "over": "view"}),
    ("blinn-phong series", "blinn-phong", {"n": 512.0}, [0.0, 0.8, 1.55], {"method": "series", "rtol": 1e-12}),
    ("blinn-phong quadrature", "blinn-phong", {"n": 64.0}, [0.2, 1.3], {"method": "quadrature", "rtol": 1e-9}),
    ("blinn-phong-gaussian", "blinn-phong-gaussian", {"n": 100.0}, [0.0, 1.0], {"rtol": 1e-8}),
    ("ggx azimuthal", "ggx", {"alpha": 0.3}, [0.0, 0.9, 1.5], {"method": "azimuthal", "rtol": 1e-10}),
    ("ggx mirror", "ggx", {"alpha": 1e-6}, [0.1, 1.55], {"rtol": 1e-10}),
    ("ggx microfacet conductor", "ggx", {"alpha_x": 0.1, "alpha_y": 0.4, "fresnel": "conductor",
                                         "eta": [0.2, 0.9, 1.1], "k": [3.0, 2.5, 2.2]},
     [0.2, 1.2], {"method": "microfacet", "rtol": 1e-8}),
    ("beckmann microfacet", "beckmann", {"alpha": 0.5, "shadowing": "separable"}, [0.0, 1.3],
     {"method": "microfacet", "rtol": 1e-9}),
    ("ggx kulla-conty", "ggx", {"alpha": 0.5, "ms": "kulla-conty", "ms_table": 16}, [0.0, 1.0], {"rtol": 1e-8}),
    ("ggx-dielectric", "ggx-dielectric", {"alpha": 0.3, "eta": 1.5}, [0.0, 1.2], {"rtol": 1e-8}),
    ("beckmann-dielectric inside", "beckmann-dielectric", {"alpha": 0.7, "eta": 1 / 1.5}, [0.4, 1.0],
     {"rtol": 1e-8}),
    ("phong closed form", "phong", {"n": 10.0}, [0.0], {"method": "closed-form"}),
    ("phong certified", "phong", {"n": 7.0}, [0.0, 0.9], {"method": "certified", "digits": 20}),
]

#: (label, .brdf file, params, theta, keywords): the generic engine on shader lobes (half-vector route included)
FILE_CASES = [
    ("ggx.brdf", "examples/ggx.brdf", {"roughness": 0.1}, [0.0, 1.2, 1.5], {"rtol": 1e-8}),
    ("anisotropic_ggx.brdf", "examples/anisotropic_ggx.brdf", {}, [0.5], {"rtol": 1e-6}),
    ("oren_nayar.brdf", "examples/oren_nayar.brdf", {}, [0.0, 1.3], {"rtol": 1e-8}),
    ("layered_series.brdf", "examples/layered_series.brdf", {}, [0.3, 1.5], {"rtol": 1e-7}),
]

#: (label, model, params, axes, keywords): tables with E_avg (its μ-average's stages)
TABLE_CASES = [
    ("ggx table", "ggx", {}, {"mu": [0.05, 0.5, 1.0], "alpha": [0.1, 0.8]}, {"rtol": 1e-8}),
    ("blinn-phong table", "blinn-phong", {}, {"mu": [0.25, 1.0], "n": [4.0, 64.0]}, {"rtol": 1e-8}),
    ("glass table", "ggx-dielectric", {}, {"mu": [0.3, 0.9], "alpha": [0.5], "eta": [1.5]}, {"rtol": 1e-7}),
]


def _hex(values) -> object:
    array = np.asarray(values)
    if array.dtype.kind in "fc":
        return [float(v).hex() for v in array.astype(float).ravel()]
    return [v.item() if hasattr(v, "item") else v for v in array.ravel()]


def _albedo_record(result) -> dict:
    record = {"method": result.method, "value": _hex(result.value), "error": _hex(result.error),
              "evaluations": _hex(result.evaluations), "converged": _hex(result.converged),
              "reason": None if result.reason is None else [str(r) for r in np.ravel(result.reason)]}
    for extra in ("lower", "upper"):
        if getattr(result, extra) is not None:
            record[extra] = [str(v) for v in np.ravel(getattr(result, extra))]
    for part in ("reflected", "transmitted"):
        if getattr(result, part) is not None:
            record[part] = _hex(getattr(result, part))
    return record


def compute() -> dict:
    """Every case's record, keyed by its label."""
    grid = {}
    for label, name, params, theta, keywords in ALBEDO_CASES:
        grid[label] = _albedo_record(bn.albedo(bn.load(name, **params), np.array(theta), **keywords))
    for label, path, params, theta, keywords in FILE_CASES:
        grid[label] = _albedo_record(bn.albedo(bn.load(ROOT / path, **params), np.array(theta), **keywords))
    for label, name, params, axes, keywords in TABLE_CASES:
        table = lut.compute(bn.load(name, **params), axes, **keywords)
        grid[label] = {key: _hex(table[key]) for key in sorted(table)}
    return grid


if __name__ == "__main__":
    FIXTURE.write_text(json.dumps(compute(), indent=1) + "\n", encoding="utf-8")
    sys.stderr.write(f"wrote {FIXTURE}\n")
