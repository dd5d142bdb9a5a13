"""The numbers behind ``brdfnorm report``: every computation of the page, as plain arrays, before any plotting.

Default study (the seed lobes phong, modified-phong, blinn-phong, blinn-phong-gaussian):

* :func:`factor_table` — normalization factors at L = N over n: seed 000's closed forms (2π/(n+1), 2π/(n+2),
  8π(2^(−n/2)+n)/((n+2)(n+4)), :mod:`brdfnorm.models.closed_forms`) against adaptive quadrature, and where over
  θ ∈ [0°, 89.9°] the albedo is largest (seeds 000 and 003 assume θ = 0 "without proof"; here it is searched).
* :func:`albedo_curves` — E(θ_o) at several n, raw and times the L = N factor (seed 002's open problem: the
  energy a normalized lobe loses towards grazing views).
* :func:`folklore` — Blinn-Phong's α(n) = 1/E(L = N) beside the folklore (n+8)/8π (seed 000 refutes it).
* :func:`seed003_fits` — seed 003's linear fit 0.17287429 + 0.01388682·n of the Gaussian Blinn-Phong factor over
  n ∈ [1, 512], against refits by :func:`brdfnorm.fit.fit`: the seed's own least-squares line, the commenter's
  hyperbola and the automatic choice of form.
* :func:`polar_lobes` — f(L, V)(N·L)·factor over L in the plane of N and V at a few view angles.

For any other model (a built-in name or a ``.brdf`` file), :func:`model_study` does the same over one float
parameter (the first declared one unless a sweep names another): factors at L = N and at the maximum over
directions, albedo curves and polar plots.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .. import load
from ..engine.methods import METHODS, albedo
from ..errors import ArgumentError
from ..models import closed_forms
from ..models.base import Model
from ..normalization import normalize

#: The seed lobes of the default study, in page order.
SEED_LOBES = ("phong", "modified-phong", "blinn-phong", "blinn-phong-gaussian")
#: Seed 000's closed-form albedo at L = N for each lobe that has one (over the light, as the albedo is defined).
CLOSED_FORM_OF = {"phong": "phong-original", "modified-phong": "phong-modified", "blinn-phong": "blinn-phong-normal"}


@dataclass(frozen=True)
class StudyConfig:
    """Grids and tolerances; :meth:`quick` is a reduced configuration for tests."""

    table_n: tuple[float, ...] = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 4096, 10000)
    curve_n: tuple[float, ...] = (1, 10, 100, 1000)
    theta_count: int = 90  # θ_o grid 0°…89° (whole degrees with 90 points)
    alpha_count: int = 161  # n grid of the closed-form α(n) curves
    fit_count: int = 512  # n grid over seed 003's [1, 512] (every integer with 512 points, as the seed sampled)
    fit_samples: int = 64  # geometrically spaced points of that grid given to the minimax fits
    polar_n: float = 32.0
    polar_views: tuple[float, ...] = (0.0, 30.0, 60.0, 80.0)  # degrees
    polar_points: int = 361
    sweep_count: int = 11  # default sweep length of a model study
    curve_count: int = 4  # parameter values drawn as curves in a model study
    table_rtol: float = 1e-12  # the default study's factor tables
    search_rtol: float = 1e-9  # the default study's at="max" search
    plot_rtol: float = 1e-8  # curves
    # Models from files are GLSL compiled to numpy and, without a lobe hint, integrated with a sampled one:
    # a moderate tolerance and a coarser search grid keep a study of one file within a minute.
    model_rtol: float = 1e-9
    model_search_rtol: float = 1e-7
    model_search_points: int = 12
    #: Include seed 003's fits and the verify table (about 10 s; the quick configuration leaves them out).
    extras: bool = True

    @classmethod
    def quick(cls) -> StudyConfig:
        return cls(table_n=(1, 8, 64, 512, 4096), curve_n=(1, 100), theta_count=12, alpha_count=21,
                   fit_count=48, fit_samples=12, polar_views=(0.0, 60.0), polar_points=61, sweep_count=4,
                   curve_count=2, extras=False)

    @property
    def theta(self) -> np.ndarray:
        """The θ_o grid of the albedo curves, radians."""
        return np.radians(np.linspace(0.0, 89.0, self.theta_count))


#: Progress within a section: ``tick(detail, fraction)``, the fraction of the section done once ``detail`` starts.
Tick = Callable[[str, float], None]


def quiet_progress(detail: str, fraction: float) -> None:
    """The default :data:`Tick`: report nothing."""


# -- default study -----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class FactorTable:
    n: np.ndarray  # (S,)
    closed: dict[str, np.ndarray]  # lobe -> (S,) closed-form factor (lobes with one)
    quadrature: dict[str, np.ndarray]  # lobe -> (S,) quadrature factor at L = N
    error: dict[str, np.ndarray]  # lobe -> (S,) relative error estimate of the quadrature factor
    theta_max: dict[str, np.ndarray]  # lobe -> (S,) θ (radians) of the largest albedo over θ ∈ [0°, 89.9°]
    max_over_normal: dict[str, np.ndarray]  # lobe -> (S,) E(θ_max)/E(0) − 1 (0 when the max is at N)
    certified: CertifiedFactors | None = None  # None where python-flint (brdfnorm[certified]) is not installed

    def relative_difference(self, lobe: str) -> np.ndarray:
        return self.quadrature[lobe] / self.closed[lobe] - 1.0


@dataclass(frozen=True)
class CertifiedFactors:
    """Guaranteed enclosures of the albedo at L = N for every lobe and n of the factor table
    (brdfnorm.engine.routes.certified)."""

    digits: int
    radius: dict[str, np.ndarray]  # lobe -> (S,) relative radius of the enclosure
    closed_inside: dict[str, np.ndarray]  # lobe -> (S,) the closed form lies inside the enclosure (lobes with one)
    quadrature_covered: dict[str, np.ndarray]  # lobe -> (S,) the quadrature estimate covers its distance to it


def certified_factors(n: np.ndarray, quadrature: dict, error: dict, digits: int = 30) -> CertifiedFactors | None:
    from ..engine.routes import certified
    from ..errors import ArgumentError

    try:
        certified.require_flint()
    except ArgumentError:
        return None
    radius, inside, covered = {}, {}, {}
    for lobe in SEED_LOBES:
        enclosures = [certified.enclose(load(lobe, n=k), 0.0, {"n": float(k)}, digits=digits)[0] for k in n]
        radius[lobe] = np.array([float(e.ball.rad()) / abs(e.value) for e in enclosures])
        # the float64 factor's relative error estimate against its distance from the certified albedo
        covered[lobe] = np.array([abs(1.0 / q - e.value) / e.value <= r + e.error / e.value
                                  for q, r, e in zip(quadrature[lobe], error[lobe], enclosures, strict=True)])
        if lobe in CLOSED_FORM_OF:
            inside[lobe] = np.array([certified.closed_form_inside(lobe, float(k), e)
                                     for k, e in zip(n, enclosures, strict=True)])
    return CertifiedFactors(digits, radius, inside, covered)


def factor_table(config: StudyConfig, tick: Tick = quiet_progress) -> FactorTable:
    n = np.asarray(config.table_n, dtype=float)
    closed, quad, error, theta_max, excess = {}, {}, {}, {}, {}
    parts = 2 * len(SEED_LOBES) + 1
    for index, lobe in enumerate(SEED_LOBES):
        model = load(lobe)
        tick(f"{lobe} at L = N", 2 * index / parts)
        at_normal = normalize(model, "normal", sweep={"n": n}, rtol=config.table_rtol, method="quadrature")
        quad[lobe] = at_normal.factor[:, 0, 0]
        error[lobe] = at_normal.error[:, 0, 0] / at_normal.albedo[:, 0, 0]
        if lobe in CLOSED_FORM_OF:
            closed[lobe] = 1.0 / closed_forms.CLOSED_FORMS[CLOSED_FORM_OF[lobe]].function(n)
        tick(f"{lobe}: searching for the maximum", (2 * index + 1) / parts)
        at_max = normalize(model, "max", sweep={"n": n}, rtol=config.search_rtol, method="quadrature")
        theta_max[lobe] = at_max.theta[:, 0]
        excess[lobe] = at_max.albedo[:, 0, 0] * at_normal.factor[:, 0, 0] - 1.0
    tick("certified enclosures", (parts - 1) / parts)
    return FactorTable(n, closed, quad, error, theta_max, excess, certified_factors(n, quad, error))


@dataclass(frozen=True)
class AlbedoCurves:
    title: dict[str, str]  # panel key -> title
    values: dict[str, np.ndarray]  # panel key -> (K,) parameter values of the curves
    parameter: str
    theta: np.ndarray  # (T,) radians
    albedo: dict[str, np.ndarray]  # panel key -> (K, T, C)

    def normalized(self, key: str) -> np.ndarray:
        """E(θ)·factor at L = N; the grid starts at θ = 0, so the factor is 1/E(0) of the same integrals."""
        curves = self.albedo[key]
        with np.errstate(divide="ignore", invalid="ignore"):  # a lobe with zero albedo has no factor: NaN/∞
            return curves / curves[:, :1, :]


def albedo_curves(config: StudyConfig, tick: Tick = quiet_progress) -> AlbedoCurves:
    n = np.asarray(config.curve_n, dtype=float)
    theta = config.theta
    curves = {}
    for index, lobe in enumerate(SEED_LOBES):
        tick(lobe, index / len(SEED_LOBES))
        # One batched call per lobe: the n values (K, 1) broadcast against the θ grid (1, T).
        swept = load(lobe).with_params(n=n[:, None])
        curves[lobe] = albedo(swept, theta[None, :], rtol=config.plot_rtol, method="quadrature").value
    return AlbedoCurves({lobe: lobe for lobe in SEED_LOBES}, {lobe: n for lobe in SEED_LOBES}, "n", theta, curves)


@dataclass(frozen=True)
class Folklore:
    n: np.ndarray  # (A,) dense grid
    exact: np.ndarray  # (A,) α(n) = 1/E(L = N), seed 000
    folklore: np.ndarray  # (A,) (n+8)/8π
    table_n: np.ndarray  # (S,)
    quadrature: np.ndarray  # (S,) α by quadrature at the table's n

    @property
    def relative_error(self) -> np.ndarray:
        """(n+8)/8π relative to the exact α(n)."""
        return self.folklore / self.exact - 1.0


def folklore(config: StudyConfig, table: FactorTable) -> Folklore:
    n = np.geomspace(0.1, 1e4, config.alpha_count)
    return Folklore(n, 1.0 / closed_forms.blinn_phong_albedo_normal(n), closed_forms.blinn_phong_folklore_factor(n),
                    table.n, table.quadrature["blinn-phong"])


@dataclass(frozen=True)
class FitCurve:
    label: str
    expression: str
    prediction: np.ndarray  # (F,) at the fit grid
    coefficients: tuple[float, ...]


@dataclass(frozen=True)
class Seed003Fits:
    n: np.ndarray  # (F,)
    factor: np.ndarray  # (F,) quadrature factor of blinn-phong-gaussian at L = N
    fits: list[FitCurve] = field(default_factory=list)

    def relative_error(self, fit: FitCurve) -> np.ndarray:
        return fit.prediction / self.factor - 1.0


def seed003_fits(config: StudyConfig, fit: Callable, tick: Tick = quiet_progress) -> Seed003Fits:
    """Seed 003's line against refits by :func:`brdfnorm.fit.fit` (passed in: the fit module is optional).

    The factor is computed on seed 003's grid (n = 1, 2, …, 512); the least-squares line uses all of it, as
    the seed did, and so should reproduce the seed's coefficients. The minimax fits (the commenter's hyperbola
    and the automatic choice) see only a geometrically spaced subset; their errors are shown on the whole grid.
    """
    n = np.linspace(*closed_forms.SEED_003_RANGE, config.fit_count)
    tick("the factor on seed 003's grid", 0.0)
    result = normalize(load("blinn-phong-gaussian"), "normal", sweep={"n": n}, rtol=config.table_rtol,
                       method="quadrature")
    factor = result.factor[:, 0, 0]
    spaced = np.geomspace(*closed_forms.SEED_003_RANGE, config.fit_samples)
    subset = np.unique(np.abs(n[:, None] - spaced).argmin(axis=0))
    fits = [FitCurve("seed 003 line", closed_forms.SEED_003_TEXT, closed_forms.seed003_factor(n),
                     closed_forms.SEED_003_LINE)]
    for label, form, metric, points in (
        ("least-squares line", "linear", "abs-lsq", slice(None)),
        ("hyperbola (minimax)", "hyperbola", "minimax-rel", subset),
        ("auto fit (minimax)", "auto", "minimax-rel", subset),
    ):
        tick(label, 0.5 + 0.5 * len(fits) / 4)
        fitted = fit(n[points], factor[points], form=form, metric=metric, names=("n", "t"))
        fits.append(FitCurve(label, fitted.expression, np.asarray(fitted(n), dtype=float),
                             tuple(float(c) for c in fitted.coefficients)))
    return Seed003Fits(n, factor, fits)


@dataclass(frozen=True)
class PolarPanel:
    title: str
    t: np.ndarray  # (P,) polar angle of L in the plane, radians (negative: the side opposite to V)
    views: np.ndarray  # (W,) view angles, radians
    radiance: np.ndarray  # (W, P, C) f(L, V)(N·L)·factor


def polar_panel(model: Model, title: str, views_deg, points: int, factor: np.ndarray) -> PolarPanel:
    """f(L, V)(N·L)·factor over L = (sin t, 0, cos t), t ∈ [−90°, 90°], with V = (sin θ_v, 0, cos θ_v)."""
    t = np.linspace(-np.pi / 2, np.pi / 2, points)
    views = np.radians(np.asarray(views_deg, dtype=float))
    L = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)[None, :, :]
    V = np.stack([np.sin(views), np.zeros_like(views), np.cos(views)], axis=-1)[:, None, :]
    with np.errstate(all="ignore"):
        # The original Phong lobe divides by N·L; its product with N·L is what the plot shows, so use the
        # model's own (cancelled) product rather than f·cos, which is 0/0 at the horizon.
        value = model.projected(*np.broadcast_arrays(L, V), model.params)
    with np.errstate(invalid="ignore"):  # 0·∞ where a lobe has zero albedo: NaN, not drawn
        value = np.where(np.isfinite(value), value, np.nan) * np.asarray(factor, dtype=float)
    return PolarPanel(title, t, views, value)


def polar_lobes(config: StudyConfig, tick: Tick = quiet_progress) -> list[PolarPanel]:
    panels = []
    for index, lobe in enumerate(SEED_LOBES):
        tick(lobe, index / len(SEED_LOBES))
        model = load(lobe, n=config.polar_n)
        factor = 1.0 / albedo(model, 0.0, rtol=config.plot_rtol, method="quadrature").value
        panels.append(polar_panel(model, f"{lobe}, n = {config.polar_n:g}", config.polar_views,
                                  config.polar_points, factor))
    return panels


# -- any model ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ModelStudy:
    model: Model
    label: str  # what the user named (model name or file path)
    parameter: str | None
    values: np.ndarray  # (S,) swept values (one NaN entry when nothing is swept)
    normal_albedo: np.ndarray  # (S, C)
    normal_error: np.ndarray  # (S, C)
    closed_albedo: np.ndarray | None  # (S, C) where the model declares a closed form at L = N
    max_theta: np.ndarray  # (S,) radians
    max_phi: np.ndarray  # (S,) radians
    max_albedo: np.ndarray  # (S, C)
    curves: AlbedoCurves
    polar: list[PolarPanel]
    method: str


def sweep_values(model: Model, name: str, count: int) -> np.ndarray:
    """A default sweep of a float parameter: its declared range (slider range for files), geometric when wide.

    Unbounded ranges (the built-in exponents) span the default ÷32 … ×32.
    """
    p = model.parameter(name)
    default = float(p.default)
    low = p.minimum if p.minimum is not None else (default / 32 if default > 0 else default - 1.0)
    high = p.maximum if p.maximum is not None else (default * 32 if default > 0 else default + 1.0)
    if p.maximum is None and default > 0:
        low = max(low, default / 32)
    if low > 0 and high / low >= 20:
        return np.geomspace(low, high, count)
    return np.linspace(low, high, count)


def first_float(model: Model) -> str | None:
    return next((p.name for p in model.parameters if p.kind == "float"), None)


def model_study(model: Model, label: str, sweep: tuple[str, np.ndarray] | None, config: StudyConfig,
                tick: Tick = quiet_progress) -> ModelStudy:
    if sweep is not None:
        name, values = sweep
        parameter = model.parameter(name)
        if parameter.kind != "float":
            raise ArgumentError(f"only float parameters can be swept; {name} is {parameter.kind}", where="sweep")
        values = np.asarray(values, dtype=float)
    else:
        name = first_float(model)
        values = sweep_values(model, name, config.sweep_count) if name else np.full(1, np.nan)
    sweep_arg = {name: values} if name else None
    tick("factors at L = N", 0.0)
    normal = normalize(model, "normal", sweep=sweep_arg, rtol=config.model_rtol)
    tick("searching for the maximum", 0.2)
    at_max = normalize(model, "max", sweep=sweep_arg, rtol=config.model_search_rtol,
                       search_points=config.model_search_points)
    tick("albedo curves and polar plots", 0.7)
    closed = None
    if METHODS["closed-form"].applies(model, "light"):
        swept = model.with_params(**{name: values}) if name else model
        closed = np.broadcast_to(albedo(swept, 0.0, method="closed-form").value, normal.albedo[:, 0].shape)
    # A few of the swept values (evenly spaced through the sweep) drawn as albedo curves and polar lobes.
    picks = np.unique(np.round(np.linspace(0, values.size - 1, min(config.curve_count, values.size))).astype(int))
    shown = values[picks]
    theta = config.theta
    swept = model.with_params(**{name: shown[:, None]}) if name else model
    curve = albedo(swept, theta[None, :], rtol=config.plot_rtol)
    curve_values = np.broadcast_to(curve.value, (shown.size,) + curve.value.shape[1:])
    curves = AlbedoCurves({label: label}, {label: shown}, name or "", theta, {label: curve_values})
    polar = []
    for k, value in enumerate(shown):
        bound = model.with_params(**{name: float(value)}) if name else model
        title = f"{name} = {value:.4g}" if name else model.name
        polar.append(polar_panel(bound, title, config.polar_views, config.polar_points,
                                 normal.factor[picks[k], 0]))
    return ModelStudy(model, label, name, values, normal.albedo[:, 0], normal.error[:, 0], closed,
                      at_max.theta[:, 0], at_max.phi[:, 0], at_max.albedo[:, 0], curves, polar, normal.method)
