"""Convention inference: which declared convention (:mod:`.conventions`) a table was made in, with residuals.

Two stages, both against exact values (:mod:`.reference`):

1. Every geometry (axis roles, flips, sample positions, shadowing) is scored on a subset of interior cells —
   the same indices on each axis, symmetric under a flip, so that flipped and transposed hypotheses reuse each
   other's reference values; boundary rows are left out there because only they depend on the endpoint clamps.
   Each channel takes the meaning with the smallest median residual; a geometry's score is that of its
   best-fitting channel. Meanings that need the split-sum bias F90 (slow: a generic quadrature) are scored only
   if no cheaper meaning fits the subset.
2. The best geometries are evaluated on every cell, the endpoint clamps searched where the grid reaches μ = 0 or
   α = 0, and ranked by the share of cells within the tolerance, then their median residual, then their maximum
   (:attr:`Hypothesis.rank`): a few wrong cells never decide the convention of the rest. A table of more than
   SUBGRID_CELLS cells is ranked (clamps searched, channels retried) on a fixed subgrid of at most INFER_CELLS
   cells (RANK_CELLS where the meanings need F90) that holds the first and last three indices of every axis
   (:func:`inference_index`): the inference's work is bounded whatever the table's size. Only the best is then
   measured on every cell (:func:`_complete`; the runners-up's statistics say they were sampled), exactly up to
   EXACT_CELLS cells and above that from a bounded coarse subgrid interpolated with an error estimate, every
   cell whose verdict that estimate leaves open computed exactly (:mod:`.interpolated`).

Every cell is judged against the tolerance (or the one given, ``--tolerance``)

    tol = storage step (half a code, or half an ulp at 1) + the reference's own error estimate + k σ̂,

σ̂ the noise of the residual estimated from its second differences along each axis (median absolute deviation
/ 0.6745 / √6: white noise survives second differences with variance 6σ², a smooth misfit does not), and
k = max(5, √(2 ln 2n) + 1) for n cells. A channel whose σ̂ exceeds MAX_NOISE_SHARE of the exact table's standard
deviation never fits (data that are mostly noise would fit any hypothesis). A channel's meaning is *named*
(:attr:`.fits.ChannelFit.fits`) when most of its cells are within the tolerance and its median residual is at
the noise level; the table *passes* only when every cell of every channel is (:attr:`.fits.ChannelFit.clean`).
The cells outside are listed (:func:`.api.wrong_cells`). A channel the best convention leaves unnamed is tried
in the table's other layouts (:func:`_relayout_channels`: reversed, transposed). The result is never a silent
best guess: :class:`Inference` says whether the best fits, and whether the runner-up is as good (then the table
does not decide between them).

Meanings with the exact dielectric Fresnel factor (E_dielectric, E_f0_dielectric) cost a quadrature per
(μ, α, η) and are rarely what an engine ships; both stages run again with them only when nothing fits without
them (or from the start when ``eta=`` or the channels are pinned).
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
from scipy import optimize

from ..errors import ArgumentError
from ..lut.splitsum import DFG_F0, DFG_F90
from .conventions import (
    ALPHA_FLOORS,
    ETA,
    GLASS_MEANINGS,
    MU_FLOORS,
    Convention,
    coordinates,
    fresnel_of,
    geometries,
    stored_axis_values,
)
from .fits import MAJORITY, MAX_NOISE_SHARE, ChannelFit, Hypothesis, Inference, Precision
from .interpolated import coarse_index, measured, per_axis
from .reference import Reference

__all__ = ["MAJORITY", "MAX_NOISE_SHARE", "ChannelFit", "Hypothesis", "Inference", "Precision", "infer",
           "noise_sigma"]

#: Geometries carried from stage 1 to the full table (fewer when a meaning needs F90, ~3 ms a cell).
STAGE2 = 4
STAGE2_F90 = 2
#: Interior samples per axis in stage 1 (before symmetrizing), for cheap meanings and for F90 meanings.
SUBSET = 6
SUBSET_F90 = 3
#: Above this many cells, stage 2 (and the channel retries) run on a fixed subgrid (:func:`inference_index`) of at
#: most INFER_CELLS cells, or RANK_CELLS where the meanings need F90; only the best hypothesis is then measured
#: on every cell (:func:`_complete`). The runners-up's statistics are on the subgrid.
SUBGRID_CELLS = 1024
INFER_CELLS = 1024
RANK_CELLS = 256
#: A hypothesis is measured on every cell of a table of up to so many cells exactly (by kind of meaning: cheap,
#: or a quadrature per cell); above, from a coarse subgrid of at most NODE_CELLS exact cells interpolated
#: (:mod:`.interpolated`), with up to RESOLVE_CELLS more computed exactly where a verdict or a fix needs them.
EXACT_CELLS = {"cheap": 16384, "expensive": 1024}
NODE_CELLS = {"cheap": 65536, "expensive": 2048}
#: The coarse subgrid of a first probe (a table no convention fits stops there).
PROBE_CELLS = {"cheap": 4096, "expensive": 256}
RESOLVE_CELLS = {"cheap": 262144, "expensive": 40000}
NOISE_FACTOR = 5.0
#: The exact-dielectric-Fresnel meaning a table of so many axes may carry.
DIELECTRIC_BY_NDIM = {1: [], 2: ["E_dielectric"], 3: ["E_f0_dielectric"]}
#: A fitted Schlick f0 this close to 0 or 1 is DFG_f90 or E, which need no fitted number: those are preferred.
SCHLICK_ENDS = 5e-3
#: Geometries a 2-D table's exact-Fresnel round fits η for and searches (ranked at η = ETA).
DIELECTRIC_GEOMETRIES = 16
#: Geometries a 3-D table's exact-Fresnel round searches: the first of Schlick's ranking (a 32³ table made with the
#: exact factor ranked its true geometry first under Schlick's when this was written).
DIELECTRIC_GEOMETRIES_3D = 64


def _subset(n: int, k: int) -> np.ndarray:
    if n <= 2:
        return np.arange(n)
    picks = np.unique(np.rint(np.linspace(1, n - 2, min(k, n - 2))).astype(int))
    return np.unique(np.concatenate([picks, n - 1 - picks]))


def inference_index(grid: tuple[int, ...], cells: int) -> list[np.ndarray]:
    """The fixed subgrid a large table's hypotheses are ranked on: at most ``cells`` cells (and at least 6 indices
    per axis, or all), the first and last three indices of every axis (where the endpoint clamps act) and evenly
    spaced ones between."""
    return [coarse_index(n, k) for n, k in zip(grid, per_axis(grid, cells), strict=True)]


def noise_sigma(residual: np.ndarray) -> float:
    """σ of white noise in ``residual`` from its second differences along each axis (robust: MAD)."""
    parts = []
    for axis in range(residual.ndim):
        if residual.shape[axis] >= 3:
            d2 = np.diff(residual, n=2, axis=axis).ravel()
            parts.append(d2[np.isfinite(d2)])
    if not parts or not sum(p.size for p in parts):
        return 0.0
    d2 = np.concatenate(parts)
    return float(np.median(np.abs(d2 - np.median(d2))) / 0.6745 / np.sqrt(6.0))


def allowed_meanings(grid_ndim: int, pins: dict, channels: int, reference: Reference | None = None) -> list[list[str]]:
    """Candidate meanings per channel (the exact dielectric ones only where pinned: see :func:`infer`)."""
    default = {1: ["E_avg", "1-E_avg"], 2: ["E", "1-E", DFG_F0, DFG_F90, "DFG_cloth", "E_schlick"],
               3: list(GLASS_MEANINGS) if reference is not None and reference.glass else ["E_f0"]}[grid_ndim]
    if "channels" not in pins:
        if "k" in pins and grid_ndim == 2:  # a conductor's η + ik is given: the exact conductor Fresnel
            default = default + ["E_conductor"]
        elif "eta" in pins:  # an index of refraction is given: the table is meant to carry the exact Fresnel
            default = default + DIELECTRIC_BY_NDIM[grid_ndim]
        return [[m for m in default if reference is None or reference.supports(m)]] * channels
    given = [m.strip() for m in pins["channels"].split(",")]
    if len(given) != channels:
        raise ArgumentError(f"channels={pins['channels']}: give one meaning per channel ({channels}), - to skip",
                            where="pins")
    for m in given:
        if m == "E_conductor" and "k" not in pins:
            raise ArgumentError("channels: E_conductor needs the conductor's η + ik: --as eta=… --as k=…",
                                where="pins")
        if reference is not None and not reference.supports(m):
            raise ArgumentError(f"channels: {m} needs a lobe with an exact Fresnel factor of that kind "
                                f"(-p fresnel=...); {reference.model.name} has none", where="pins")
    return [[] if m == "-" else [m] for m in given]


def _mesh(shape: tuple[int, ...], index: list[np.ndarray]) -> list[np.ndarray]:
    return list(np.meshgrid(*index, indexing="ij")) if index else []


def _exact(reference: Reference, c: Convention, meaning: str, coords: dict) -> tuple[np.ndarray, np.ndarray]:
    return reference.meaning(meaning, c.shadowing, coords.get("mu"), coords["alpha"], coords.get("f0"),
                             axis_eta=coords.get("eta"), **fresnel_of(c))


def infer(values: np.ndarray, names: list[str], reference: Reference, pins: dict, step: float,
          audit_channels: list[int] | None = None, keep_runners: int = 3,
          explicit: dict[str, np.ndarray] | None = None, tolerance: float | None = None) -> Inference:
    """The best conventions for ``values`` (*grid, channels) — see the module docstring. Meanings with the exact
    dielectric Fresnel factor are searched in a second round, only when nothing fits without them (or from the
    start when ``eta`` or the channels are pinned): each of their cells costs a quadrature."""
    grid = values.shape[:-1]
    ndim = len(grid)
    precision = Precision(step, tolerance)
    chosen = list(range(values.shape[-1])) if audit_channels is None else audit_channels
    meanings = allowed_meanings(ndim, pins, values.shape[-1], reference)
    candidates = geometries(ndim, pins, explicit, grid, reference.shadowings, reference.third_kinds)
    if not candidates:
        sizes = ", ".join(f"{k}: {len(v)}" for k, v in (explicit or {}).items())
        raise ArgumentError(f"no array axis has as many samples as the --axis values ({sizes}; shape {grid})",
                            where="axes")
    dielectric_pinned = any(m == "E_dielectric" for ms in meanings for m in ms)
    if dielectric_pinned and "eta" not in pins:  # the table's index of refraction is found, not assumed
        candidates = _with_fitted_eta(values, candidates, reference, chosen)
    best, runners, order = _measured(values, names, reference, pins, precision, chosen, candidates, meanings)
    extra = [m for m in DIELECTRIC_BY_NDIM[ndim] if reference.supports(m)]
    if extra and not best.fits and "channels" not in pins and "eta" not in pins:
        # a 3-D table's exact-Fresnel round ranks the geometries Schlick's E_f0 ranked first (each of its cells is a
        # quadrature at its own η): the two factors differ by a few per cent, a wrong geometry by far more
        wider = (_with_fitted_eta(values, candidates, reference, chosen) if ndim == 2
                 else order[:DIELECTRIC_GEOMETRIES_3D] if ndim == 3 else candidates)
        second = _measured(values, names, reference, pins, precision, chosen, wider, [ms + extra for ms in meanings])
        if second[0].fits or second[0].rank < best.rank:
            best, runners, _ = second
    return Inference(best, runners[:keep_runners], len(candidates), dict(reference.computed))


def _measured(values, names, reference, pins, precision, chosen, candidates, meanings):
    """:func:`_rounds`, its best measured on every cell where the rounds ranked on a subgrid: whether it fits is
    decided there (on a coarse subgrid a smooth misfit's curvature passes for noise and widens the tolerance)."""
    best, runners, index, order = _rounds(values, names, reference, pins, precision, chosen, candidates, meanings)
    if index is not None:
        best = _complete(values, names, best, reference, precision)
    return best, runners, order


def _with_fitted_eta(values, candidates, reference, chosen) -> list[Convention]:
    """The DIELECTRIC_GEOMETRIES geometries of a 2-D table that the exact dielectric factor at η = ETA fits best
    on the stage-1 subset, each with the index of refraction at which it fits: η solves
    mean(table − E_dielectric(η)) = 0 on the subset (E_dielectric grows with η at every cell) by Brent's method.

    A wrong η shifts the whole table by a smooth amount, so the true geometry ranks among the first few at
    η = 1.5: first or second for 16×16 tables made at η = 1.2, 1.33, 1.5, 1.8, 2.4 and 3 (measured when this was
    written; tests/audit/test_fresnel_tables.py keeps η = 1.33 and 1.5). Schlick's factor with a free f0, or an
    interpolation in f0 between two exact η, ranked it 5th to 60th: they are several per cent off at grazing cells,
    as much as a wrong sample position."""
    grid = values.shape[:-1]
    index = [_subset(n, SUBSET_F90) for n in grid]
    mesh = _mesh(grid, index)
    sample = values[np.ix_(*index)]
    ranked = []
    for c in candidates:
        coords = coordinates(c, grid, mesh)
        with reference.ranking():
            exact, _ = reference.meaning("E_dielectric", c.shadowing, coords["mu"], coords["alpha"], eta=ETA)
        for channel in chosen:
            data = sample[..., channel]
            ok = np.isfinite(data)
            if ok.any():
                ranked.append((float(np.max(np.abs(data - exact)[ok])), channel, c))
    ranked.sort(key=lambda item: item[0])
    out = []
    for _, channel, c in ranked[:DIELECTRIC_GEOMETRIES]:
        coords = coordinates(c, grid, mesh)
        data = sample[..., channel]
        ok = np.isfinite(data)

        def gap(eta: float, c=c, coords=coords, data=data, ok=ok) -> float:
            exact, _ = reference.meaning("E_dielectric", c.shadowing, coords["mu"], coords["alpha"], eta=eta)
            return float(np.mean(data[ok] - exact[ok]))

        low, high = 1.0 + 1e-4, min(10.0, reference.eta_max)
        at_high = gap(high)
        if at_high > 0 and reference.eta_max > high:
            high = reference.eta_max
            at_high = gap(high)
        if gap(low) > 0 > at_high:
            out.append(replace(c, eta=float(optimize.brentq(gap, low, high, xtol=1e-7, rtol=1e-10))))
    return list(dict.fromkeys(out)) or [replace(c, eta=ETA) for _, _, c in ranked[:DIELECTRIC_GEOMETRIES]]


def _rounds(values, names, reference, pins, precision, chosen, candidates,
            meanings) -> tuple[Hypothesis, list[Hypothesis], list[np.ndarray] | None, list[Convention]]:
    """Stage 1 (cheap meanings first, the expensive ones only if no cheap one fits loosely) and stage 2: the
    best hypothesis, the runners-up, the subgrid they were measured on (None: every cell), and the candidates in
    stage 1's order."""
    grid = values.shape[:-1]
    cheap = [[m for m in meanings[k] if not Reference.expensive(m)] for k in range(values.shape[-1])]
    scored = _stage1(values, candidates, reference, cheap, chosen, SUBSET)
    # "loosely": a median residual within twice the storage precision plus 1e-3 (a Monte-Carlo table's median residual
    # is about 0.67 σ); a split-sum scale read as E is off by a median 1e-2
    loose = 2.0 * (precision.step + 1e-3)
    if (not scored or scored[0][0] > loose) and any(Reference.expensive(m) for ms in meanings for m in ms):
        scored = _stage1(values, candidates, reference, meanings, chosen, SUBSET_F90)
    keep = STAGE2_F90 if any(Reference.expensive(m) for _, c in scored[:STAGE2] for m in c.meanings if m) else STAGE2
    search = ("mu_floor" not in pins, "alpha_floor" not in pins)
    top = [c for _, c in scored[:max(keep, 2)]]
    # a large table's candidates are ranked on a fixed subgrid (its size, not the table's, bounds the work of the
    # inference), clamps searched on its boundary rows; only the best is then measured on every cell
    index = (inference_index(grid, RANK_CELLS if keep == STAGE2_F90 else INFER_CELLS)
             if int(np.prod(grid)) > SUBGRID_CELLS else None)
    finals = [_stage2(values, names, c, reference, precision, chosen, search, index) for c in top]
    _same_noise(finals, precision)
    finals.sort(key=lambda h: h.rank)
    finals[0] = _retry_channels(values, names, finals[0], reference, precision, chosen, meanings, index)
    finals[0] = _relayout_channels(values, names, finals[0], reference, precision, chosen, meanings, index)
    return finals[0], finals[1:], index, [c for _, c in scored]


def _complete(values, names, best: Hypothesis, reference, precision) -> Hypothesis:
    """``best`` (found on a subgrid) measured on every cell, channel by channel; a channel stored in another
    layout (:func:`_relayout_channels`) is judged at the tolerance its own layout had on the subgrid."""
    c = best.convention
    fits = []
    for fit in best.channels:
        k = names.index(fit.channel)
        alone = replace(c, meanings=tuple(fit.meaning if j == k else None for j in range(len(names))))
        judged = Precision(precision.step, fit.tolerance) if fit.layout else precision
        full = full_hypothesis(values, alone, reference, names, judged, [k]).channels[0]
        if fit.layout:
            full.layout, full.noise = fit.layout, fit.noise
        fits.append(full)
    return Hypothesis(c, fits)


def _same_noise(hypotheses: list[Hypothesis], precision: Precision) -> None:
    """Every hypothesis's channels judged with the table's noise: per channel, the smallest σ̂ any of them saw. The
    noise is the table's, not a hypothesis's: on a coarse grid a smooth misfit's curvature survives the second
    differences and would otherwise widen a wrong hypothesis's tolerance until it "fits" most cells."""
    if precision.tolerance is not None:
        return
    sigma: dict[str, float] = {}
    for h in hypotheses:
        for fit in h.channels:
            if fit.residual is not None and np.isfinite(fit.noise):
                sigma[fit.channel] = min(sigma.get(fit.channel, np.inf), fit.noise)
    for h in hypotheses:
        for fit in h.channels:
            if fit.channel in sigma:
                fit.judged(sigma[fit.channel])


def _stage1(values, candidates, reference, meanings, chosen, k) -> list[tuple[float, Convention]]:
    with reference.ranking():
        return _rank(values, candidates, reference, meanings, chosen, k)


def _rank(values, candidates, reference, meanings, chosen, k) -> list[tuple[float, Convention]]:
    grid = values.shape[:-1]
    index = [_subset(n, k) for n in grid]
    mesh = _mesh(grid, index)
    sample = values[np.ix_(*index)] if grid else values
    out = []
    for c in candidates:
        coords = coordinates(c, grid, mesh)
        picks, best = [], float("inf")
        for channel in range(values.shape[-1]):
            if channel not in chosen or not meanings[channel]:
                picks.append(None)
                continue
            data = sample[..., channel]
            ok = np.isfinite(data)
            residuals = {}
            for meaning in meanings[channel]:
                if meaning == "E_schlick" and c.free_f0:
                    c = _fit_schlick(c, reference, coords, data)
                    if not SCHLICK_ENDS < c.schlick_f0 < 1.0 - SCHLICK_ENDS:
                        continue  # f0 = 0 is DFG_f90 and f0 = 1 is E: the meanings without a fitted number
                exact, _ = _exact(reference, c, meaning, coords)
                residuals[meaning] = float(np.median(np.abs(data[ok] - exact[ok]))) if ok.any() else float("inf")
            meaning = min(residuals, key=residuals.get)
            picks.append(meaning)
            best = min(best, residuals[meaning])
        out.append((best, replace(c, meanings=tuple(picks))))
    out.sort(key=lambda item: item[0])
    return out


def _fit_schlick(c: Convention, reference, coords: dict, data: np.ndarray) -> Convention:
    """``c`` with the f0 at which Schlick's factor fits ``data`` best in least squares: ∫ f cos F_Schlick =
    f0·(E − F90) + F90 is linear in f0, so f0 = ⟨d − F90, E − F90⟩ / ⟨E − F90, E − F90⟩, clipped to [0, 1]."""
    E, _ = _exact(reference, c, "E", coords)
    bias, _ = _exact(reference, c, DFG_F90, coords)
    ok = np.isfinite(data)
    scale = (E - bias)[ok]
    f0 = float(np.sum((data[ok] - bias[ok]) * scale) / max(float(np.sum(scale * scale)), 1e-300)) if ok.any() else 0.0
    return replace(c, schlick_f0=float(np.clip(f0, 0.0, 1.0)))


def _fit(data: np.ndarray, exact: np.ndarray, error: np.ndarray, name: str, meaning: str,
         precision: Precision) -> ChannelFit:
    residual = data - exact
    ok = np.isfinite(residual)
    if not ok.any():
        return ChannelFit(name, meaning, float("inf"), float("inf"), float("inf"), (), 0.0, 0.0, residual, exact,
                          cells=int(residual.size), bad=np.ones(residual.shape, dtype=bool))
    magnitude = np.where(ok, np.abs(residual), np.inf)  # a non-finite cell is infinitely wrong
    # the worst finite cell (non-finite ones are listed as bad cells of their own)
    worst = tuple(int(i) for i in np.unravel_index(int(np.argmax(np.where(ok, magnitude, -1.0))), residual.shape))
    sigma = noise_sigma(np.where(ok, residual, 0.0))
    factor = max(NOISE_FACTOR, float(np.sqrt(2.0 * np.log(2.0 * residual.size))) + 1.0)
    base = precision.step * max(1.0, float(np.max(np.abs(exact[ok])))) + float(np.max(error[ok]))
    tolerance = precision.tolerance if precision.tolerance is not None else base + factor * sigma
    bulk = precision.tolerance if precision.tolerance is not None else base + 2.0 * sigma
    bad = ~(magnitude <= tolerance)
    r = residual[ok]
    return ChannelFit(name, meaning, float(np.max(np.abs(r))), float(np.sqrt(np.mean(r * r))),
                      float(np.median(magnitude)), worst, tolerance, sigma, residual, exact,
                      float(np.std(exact[ok])), cells=int(residual.size), bad=bad, within=int(np.sum(~bad)),
                      bulk=bulk, base=base, factor=factor)


#: One channel's residuals judged against the tolerance (the F_avg tables of :mod:`.fresnel_average` too).
fit_channel = _fit


def full_hypothesis(values, c: Convention, reference, names, precision, chosen, index=None) -> Hypothesis:
    """Residuals of ``c`` on every cell, or on the cells ``index`` (one index vector per axis)."""
    grid = values.shape[:-1]
    sampled = index is not None
    index = index if sampled else [np.arange(n) for n in grid]
    mesh = _mesh(grid, index)
    coords = coordinates(c, grid, mesh)
    data = values[np.ix_(*index)] if sampled else values
    fits = []
    for channel, meaning in enumerate(c.meanings):
        if channel not in chosen or meaning is None:
            continue
        # E_avg is a quadrature over μ per α (~1 ms a cell): a large 1-D table's budget is the expensive one
        kind = "expensive" if Reference.expensive(meaning) or meaning in ("E_avg", "1-E_avg") else "cheap"
        if sampled or int(np.prod(grid)) <= EXACT_CELLS[kind]:
            exact, error = _exact(reference, c, meaning, coords)
            fit = _fit(data[..., channel], exact, error, names[channel], meaning, precision)
        else:
            fit = _interpolated_fit(data[..., channel], c, meaning, reference, names[channel], precision, kind)
        if fit.worst:
            stored = stored_axis_values(c, grid, [np.asarray([index[a][w]]) for a, w in enumerate(fit.worst)])
            fit.worst_at = {k: float(np.ravel(v)[0]) for k, v in stored.items()}
            fit.worst = tuple(int(index[a][w]) for a, w in enumerate(fit.worst))
        fit.sampled = sampled
        fits.append(fit)
    return Hypothesis(c, fits)


def _interpolated_fit(data: np.ndarray, c: Convention, meaning: str, reference, name: str, precision: Precision,
                      kind: str) -> ChannelFit:
    """A channel of a large table against an interpolated reference (:func:`.interpolated.measured`)."""
    grid = data.shape

    def evaluate(index: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        return _exact(reference, c, meaning, coordinates(c, grid, index))

    return measured(data, evaluate, lambda value, error: _fit(data, value, error, name, meaning, precision),
                    PROBE_CELLS[kind], NODE_CELLS[kind], RESOLVE_CELLS[kind])


def _stage2(values, names, c: Convention, reference, precision, chosen, search=(True, True), index=None) -> Hypothesis:
    """Residuals of ``c`` (every cell, or the cells ``index``) with its endpoint clamps searched where the grid
    reaches below them."""
    grid = values.shape[:-1]
    mesh = _mesh(grid, index if index is not None else [np.arange(n) for n in grid])
    if c.free_f0 and "E_schlick" in c.meanings:  # refitted on the cells measured (stage 1 saw a subset)
        channel = c.meanings.index("E_schlick")
        data = values[np.ix_(*index)][..., channel] if index is not None else values[..., channel]
        c = _fit_schlick(c, reference, coordinates(c, grid, mesh), data)
    raw = coordinates(replace(c, mu_floor=0.0, alpha_floor=0.0), grid, mesh)
    best = full_hypothesis(values, c, reference, names, precision, chosen, index)
    if search[0] and "mu" in raw and float(np.min(raw["mu"])) < max(MU_FLOORS):
        trials = [full_hypothesis(values, replace(c, mu_floor=f), reference, names, precision, chosen, index)
                  for f in MU_FLOORS if f != c.mu_floor]
        best = _clamp_choice(best, trials)
    if search[1] and float(np.min(raw["alpha"])) < max(ALPHA_FLOORS):
        trials = [full_hypothesis(values, replace(best.convention, alpha_floor=f), reference, names, precision, chosen,
                                  index)
                  for f in ALPHA_FLOORS if f != best.convention.alpha_floor]
        best = _clamp_choice(best, trials)
    return best


def _clamp_choice(default: Hypothesis, trials: list[Hypothesis]) -> Hypothesis:
    """Another clamp replaces the default only if it puts more cells within the tolerance, or as many and at least
    halves the maximum residual: a clamp changes one boundary row, and noise in that row must not pick one."""
    challenger = min(trials, key=lambda h: (-h.within, h.score))
    if challenger.within > default.within:
        return challenger
    return challenger if challenger.within == default.within and challenger.score < 0.5 * default.score else default


def _retry_channels(values, names, best: Hypothesis, reference, precision, chosen, meanings,
                    cells=None) -> Hypothesis:
    """Channels the best geometry leaves unfitted with cheap meanings try the F90 ones (an LTC table's Fresnel
    channel beside its albedo): first on the stage-1 subset, in full only where that beats the current meaning."""
    c = best.convention
    current = {fit.channel: fit for fit in best.channels}
    grid = values.shape[:-1]
    index = [_subset(n, SUBSET_F90) for n in grid]
    coords = coordinates(c, grid, _mesh(grid, index))
    sample = values[np.ix_(*index)]
    picks = list(c.meanings)
    changed = False
    for channel in chosen:
        fit = current.get(names[channel])
        extra = [m for m in meanings[channel] if Reference.expensive(m) and m != c.meanings[channel]]
        if fit is None or fit.fits or not extra or fit.meaning is None:
            continue
        data = sample[..., channel]
        ok = np.isfinite(data)
        for meaning in extra:
            exact, _ = _exact(reference, c, meaning, coords)
            if ok.any() and float(np.median(np.abs(data[ok] - exact[ok]))) < fit.median:
                candidate = full_hypothesis(values, replace(c, meanings=tuple(
                    meaning if k == channel else m for k, m in enumerate(picks))), reference, names, precision,
                    [channel], cells)
                new, old = candidate.channels[0], current[names[channel]]
                if (-new.within, new.median, new.max) < (-old.within, old.median, old.max):
                    current[names[channel]] = candidate.channels[0]
                    picks[channel] = meaning
                    changed = True
    if not changed:
        return best
    return Hypothesis(replace(c, meanings=tuple(picks)), [current[f.channel] for f in best.channels])


def _layouts(c: Convention, grid: tuple[int, ...]) -> list[tuple[str, Convention]]:
    """The other layouts one channel of a table in convention ``c`` may have been stored in by mistake: reversed
    along some array axes, or (a square 2-D table) transposed, with or without reversals."""
    out = []
    ndim = len(grid)
    for flips in itertools.product((False, True), repeat=ndim):
        toggled = [a for a in range(ndim) if flips[a]]
        if toggled:
            out.append((f"reversed along array axis {', '.join(map(str, toggled))}",
                        replace(c, flips=tuple(f != g for f, g in zip(c.flips, flips, strict=True)))))
        if ndim == 2 and grid[0] == grid[1] and c.direction_axis is not None and not c.explicit:
            swapped = replace(c, direction_axis=c.roughness_axis, roughness_axis=c.direction_axis,
                              flips=tuple(f != g for f, g in zip(c.flips[::-1], flips, strict=True)))
            out.append(("transposed" + (f" and reversed along array axis {', '.join(map(str, toggled))}"
                                        if toggled else ""), swapped))
    return out


def _relayout_channels(values, names, best: Hypothesis, reference, precision, chosen, meanings,
                       cells=None) -> Hypothesis:
    """A channel the best convention leaves unnamed while it names another is tried in the other layouts
    (:func:`_layouts`): ranked on the stage-1 subset by the median residual, the best one measured on every cell.
    If that names the channel's meaning, the channel is reported as stored in that layout and measured in the
    table's convention (every misplaced cell is then a wrong cell, and ``--fix`` rewrites it in place)."""
    if not best.fits:
        return best
    c = best.convention
    grid = values.shape[:-1]
    index = [_subset(n, SUBSET) for n in grid]
    mesh = _mesh(grid, index)
    sample = values[np.ix_(*index)]
    current = {fit.channel: fit for fit in best.channels}
    picks = list(c.meanings)
    changed = False
    expensive = any(Reference.expensive(m) for m in c.meanings if m)
    for channel in chosen:
        fit = current.get(names[channel])
        if fit is None or fit.fits or fit.too_noisy or not meanings[channel]:
            continue
        data = sample[..., channel]
        ok = np.isfinite(data)
        if not ok.any():
            continue
        trials = []
        with reference.ranking():
            for label, alt in _layouts(c, grid):
                coords = coordinates(alt, grid, mesh)
                for meaning in meanings[channel]:
                    if meaning == "E_schlick" or Reference.expensive(meaning) and not expensive:
                        continue  # an expensive meaning only where the table's other channels have one
                    exact, _ = _exact(reference, alt, meaning, coords)
                    trials.append((float(np.median(np.abs(data[ok] - exact[ok]))), label, alt, meaning))
        if not trials:
            continue
        _, label, alt, meaning = min(trials, key=lambda item: item[0])
        trial = full_hypothesis(values, replace(alt, meanings=tuple(meaning if k == channel else None
                                                          for k in range(len(picks)))),
                      reference, names, precision, [channel], cells).channels[0]
        if not trial.fits:
            continue
        placed = full_hypothesis(values, replace(c, meanings=tuple(meaning if k == channel else None
                                                         for k in range(len(picks)))),
                       reference, names, precision, [channel], cells).channels[0]
        # judged at the tolerance of the channel in its own layout: the misplaced residual is no noise estimate
        magnitude = np.where(np.isfinite(placed.residual), np.abs(placed.residual), np.inf)
        placed.tolerance, placed.noise, placed.layout = trial.tolerance, trial.noise, label
        placed.bad = ~(magnitude <= trial.tolerance)
        placed.within = int(np.sum(~placed.bad))
        current[names[channel]] = placed
        picks[channel] = meaning
        changed = True
    if not changed:
        return best
    return Hypothesis(replace(c, meanings=tuple(picks)), [current[f.channel] for f in best.channels])
