"""``brdfnorm.audit.audit``: read (or take) a table, infer its convention, measure its errors, make its fix.

>>> import numpy as np, brdfnorm as bn
>>> from brdfnorm import lut
>>> from brdfnorm.audit import audit
>>> axes = {"mu": (np.arange(8) + 0.5) / 8, "alpha": np.maximum(np.linspace(0, 1, 8), 1e-8)}
>>> t = lut.compute(bn.load("ggx"), axes, average=False)
>>> r = audit(t["E"], "ggx", shadowing="height-correlated", dense=False, sweep=False)
>>> r.fits, r.best.convention.direction, r.best.convention.roughness
(True, 'mu-texel', 'alpha-node')
>>> audit(t["E"], "ggx", axes={"alpha": np.linspace(0.1, 1, 8)}, dense=False, sweep=False).fits
False
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field

import numpy as np

from .. import __version__
from ..errors import ArgumentError, BrdfnormError
from ..inputs import shorten
from ..inputs.limits import MAX_AUDIT_GRID_AXES, MAX_AUDIT_VALUES, MAX_CHANNELS
from ..models.base import Model
from . import quality
from .conventions import parse_pins, stored_axis_values
from .fresnel_average import AverageConvention, infer_average, requested
from .infer import Hypothesis, Inference, infer
from .readers import DTYPES, Source, read_table
from .reference import Reference
from .spans import written_step


@dataclass
class AuditResult:
    """What an audit found: the best convention (``best``), the next ones (``runners_up``), per-channel error
    statistics and residual arrays (``best.channels``), interpolation error at dense points, error against
    resolution, cells that are not finite / negative / above 1, and the exact table in the input's layout."""

    source: Source
    inference: Inference
    bad_cells: dict
    interpolation: dict = field(default_factory=dict)
    resolution: dict = field(default_factory=dict)
    fixed: np.ndarray | None = None
    seconds: float = 0.0
    model: str = ""
    wrong_cells: dict = field(default_factory=dict)  # channel -> {"cells": [...], "regions": [...]}
    tolerance_given: float | None = None
    approximation: dict | None = None  # a fitted approximation the table is, and its error against exact values
    step: float = 0.0  # the storage step the tolerance starts from (the format's, or a text's written precision)

    @property
    def best(self) -> Hypothesis:
        return self.inference.best

    @property
    def runners_up(self) -> list[Hypothesis]:
        return self.inference.runners_up

    @property
    def fits(self) -> bool:
        """A convention is named: it fits most cells of at least one channel."""
        return self.inference.fits

    @property
    def passes(self) -> bool:
        """Every cell of every audited channel within the tolerance of the named convention (exit status 0)."""
        return self.inference.clean

    @property
    def unnamed(self) -> list[str]:
        """Audited channels whose meaning the audit cannot name (``--fix`` refuses to guess them)."""
        return [c.channel for c in self.best.channels if not c.fits]

    @property
    def unfixable(self) -> list[str]:
        """Channels with cells outside the tolerance whose exact value was interpolated, not computed (a large
        table past the audit's budget of exact cells): ``--fix`` refuses to write them."""
        return [c.channel for c in self.best.channels if c.estimated is not None and c.estimated.any()]

    @property
    def headline(self) -> str:
        """One sentence: the convention and how many cells it fits, or that none fits most cells."""
        h = self.best
        if not h.fits:
            return (f"NO HYPOTHESIS FITS most cells; the closest fits {_count(h.within)} of {_count(h.cells)} cells "
                    f"(median error {h.median:.3g})")
        bad = h.cells - h.within
        residuals = [c.residual[c.bad] for c in h.channels if c.meaning is not None and c.bad is not None]
        wrong = np.concatenate([r.ravel() for r in residuals]) if residuals else np.zeros(0)
        finite = wrong[np.isfinite(wrong)]
        tolerance = max(c.tolerance for c in h.channels if c.meaning is not None)
        text = f"convention fits {_count(h.within)} of {_count(h.cells)} cells to {tolerance:.2g}"
        if not bad:
            return text
        text += f"; {_count(bad)} cell{'s' if bad != 1 else ''} {'are' if bad != 1 else 'is'} wrong"
        if finite.size:
            text += f" by up to {float(np.max(np.abs(finite))):.2g}"
        if finite.size < wrong.size:
            text += f" ({wrong.size - finite.size} not finite)"
        return text

    @property
    def stats(self) -> list[dict]:
        return [c.summary() for c in self.best.channels]

    @property
    def errors(self) -> dict[str, np.ndarray]:
        return {c.channel: c.residual for c in self.best.channels}

    def to_json(self) -> dict:
        def hyp(h: Hypothesis) -> dict:
            return {"convention": h.convention.describe(), "text": h.convention.text(), "fits": h.fits,
                    "within": h.within, "cells": h.cells, "share": h.share, "median": h.median,
                    "channels": [c.summary() for c in h.channels]}

        return {
            "file": self.source.path, "format": self.source.fmt, "array": self.source.name, "model": self.model,
            "shape": list(self.source.grid_shape), "channels": self.source.channel_names,
            "storage": self.source.stored, "storage_step": self.step,
            "verdict": "fits" if self.fits else "no hypothesis fits", "ambiguous": self.inference.ambiguous,
            "best": hyp(self.best), "runners_up": [hyp(h) for h in self.runners_up],
            "hypotheses_tested": self.inference.tested, "reference_cells": self.inference.reference_cells,
            "passes": self.passes, "headline": self.headline, "unnamed_channels": self.unnamed,
            "tolerance_given": self.tolerance_given, "approximation": self.approximation,
            "wrong_cells": self.wrong_cells,
            "bad_cells": self.bad_cells, "interpolation": self.interpolation, "resolution": self.resolution,
            "notes": self.source.notes, "seconds": self.seconds, "brdfnorm": __version__,
        }

    def fix_meta(self) -> dict:
        return {"brdfnorm": __version__, "made_by": "brdfnorm audit --fix", "model": self.model,
                "convention": self.best.convention.describe(), "replaces": os.path.basename(self.source.path)}


#: Meanings that are not bounded by 1 (the cloth channel's Neubelt visibility does not conserve energy: its
#: albedo reaches 7 at grazing views of a narrow sheen).
UNBOUNDED = ("DFG_cloth",)


def _bad_cells(source: Source, inference: Inference, model: Model, limit: int = 20) -> dict:
    """Cells that are not finite, negative, or above 1 where the quantity is bounded by 1: a lobe that conserves
    energy (its declared ``energy`` says "conserved", or says nothing) and a meaning that is not UNBOUNDED."""
    values = source.values
    slack = max(source.step(), 1e-12)  # rounding of a stored 1.0 is not a violation
    conserves = model.conserves_energy is not False  # a lobe that does not say is held to E ≤ 1
    bounded = np.full(values.shape[-1], conserves)
    for channel, meaning in enumerate(inference.best.convention.meanings):
        bounded[channel] &= meaning not in UNBOUNDED
    out = {}
    for name, mask in (("non_finite", ~np.isfinite(values)),
                       ("negative", np.isfinite(values) & (values < -slack)),
                       ("above_one", np.isfinite(values) & (values > 1 + slack) & bounded)):
        where = np.argwhere(mask)
        out[name] = {"count": int(len(where)),
                     "cells": [[int(i) for i in w] for w in where[:limit]],
                     "values": [float(values[tuple(w)]) for w in where[:limit]]}
    return out


#: Tables of more cells are not compared with the fitted approximations (each geometry's formula over every cell:
#: ~18 s for a 1024² table); engines tabulate those formulas at 16² to 64².
MAX_RECOGNISED = 256 * 256


def _approximation(source: Source, reference: Reference, pins: dict, explicit: dict, step: float,
                   model: str) -> dict | None:
    """A fitted approximation (:mod:`.approximations`) the table is a tabulation of, with its error against the exact
    quantities it approximates in the same geometry (the shadowing form closer to it by the median)."""
    from dataclasses import replace

    from .approximations import recognise
    from .conventions import geometries
    from .infer import Precision, full_hypothesis

    grid = source.grid_shape
    if len(grid) != 2:
        return None
    if math.prod(grid) > MAX_RECOGNISED:
        source.notes.append(f"not compared with fitted approximations: more than {MAX_RECOGNISED} cells")
        return None
    found = recognise(source.values, source.channel_names, geometries(2, pins, explicit, grid, reference.shadowings),
                      step, model)
    if found is None:
        return None
    channels = list(range(len(source.channel_names)))
    trials = [full_hypothesis(source.values, replace(found["convention"], shadowing=shadowing,
                                                     meanings=tuple(found["meanings"])),
                              reference, source.channel_names, Precision(step), channels)
              for shadowing in reference.shadowings]
    h = min(trials, key=lambda t: t.median)
    return {"name": found["name"], "source": found["source"], "within": found["within"], "cells": found["cells"],
            "convention": h.convention.text(), "channels": [
                {"channel": c.channel, "approximates": c.meaning, "max": c.max, "median": c.median, "rms": c.rms,
                 "worst_cell": list(c.worst), "worst_at": c.worst_at} for c in h.channels]}


#: Tables of more cells are tried as F_avg tables only when the pins ask (the search computes the exact F_avg of
#: every geometry on every cell: 2 s of CPU for a 64² table, 8 s for 128²); engines tabulate F_avg at 16² to 64².
MAX_AVERAGE_FALLBACK = 64 * 64


def _infer(source: Source, reference: Reference, pins: dict, step: float, chosen: list[int] | None,
           explicit: dict, tolerance: float | None) -> tuple[Inference, dict | None]:
    """The microfacet conventions (:func:`.infer.infer`), or the F_avg ones (:mod:`.fresnel_average`) when the pins
    ask for them or when no microfacet convention fits a 1-D or 2-D table whose parts are not pinned (with the
    fitted formula the table is, if any)."""
    if requested(pins):
        return infer_average(source.values, source.channel_names, pins, step, chosen, explicit, tolerance)
    inference = infer(source.values, source.channel_names, reference, pins, step, chosen, explicit=explicit,
                      tolerance=tolerance)
    if (inference.fits or len(source.grid_shape) > 2 or set(pins) - {"flip"}
            or set(explicit) - {"eta", "f0"}):
        return inference, None
    if math.prod(source.grid_shape) > MAX_AVERAGE_FALLBACK:  # every geometry's exact F_avg on every cell
        source.notes.append(f"not tried as an F_avg table: more than {MAX_AVERAGE_FALLBACK} cells (--as "
                            "channels=F_avg tries it)")
        return inference, None
    try:
        other, fit = infer_average(source.values, source.channel_names, pins, step, chosen, explicit, tolerance)
    except ArgumentError:  # the table's axes are none of an F_avg table's: the microfacet result stands
        return inference, None
    return (other, fit) if other.fits or fit is not None else (inference, None)


def _count(n: int) -> str:
    return f"{n:,}".replace(",", "\u2009")  # thin spaces: "1 015 of 1 024"


#: Wrong cells listed one by one per channel (all of them are counted and grouped into regions; a table this
#: wrong is named only if most of its cells are right, so only tables of over 200 000 cells reach the cap).
MAX_LISTED = 100_000


def wrong_cells(source: Source, hypothesis: Hypothesis) -> dict:
    """Every cell outside the tolerance (or not finite) of each channel whose meaning is named: its table indices,
    its axis values in the table's own variables (μ or θ, r or α, f0, as stored), the stored, exact and error
    values; and the cells grouped into connected regions (cells touching by a side or a corner)."""
    from scipy import ndimage

    grid = source.grid_shape
    mesh = list(np.meshgrid(*[np.arange(n) for n in grid], indexing="ij"))
    at = stored_axis_values(hypothesis.convention, grid, mesh)
    out = {}
    for fit in hypothesis.channels:
        if not fit.fits or fit.bad is None or fit.sampled or not fit.bad.any():
            continue
        k = source.channel_names.index(fit.channel)
        labels, count = ndimage.label(fit.bad, structure=np.ones((3,) * len(grid), dtype=bool))
        cells = []
        bad = np.argwhere(fit.bad)
        for index in bad[:MAX_LISTED]:
            i = tuple(int(v) for v in index)
            stored, exact = float(source.values[i + (k,)]), float(fit.exact[i])
            cells.append({"index": list(i), "at": {name: float(v[i]) for name, v in at.items()},
                          "stored": stored, "exact": exact, "error": stored - exact, "region": int(labels[i])})
        magnitude = np.where(np.isfinite(fit.residual), np.abs(fit.residual), np.inf)
        sizes = np.bincount(labels.ravel(), minlength=count + 1)
        largest = ndimage.maximum(magnitude, labels, index=np.arange(1, count + 1)) if count else []
        regions = [{"region": label, "cells": int(sizes[label]), "from": [int(s.start) for s in box],
                    "to": [int(s.stop) - 1 for s in box], "max_error": float(top)}
                   for label, (box, top) in enumerate(zip(ndimage.find_objects(labels), np.atleast_1d(largest),
                                                          strict=True), start=1)]
        out[fit.channel] = {"meaning": fit.meaning, "layout": fit.layout, "tolerance": fit.tolerance,
                            "count": int(len(bad)), "listed": len(cells), "regions": regions, "cells": cells}
    return out


def _as_source(table, options: dict) -> Source:
    scale = options.get("scale")
    if scale is not None and not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ArgumentError(f"{shorten(scale, 40)}: the scale must be a finite number > 0", where="scale")
    if isinstance(table, (str, os.PathLike)):
        return read_table(table, **options)
    try:
        shape = np.shape(table)  # from the metadata: a broadcast view is not materialised
    except ValueError:
        raise ArgumentError("not a regular array of numbers (rows of different lengths?)", where="table") from None
    if math.prod(shape) > MAX_AUDIT_VALUES:
        raise ArgumentError(f"a table of shape {shape} holds {math.prod(shape)} values, more than the "
                            f"{MAX_AUDIT_VALUES} an audit takes", where="table")
    try:
        array = np.asarray(table, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError("not an array of real numbers", where="table") from None
    if array.ndim == 0 or array.size < 2:
        raise ArgumentError("an audit needs a table of at least two values", where="table")
    if not np.isfinite(array).any():
        raise ArgumentError("no finite values in the table", where="table")
    names = options.pop("channel_names", None)
    if names is None:
        if array.ndim >= 3 and array.shape[-1] <= 4 and min(array.shape[:-1]) > 4:
            names = [str(i) for i in range(array.shape[-1])]
        else:
            array, names = array[..., None], ["0"]
    stored = options.get("dtype") or "float64"
    if stored not in DTYPES:
        raise ArgumentError(f"unknown dtype {stored!r} (known: {', '.join(DTYPES)})", where="dtype")
    # an array holds table values; ``dtype`` says how they were stored (its step sets the tolerance)
    scale = options.get("scale") or (float(np.iinfo(np.dtype(stored)).max) if stored.startswith(("uint", "int"))
                                     else 1.0)
    return Source("<array>", "array", "", array, names, stored, scale)


#: The domain of each axis an audit can be given: (lowest, highest, as said in an error).
AXIS_DOMAINS = {"mu": (0.0, 1.0, "[0, 1]"), "theta": (0.0, np.pi / 2, "[0, π/2] radians ([0°, 90°])"),
                "alpha": (0.0, np.inf, "α ≥ 0"), "f0": (0.0, 1.0, "[0, 1]"),
                "eta": (np.finfo(float).tiny, np.inf, "η > 0 (η < 1 where the light exits)")}


def _explicit_axes(axes: dict | None) -> dict[str, np.ndarray]:
    out = {}
    for name, values in (axes or {}).items():
        array = np.asarray(values, dtype=float)
        if name == "r":
            name, array = "alpha", array * array
        if name not in ("mu", "theta", "alpha", "f0", "eta"):
            raise ArgumentError(f"axis {shorten(repr(name), 40)}: known axes are mu, theta, alpha, r (alpha = r^2), "
                                "f0, eta", where="axes")
        if array.ndim != 1 or array.size < 2 or not np.all(np.isfinite(array)):
            raise ArgumentError(f"axis {name}: at least two finite values", where="axes")
        low, high, text = AXIS_DOMAINS[name]
        if array.min() < low or array.max() > high:
            raise ArgumentError(f"axis {name}: values from {array.min():.6g} to {array.max():.6g} leave its domain "
                                f"{text}", where="axes")
        steps = np.diff(array)
        if not (np.all(steps > 0) or np.all(steps < 0)):
            raise ArgumentError(f"axis {name}: values must increase or decrease monotonically", where="axes")
        out[name] = array
    if "mu" in out and "theta" in out:
        raise ArgumentError("give mu or theta, not both", where="axes")
    return out


def audit(table, model: Model | str = "ggx", *, channel: str | int | None = None, dense: bool = True,
          sweep: bool = True, fix: bool = True, params: dict | None = None, read: dict | None = None,
          axes: dict[str, np.ndarray] | None = None, pins: dict[str, str] | None = None,
          tolerance: float | None = None, **convention: str) -> AuditResult:
    """Audit ``table`` (an array (*grid[, channels]) or a path, read with ``read`` options: fmt, array, shape,
    dtype, order, scale) as a table of ``model`` (a name or a Model, with ``params``). ``pins`` and keywords
    (``convention``) pin parts of the convention (axes, direction, roughness, f0, flip, shadowing, mu_floor,
    alpha_floor, channels, eta; see :mod:`.conventions`); the pin ``axes=mu,alpha`` (the roles of the array axes)
    goes in ``pins``, as the keyword ``axes`` gives the values of an axis outright (``mu``, ``theta`` in radians,
    ``alpha``, ``r`` with α = r², ``f0``: values in array order, monotonic). ``dense`` measures the interpolation error,
    ``sweep`` the error against resolution. ``tolerance`` (absolute, in table units) replaces the tolerance computed
    from the storage precision, the reference's error and the table's noise.

    ``fixed`` is the table with every wrong cell of every channel replaced by its exact value in the convention
    found (cells within the tolerance are kept as read); it is None when a channel's meaning cannot be named."""
    if tolerance is not None and not (np.isfinite(tolerance) and tolerance > 0):
        raise ArgumentError("tolerance must be a positive number", where="tolerance")
    explicit = _explicit_axes(axes)
    from .. import load

    started = time.perf_counter()
    m = load(model) if isinstance(model, str) else model
    if params:
        m = m.with_params(**params)
    source = _as_source(table, dict(read or {}))
    grid = source.grid_shape
    if source.values.size > MAX_AUDIT_VALUES or len(grid) > MAX_AUDIT_GRID_AXES or source.values.shape[-1] > \
            MAX_CHANNELS:
        where = source.path if source.path != "<array>" else "table"
        raise ArgumentError(f"a table of {len(grid)} grid axes {tuple(grid)} and {source.values.shape[-1]} "
                            f"channel(s), {source.values.size} values: an audit takes at most "
                            f"{MAX_AUDIT_GRID_AXES} grid axes, {MAX_CHANNELS} channels and {MAX_AUDIT_VALUES} "
                            "values (give --shape or "
                            "--array for another reading)", where=where)
    try:
        pins = parse_pins({**(pins or {}), **convention})
    except BrdfnormError:
        raise
    except (ValueError, TypeError) as error:
        raise ArgumentError(shorten(error, 200), where="pins") from None
    flip = pins.get("flip")
    if flip is not None and not all(part.strip() in ("0", "1") for part in str(flip).split(",")):
        raise ArgumentError(f"flip={shorten(flip, 40)}: 0 or 1 per array axis, comma-separated (e.g. flip=0,1)",
                            where="pins")
    reference = Reference(m)
    chosen = None
    if channel is not None:
        names = source.channel_names
        if isinstance(channel, int) or str(channel).isascii() and str(channel).isdigit():
            k = int(channel)
            if not 0 <= k < len(names):
                raise ArgumentError(f"channel index {k} outside 0..{len(names) - 1}", where="channel")
        elif channel in names:
            k = names.index(channel)
        else:
            raise ArgumentError(f"no channel {channel!r} (channels: {', '.join(names)})", where="channel")
        chosen = [k]
    step = source.step()
    written = written_step(source)
    if written is not None and written[1] and source.stored == "float64":
        source.stored = "float32"  # the fix writes single-precision values back, as the file holds
        source.notes.append("decimal text of single-precision values: float32's step is the storage step")
        step = source.step()
    elif written is not None and written[0] > step:  # decimal text keeps fewer digits than its float type
        step = written[0]
        source.notes.append(f"numbers written to about {step:.2g} (half their last digit): that is the storage "
                            "step")
    inference, average_fit = _infer(source, reference, pins, step, chosen, explicit, tolerance)
    result = AuditResult(source, inference, _bad_cells(source, inference, m), model=m.name,
                         wrong_cells=wrong_cells(source, inference.best), tolerance_given=tolerance, step=step)
    best = inference.best
    grid = source.grid_shape
    averages = isinstance(best.convention, AverageConvention)  # an F_avg table: no lobe, no GPU lookups measured
    if averages:
        result.model = "none (the average of a Fresnel factor)"
        result.approximation = average_fit
    elif not result.passes and "channels" not in pins:
        result.approximation = _approximation(source, reference, pins, explicit, step, m.name)
    if (dense or sweep) and not averages:
        # the channels that fit (or, when none does, the closest): a renderer's error for a meaning it has
        measured = [f for f in best.channels if f.fits] or sorted(best.channels, key=lambda f: f.max)[:1]
        for fit in measured:
            if fit.meaning is None or fit.meaning in ("E_avg", "1-E_avg") and len(grid) != 1:
                continue
            points = quality.dense_points(best.convention, grid, quality.budget_points(fit.meaning))
            k = source.channel_names.index(fit.channel)
            if dense:
                e = quality.dense_error(source.values[..., k], best.convention, fit.meaning, reference, points)
                result.interpolation[fit.channel] = {"max": e.max, "rms": e.rms, "worst": e.worst,
                                                     "points": e.points, "of_grid": e.of_grid,
                                                     "density": quality.DENSITY}
            if sweep:
                result.resolution[fit.channel] = quality.sweep(best.convention, fit.meaning, reference, points,
                                                               len(grid))
    if fix and not result.unnamed and not result.unfixable:
        fixed = np.array(source.values, dtype=float)
        # only the wrong cells change: a cell within the tolerance is kept as read (a minimal diff)
        for fit in best.channels:
            k = source.channel_names.index(fit.channel)
            fixed[..., k] = np.where(fit.bad, fit.exact, fixed[..., k])
        result.fixed = fixed
    result.seconds = time.perf_counter() - started
    return result
