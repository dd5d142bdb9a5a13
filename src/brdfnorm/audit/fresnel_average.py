"""Tables of a Fresnel factor's hemispherical average F_avg = 2∫₀¹ F(μ) μ dμ — the number every Kulla–Conty
compensation multiplies by (Kulla & Conty 2017, "Revisiting physically based shading at Imageworks") — audited:
the convention found, every cell's error against the exact F_avg, and the fitted formulas engines ship named.

A table's channel meaning is ``F_avg``; which Fresnel factor it averages follows from its axes
(:class:`AverageConvention`):

* two axes (r, g): Gulbrandsen 2014's artist-friendly conductor ("Artist friendly metallic Fresnel", JCGT 3(4)),
  reflectivity r and edge tint g, each at nodes i/(N − 1) or texel centres (i + ½)/N of [0, 1], in either order,
  each possibly reversed; r clamped to OSPRay's 0.99 or not (searched where the grid reaches above 0.99). The
  exact F_avg is :meth:`brdfnorm.models.fresnel.Fresnel.average` (adaptive Gauss–Legendre, error ~1e-14); r = 1
  is the perfect mirror, F_avg = 1 (η → 0, k → 1 at g = 1, η → ∞ at g = 0: F = 1 at every angle);
* one f0 axis: Schlick's factor, F_avg = f0 + (1 − f0)/21 exactly (Kulla & Conty 2017);
* one η axis: the exact dielectric's F_avg (total internal reflection where η < 1), with η laid out as Cycles'
  precompute lays it (``eta-cycles``: F0 = clamp(t, 1e-4, 0.99)⁴), as MoonRay's ``TransmissionAlbedo`` reads it
  (``eta-moonray``: η = 1.05 + 2t, t = i/(N − 1)), each entering or exiting (1/η), or given with ``--axis eta=…``.

Fitted formulas recognised in such a table (:data:`FITS`, each written from its published constants): OSPRay's
``FresnelConductorArtistic_evalAvg`` (``modules/cpu/render/bsdfs/Fresnel.ih``, Apache-2.0), Kulla & Conty's cubic
fit of the artistic conductor's F_avg, evaluated at OSPRay's clamped r = min(r, 0.99) (or unclamped); OSPRay's
``fresnelDielectricAvg`` fit of the dielectric's (:func:`brdfnorm.models.fresnel.kulla_conty_dielectric_fit`). A
table is *the fit tabulated* when more than half of its cells equal it within the storage step plus 1e-6 (a
float32 evaluation); the hypothesis in that geometry is then reported first, so the residuals, the error map and
the wrong cells are the fit's error against the exact F_avg.

The search is selected by ``--as channels=F_avg`` (or ``--as axes=r,g``, ``g,r``, ``f0``, ``eta``), and tried
when no microfacet convention fits a 1-D or 2-D table.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError
from ..models.fresnel import DESCRIPTIONS, OSPRAY_R_MAX, Fresnel, kulla_conty_artistic_fit, kulla_conty_dielectric_fit
from .conventions import ETA_AXES, PINNED_ETA_AXES, Convention, role_value
from .fits import Hypothesis, Inference, Precision
from .infer import fit_channel

F_AVG = "F_avg"
POSITIONS = ("node", "texel")
#: Layouts of an η axis: Cycles' (F0 = t⁴), MoonRay's (η = 1.05 + 2t), appleseed's (η = lerp(1.01, 3, t)), each
#: entering or exiting.
ETA_LAYOUTS = ETA_AXES + PINNED_ETA_AXES
#: The Fresnel factor an F_avg table averages, by its axis roles.
KIND_OF_ROLES = {("g", "r"): "artistic", ("f0",): "schlick", ("eta",): "dielectric"}


@dataclass(frozen=True)
class AverageConvention:
    """One hypothesis for an F_avg table: per array axis its role (r, g, f0, eta), sample positions (node, texel,
    an η layout, or ``explicit``) and orientation; OSPRay's clamp of r; the channel meanings."""

    roles: tuple[str, ...]
    positions: tuple[str, ...]
    flips: tuple[bool, ...]
    r_max: float = 1.0
    meanings: tuple[str | None, ...] = ()
    explicit: tuple[float, ...] = ()  # the η or f0 values given with --axis, in array order
    shadowing: str = ""  # (no lobe: what a microfacet convention's readers expect to find)

    @property
    def kind(self) -> str:
        return KIND_OF_ROLES[tuple(sorted(self.roles))]

    def geometry(self) -> tuple:
        return (self.roles, self.positions, self.flips, self.r_max, self.explicit)

    def describe(self) -> dict:
        return {"axes": list(self.roles), "flipped": [bool(f) for f in self.flips], "positions": list(self.positions),
                "fresnel": self.kind, **({"r_max": self.r_max} if "r" in self.roles else {}),
                "channels": list(self.meanings)}

    def text(self) -> str:
        parts = [f"F_avg of the {DESCRIPTIONS[self.kind]}", f"axes ({', '.join(self.roles)})",
                 ", ".join(f"{role} {pos}" for role, pos in zip(self.roles, self.positions, strict=True))]
        flipped = [role for role, f in zip(self.roles, self.flips, strict=True) if f]
        if flipped:
            parts.append("reversed: " + ", ".join(flipped))
        if "r" in self.roles and self.r_max < 1.0:
            parts.append(f"r<={self.r_max:g}")
        parts.append("channels " + "/".join(m or "?" for m in self.meanings))
        return "; ".join(parts)

    def unit(self, axis: int, n: int, index: np.ndarray) -> np.ndarray:
        index = np.asarray(index, dtype=float)
        if self.flips[axis]:
            index = n - 1 - index
        if self.positions[axis] == "texel":
            return (index + 0.5) / n
        return index / (n - 1) if n > 1 else np.zeros_like(index)

    def stored_values(self, shape: tuple[int, ...], index: list[np.ndarray]) -> dict[str, np.ndarray]:
        """Each axis's value at the samples ``index`` as the table is indexed by it (r before OSPRay's clamp)."""
        out = {}
        for axis, role in enumerate(self.roles):
            i = np.asarray(index[axis])
            if self.positions[axis] == "explicit":
                out[role] = np.asarray(self.explicit)[i.astype(int)]
                continue
            t = self.unit(axis, shape[axis], i)
            if role == "eta":
                out[role] = role_value(_LAYOUTS[self.positions[axis]], "eta", t)
            else:
                out[role] = t
        return out

    def coordinates(self, shape: tuple[int, ...], index: list[np.ndarray]) -> dict[str, np.ndarray]:
        """r (clamped), g, f0 or η at the samples ``index``."""
        out = self.stored_values(shape, index)
        if "r" in out:
            out["r"] = np.minimum(out["r"], self.r_max)
        return out


#: The η layouts as :func:`.conventions.role_value` evaluates them.
_LAYOUTS = {layout: Convention(f0=layout) for layout in ETA_LAYOUTS}


def exact_average(kind: str, coords: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(F_avg, error estimate) at each cell: closed form for Schlick, adaptive quadrature for the others."""
    if kind == "schlick":
        return Fresnel("schlick", f0=coords["f0"]).average()
    if kind == "dielectric":
        eta = np.asarray(coords["eta"], dtype=float)
        value, error = np.zeros(eta.shape), np.zeros(eta.shape)
        matched = np.abs(eta - 1.0) < 1e-12  # an index-matched interface reflects nothing
        if (~matched).any():
            value[~matched], error[~matched] = Fresnel("dielectric", eta=eta[~matched]).average()
        return value, error
    r, g = np.broadcast_arrays(np.asarray(coords["r"], dtype=float), np.asarray(coords["g"], dtype=float))
    value, error = np.ones(r.shape), np.zeros(r.shape)  # r = 1: the perfect mirror
    inside = r < 1.0
    if inside.any():
        value[inside], error[inside] = Fresnel("artistic", r=r[inside], g=g[inside]).average()
    return value, error


def requested(pins: dict) -> bool:
    """Whether the pins ask for an F_avg table (``channels=F_avg…`` or axes r, g, f0 or eta alone)."""
    if F_AVG in [m.strip() for m in pins.get("channels", "").split(",")]:
        return True
    axes = tuple(sorted(a.strip() for a in pins.get("axes", "").split(","))) if "axes" in pins else ()
    return axes in KIND_OF_ROLES


def conventions(grid: tuple[int, ...], channels: int, pins: dict,
                explicit: dict[str, np.ndarray] | None = None) -> list[AverageConvention]:
    """Every F_avg hypothesis of a table of shape ``grid`` (1 or 2 axes), with the pinned axes and flips."""
    ndim = len(grid)
    given = dict(explicit or {})
    unknown = sorted(set(given) - {"eta", "f0"})
    if unknown:
        raise ArgumentError(f"axis {unknown[0]}: an F_avg table's r and g axes are node or texel grids over [0, 1]; "
                            "give eta or f0 values outright", where="axes")
    if ndim == 2:
        role_sets = [("r", "g"), ("g", "r")]
    elif ndim == 1:
        role_sets = [("f0",), ("eta",)]
    else:
        raise ArgumentError(f"an F_avg table has one axis (f0 or eta) or two (r, g); this one has {ndim}",
                            where="shape")
    if "axes" in pins:
        wanted = tuple(a.strip() for a in pins["axes"].split(","))
        if wanted not in role_sets:
            raise ArgumentError(f"axes={pins['axes']}: an F_avg table of {ndim} axis(es) has axes "
                                + " or ".join(",".join(s) for s in role_sets), where="pins")
        role_sets = [wanted]
    if given:
        role_sets = [s for s in role_sets if all(role in given for role in s)]
    flip_sets = list(itertools.product((False, True), repeat=ndim))
    if "flip" in pins:
        flip_sets = [tuple(bool(int(x)) for x in pins["flip"].split(","))]
        if len(flip_sets[0]) != ndim:
            raise ArgumentError(f"flip=: one 0/1 per array axis ({ndim})", where="pins")
    meanings = _meanings(pins, channels)
    out = []
    for roles in role_sets:
        if roles[0] in given:  # values given outright: never flipped, never re-laid out
            values = tuple(float(v) for v in given[roles[0]])
            if len(values) != grid[0]:
                raise ArgumentError(f"axis {roles[0]}: {len(values)} values for an axis of {grid[0]}", where="axes")
            out.append(AverageConvention(roles, ("explicit",), (False,), meanings=meanings, explicit=values))
            continue
        choices = [ETA_LAYOUTS if role == "eta" else POSITIONS for role in roles]
        for positions, flips in itertools.product(itertools.product(*choices), flip_sets):
            r_axis = roles.index("r") if "r" in roles else None
            reaches = r_axis is not None and _unit_max(positions[r_axis], grid[r_axis]) > OSPRAY_R_MAX
            for r_max in ((1.0, OSPRAY_R_MAX) if reaches else (1.0,)):
                out.append(AverageConvention(roles, positions, flips, r_max, meanings))
    if not out:
        raise ArgumentError(f"the --axis values ({', '.join(sorted(given))}) name no axis of an F_avg table of "
                            f"{ndim} axes (r, g over two; f0 or eta over one)", where="axes")
    return out


def _unit_max(position: str, n: int) -> float:
    return (n - 0.5) / n if position == "texel" else 1.0


def _meanings(pins: dict, channels: int) -> tuple[str | None, ...]:
    if "channels" not in pins:
        return (F_AVG,) * channels
    given = [m.strip() for m in pins["channels"].split(",")]
    if len(given) != channels or any(m not in (F_AVG, "-") for m in given):
        raise ArgumentError(f"channels={pins['channels']}: an F_avg table's channels are F_avg (or - to skip), one "
                            f"per channel ({channels})", where="pins")
    return tuple(None if m == "-" else m for m in given)


class _Exact:
    """Exact F_avg per (kind, coordinates), computed once for the hypotheses that share sample positions."""

    def __init__(self) -> None:
        self.cache: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self.computed = 0

    def __call__(self, c: AverageConvention, grid: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
        index = list(np.meshgrid(*[np.arange(n) for n in grid], indexing="ij"))
        coords = c.coordinates(grid, index)
        key = (c.kind,) + tuple((role, coords[role].tobytes()) for role in sorted(coords))
        if key not in self.cache:
            self.cache[key] = exact_average(c.kind, coords)
            self.computed += int(np.prod(grid))
        return self.cache[key]


def hypothesis(values: np.ndarray, names: list[str], c: AverageConvention, exact: _Exact, precision: Precision,
               chosen: list[int]) -> Hypothesis:
    grid = values.shape[:-1]
    reference, error = exact(c, grid)
    fits = []
    for channel, meaning in enumerate(c.meanings):
        if channel not in chosen or meaning is None:
            continue
        fit = fit_channel(values[..., channel], reference, error, names[channel], meaning, precision)
        if fit.worst:
            at = c.stored_values(grid, [np.asarray([w]) for w in fit.worst])
            fit.worst_at = {k: float(np.ravel(v)[0]) for k, v in at.items()}
        fits.append(fit)
    return Hypothesis(c, fits)


def infer_average(values: np.ndarray, names: list[str], pins: dict, step: float, chosen: list[int] | None = None,
                  explicit: dict[str, np.ndarray] | None = None, tolerance: float | None = None,
                  keep_runners: int = 3) -> tuple[Inference, dict | None]:
    """The best F_avg conventions for ``values`` (*grid, channels), and the fitted formula the table is, if any
    (its hypothesis is then ranked first: the residuals are the fit's error against the exact F_avg)."""
    grid = values.shape[:-1]
    chosen = list(range(values.shape[-1])) if chosen is None else chosen
    candidates = conventions(grid, values.shape[-1], pins, explicit)
    precision = Precision(step, tolerance)
    exact = _Exact()
    hypotheses = [hypothesis(values, names, c, exact, precision, chosen) for c in candidates]
    if tolerance is None:  # every hypothesis judged with the table's noise: the smallest σ̂ any saw, per channel
        for k in range(len(hypotheses[0].channels)):
            sigma = min(h.channels[k].noise for h in hypotheses)
            for h in hypotheses:
                h.channels[k].judged(sigma)
    hypotheses.sort(key=lambda h: h.rank)
    fit = recognise(values, candidates, step)
    if fit is not None and not hypotheses[0].fits:
        index = next(i for i, h in enumerate(hypotheses) if h.convention == fit["convention"])
        hypotheses.insert(0, hypotheses.pop(index))
        best = hypotheses[0]
        fit = {k: v for k, v in fit.items() if k != "convention"}
        fit.update({"convention": best.convention.text(), "channels": [
            {"channel": c.channel, "approximates": c.meaning, "max": c.max, "median": c.median, "rms": c.rms,
             "worst_cell": list(c.worst), "worst_at": c.worst_at} for c in best.channels]})
    return Inference(hypotheses[0], hypotheses[1:1 + keep_runners], len(candidates), {F_AVG: exact.computed}), fit


@dataclass(frozen=True)
class Fit:
    name: str
    source: str
    kind: str
    evaluate: Callable[[dict[str, np.ndarray], float], np.ndarray]


FITS = (
    Fit("OSPRay's Kulla–Conty cubic fit of the artistic conductor's F_avg",
        "OSPRay modules/cpu/render/bsdfs/Fresnel.ih FresnelConductorArtistic_evalAvg (Kulla & Conty 2017), r "
        "clamped to 0.99 as OSPRay's FresnelConductorArtistic_create does", "artistic",
        lambda x, r_max: kulla_conty_artistic_fit(np.minimum(x["r"], r_max), x["g"])),
    Fit("OSPRay's Kulla–Conty fit of the dielectric's F_avg",
        "OSPRay fresnelDielectricAvg (Kulla & Conty 2017), written for eta = interior/exterior", "dielectric",
        lambda x, r_max: kulla_conty_dielectric_fit(x["eta"])),
)


def recognise(values: np.ndarray, candidates: list[AverageConvention], step: float) -> dict | None:
    """The fit (and geometry) that equals the most cells of the table, when it equals more than half of them within
    ``step`` plus 1e-6 (a float32 evaluation of the formula); None otherwise. The fit is evaluated at the
    geometry's own r clamp (OSPRay's 0.99, or none)."""
    grid = values.shape[:-1]
    index = list(np.meshgrid(*[np.arange(n) for n in grid], indexing="ij"))
    tolerance = step + 1e-6
    best = None
    for c in candidates:
        for fit in FITS:
            if fit.kind != c.kind:
                continue
            with np.errstate(all="ignore"):
                formula = fit.evaluate(c.stored_values(grid, index), c.r_max)
            within = sum(int(np.sum(np.abs(values[..., k] - formula) <= tolerance))
                         for k, m in enumerate(c.meanings) if m is not None)
            if best is None or within > best[0]:
                best = (within, fit, c)
    if best is None:
        return None
    within, fit, c = best
    cells = int(sum(values[..., k].size for k, m in enumerate(c.meanings) if m is not None))
    if within <= 0.5 * cells:
        return None
    return {"name": fit.name, "source": fit.source, "within": within, "cells": cells, "convention": c}
