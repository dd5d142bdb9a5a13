"""What an audit measures of one hypothesis (:mod:`.infer`): per channel, the residual against the exact values,
the tolerance every cell is judged against, and which cells are outside it; per hypothesis, the share of cells
within the tolerance that ranks it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .conventions import Convention

#: A meaning is named for a channel when more than this share of its cells lie within the tolerance.
MAJORITY = 0.5
#: Largest noise σ̂, as a share of the standard deviation of the exact table, a fit may have.
MAX_NOISE_SHARE = 0.05


@dataclass(frozen=True)
class Precision:
    """What a cell is judged against: the storage step (half a code, or half an ulp at 1) and, when given
    (``--tolerance``), an absolute tolerance that replaces the computed one."""

    step: float
    tolerance: float | None = None


@dataclass
class ChannelFit:
    """How one channel of the table matches a meaning under a convention."""

    channel: str
    meaning: str | None
    max: float
    rms: float
    median: float
    worst: tuple[int, ...]
    tolerance: float
    noise: float
    residual: np.ndarray | None = None  # table − exact, over the grid
    exact: np.ndarray | None = None
    spread: float = 0.0  # standard deviation of the exact values over the table
    worst_at: dict = field(default_factory=dict)  # μ, α (f0) of the worst cell
    cells: int = 0  # cells measured
    sampled: bool = False  # measured on a subgrid of the table (infer.inference_index), not on every cell
    bad: np.ndarray | None = None  # cells outside the tolerance or not finite (over the cells measured)
    within: int = 0  # cells within the tolerance
    #: How this channel alone is laid out when it is not laid out as the others ("transposed", "reversed along
    #: array axis 1"): its meaning is named by that layout; every cell is measured in the table's convention.
    layout: str = ""
    #: The largest median |residual| of a channel that fits: the storage step and the reference's error plus 2 σ̂
    #: (white noise has a median |r| of 0.67 σ). A smooth misfit on a coarse grid inflates σ̂ (its curvature shows
    #: in the second differences) and so the tolerance, but leaves most cells well above the noise level.
    bulk: float = float("inf")
    base: float = 0.0  # the tolerance before the noise term: storage step × max|exact| + the reference's error
    factor: float = 5.0  # k of the noise term k σ̂
    #: Bad cells whose exact value is interpolated, not computed (a large table past the audit's budget of exact
    #: cells, :mod:`.interpolated`): ``--fix`` refuses to write them. None when every value was computed.
    estimated: np.ndarray | None = None
    interpolation: dict | None = None  # how the exact values of a large table were had (:mod:`.interpolated`)

    def judged(self, sigma: float, given: float | None = None) -> None:
        """Judge every cell again with the table's noise ``sigma`` (the smallest σ̂ any hypothesis saw: a misfit adds
        to the noise of the residual, never removes it), or the ``given`` tolerance."""
        if self.residual is None or given is not None:
            return
        self.noise = sigma
        self.tolerance = self.base + self.factor * sigma
        self.bulk = self.base + 2.0 * sigma
        magnitude = np.where(np.isfinite(self.residual), np.abs(self.residual), np.inf)
        self.bad = ~(magnitude <= self.tolerance)
        self.within = int(np.sum(~self.bad))

    @property
    def too_noisy(self) -> bool:
        """Noise above MAX_NOISE_SHARE of the table's own spread: random data would 'fit' anything."""
        return bool(self.noise > MAX_NOISE_SHARE * self.spread)

    @property
    def fits(self) -> bool:
        """The meaning is named: more than MAJORITY of the cells lie within the tolerance (a handful of wrong cells
        never changes the convention found; they are listed as bad cells instead)."""
        return (self.meaning is not None and self.cells > 0 and not self.too_noisy
                and (bool(self.layout) or self.within > MAJORITY * self.cells and self.median <= self.bulk))

    @property
    def clean(self) -> bool:
        """Every cell within the tolerance (what an exit status of 0 needs)."""
        return self.fits and self.within == self.cells

    def summary(self) -> dict:
        return {"channel": self.channel, "meaning": self.meaning, "fits": self.fits, "clean": self.clean,
                "within": self.within, "cells": self.cells, "bad": self.cells - self.within, "max": self.max,
                "rms": self.rms, "median": self.median, "worst_cell": list(self.worst),
                "worst_at": self.worst_at, "tolerance": self.tolerance, "noise_sigma": self.noise,
                "too_noisy": self.too_noisy, "sampled": self.sampled, "layout": self.layout,
                "interpolated_reference": self.interpolation}


@dataclass
class Hypothesis:
    convention: Convention
    channels: list[ChannelFit]

    @property
    def score(self) -> float:
        fitted = [c.max for c in self.channels if c.meaning is not None]
        return min(fitted) if fitted else float("inf")

    @property
    def within(self) -> int:
        return sum(c.within for c in self.channels if c.meaning is not None)

    @property
    def cells(self) -> int:
        return sum(c.cells for c in self.channels if c.meaning is not None)

    @property
    def share(self) -> float:
        """The share of cells (of every channel with a meaning) within the tolerance: what ranks hypotheses."""
        return self.within / self.cells if self.cells else 0.0

    @property
    def median(self) -> float:
        """The median |table − exact| over every cell of every channel with a meaning (non-finite cells count as
        infinitely wrong): what breaks ties in the share."""
        parts = [np.where(np.isfinite(c.residual), np.abs(c.residual), np.inf).ravel()
                 for c in self.channels if c.meaning is not None and c.residual is not None]
        return float(np.median(np.concatenate(parts))) if parts else float("inf")

    @property
    def rank(self) -> tuple[int, float, float, float]:
        """Hypotheses that name a channel come first, ranked by the share of cells within the tolerance, then by
        the median residual, then by the maximum: a few wrong cells (a bright block, a swapped pair, a NaN, a
        Monte-Carlo table's zeroed column) must not decide which convention the rest is in; they are listed as
        wrong cells instead. Hypotheses that name nothing (the closest, when nothing fits) are ranked by the median
        residual alone: their tolerances come from a misfit's curvature, not from noise, so their shares mean
        nothing."""
        if self.fits:
            return (0, -round(self.share, 12), self.median, self.score)
        return (1, 0.0, self.median, self.score)

    @property
    def fits(self) -> bool:
        return any(c.fits for c in self.channels)

    @property
    def clean(self) -> bool:
        return bool(self.channels) and all(c.clean for c in self.channels)


@dataclass
class Inference:
    best: Hypothesis
    runners_up: list[Hypothesis]
    tested: int
    reference_cells: dict = field(default_factory=dict)

    @property
    def fits(self) -> bool:
        return self.best.fits

    @property
    def clean(self) -> bool:
        return self.best.clean

    @property
    def ambiguous(self) -> bool:
        return bool(self.runners_up) and self.best.fits and self.runners_up[0].share >= self.best.share
