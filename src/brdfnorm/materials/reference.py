"""Reference values engines can put in CI: a material's E(μ), E_avg and white-furnace residual over a parameter
grid, as JSON or CSV, with the material, the conventions and brdfnorm's version in the file.

JSON: ``{"format": "brdfnorm-material-reference", "brdfnorm": VERSION, "material": {...}, "conventions": {...},
"mu": [...], "grid": {NAME: [...]}, "points": [{"params": {...}, "E": [[R, G, B] per μ], "E_error": ...,
"E_avg": [...], "E_avg_error": [...], "furnace_residual": [[E − 1] per μ], "max_residual": r,
"argmax_mu": μ}]}`` (with "E_R" and "E_T", reflected and transmitted, for a material that transmits). CSV: one
row per (grid point, μ) with the same quantities, the metadata as ``#`` lines first.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
from collections.abc import Mapping, Sequence

import numpy as np

from .. import __version__
from ..engine.methods import albedo
from ..errors import ArgumentError
from ..models.base import Model
from ..validate import DEFAULT_RTOL
from .furnace import average_albedo

FORMAT = "brdfnorm-material-reference"
CONVENTIONS = {
    "albedo": "E(mu_o) = integral over the light of f(L, V) (N.L) dL, the view fixed (over='light')",
    "mu": "cos of the view angle theta_o; N = +z",
    "E_avg": "2 * integral_0^1 E(mu) mu dmu (16-point Gauss-Legendre on [0, 0.05, 0.3, 1]; error vs 8-point)",
    "roughness": "perceptual roughness r of the OpenPBR parameters; GGX alpha = r^2",
    "furnace_residual": "E - 1 per channel (0 for a lossless white material)",
    "channels": "R, G, B",
}


def reference(model: Model, grid: Mapping[str, Sequence[float]], mu: Sequence[float], *,
              rtol: float = DEFAULT_RTOL) -> dict:
    """The reference document of ``model`` over the product of the ``grid`` values at the view cosines ``mu``."""
    mu = np.asarray(mu, dtype=float).ravel()
    if mu.size == 0 or np.any((mu <= 0) | (mu > 1)) or not np.all(np.isfinite(mu)):
        raise ArgumentError("view cosines must lie in (0, 1]", where="mu")
    names = list(grid)
    for name in names:
        parameter = model.parameter(name)
        if parameter.kind not in ("float", "int", "color", "spectrum"):
            raise ArgumentError(f"{name} is a {parameter.kind}; a grid axis takes numbers", where="grid")
    points = []
    for combination in itertools.product(*(list(grid[n]) for n in names)):
        values = dict(zip(names, combination, strict=True))
        bound = model.with_params(**values)
        result = albedo(bound, np.arccos(mu), rtol=rtol)
        value = result.value.reshape(mu.size, -1)
        average, average_error = average_albedo(bound, rtol=rtol)
        residual = value - 1.0
        i = int(np.unravel_index(np.argmax(np.abs(residual)), residual.shape)[0])
        points.append({"params": {k: float(v) for k, v in values.items()},
                       "E": value.tolist(), "E_error": result.error.reshape(mu.size, -1).tolist(),
                       "E_avg": average.tolist(), "E_avg_error": average_error.tolist(),
                       "furnace_residual": residual.tolist(),
                       "max_residual": float(residual.flat[np.argmax(np.abs(residual))]), "argmax_mu": float(mu[i])})
        if result.transmitted is not None:  # a translucent base: the reflected and transmitted shares apart
            points[-1].update(E_R=result.reflected.reshape(mu.size, -1).tolist(),
                              E_T=result.transmitted.reshape(mu.size, -1).tolist())
    params = {k: (list(v) if isinstance(v, tuple) else v) for k, v in model.params.items()}
    return {"format": FORMAT, "brdfnorm": __version__,
            "material": {"model": model.name, "source": model.source_path,
                         "name": getattr(model, "material_name", model.name), "params": params},
            "conventions": CONVENTIONS, "mu": mu.tolist(), "grid": {n: list(map(float, grid[n])) for n in names},
            "points": points}


def to_json(document: dict) -> str:
    return json.dumps(document, indent=1) + "\n"


def to_csv(document: dict) -> str:
    out = io.StringIO()
    for key in ("format", "brdfnorm"):
        out.write(f"# {key}: {document[key]}\n")
    out.write(f"# material: {json.dumps(document['material'])}\n")
    for key, text in document["conventions"].items():
        out.write(f"# {key}: {text}\n")
    names = list(document["grid"])
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(names + ["mu"] + [f"{q}_{c}" for q in ("E", "E_error", "residual", "E_avg", "E_avg_error")
                                      for c in "RGB"])
    for point in document["points"]:
        for j, mu in enumerate(document["mu"]):
            writer.writerow([repr(point["params"][n]) for n in names] + [repr(mu)]
                            + [repr(x) for x in (*point["E"][j], *point["E_error"][j], *point["furnace_residual"][j],
                                                 *point["E_avg"], *point["E_avg_error"])])
    return out.getvalue()
