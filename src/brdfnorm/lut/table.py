"""Energy-compensation tables: the directional albedo of a lobe over a grid of view angles and parameters.

What every engine that ships a microfacet lobe also ships (Kulla & Conty 2017, "Revisiting physically based
shading at Imageworks"; Karis 2013's split-sum "DFG" texture): the single-scattering albedo E(μ, α) with
μ = cos θ_o, its cosine-weighted average E_avg(α) = 2∫₀¹ E(μ) μ dμ, and 1 − E, here with an error estimate on
every cell. The tables are arrays indexed in the order of the axes given; tables that do not depend on an axis
(E_avg does not depend on μ) drop it and keep the others' order.

* Cells: one batched :func:`brdfnorm.albedo` call per chunk of cells (parameter values as arrays broadcast
  against θ), :func:`compute_cells` — a pure function of (model, directions, parameter values, settings), so a
  process pool or a cluster can compute any chunk.
* E_avg: the exact integral over μ ∈ [0, 1] in x = √μ, vectorized over the other axes — never a sum over the
  table's samples: nested Clenshaw–Curtis (16, 32, 64 intervals; error |Q₂ₙ − Qₙ|, or less where the last
  two doublings' differences fell at least 16-fold, :func:`rule_error`; each node's albedo asked for its share
  n·w·4x³ of the rule, re-asked tighter where the nodes' estimates rather than the rule's keep a value open,
  :func:`_tighten`), and for what that does not
  settle a globally adaptive Gauss–Kronrod (G7/K15) quadrature (error |K15 − G7|, the G7 rule's, a deliberately
  pessimistic bound for the K15 value that is used, and at least half the parent panel's bisection discrepancy); both
  add the albedo error estimates through |weights|. On more than one thread (:mod:`brdfnorm.parallel.threads`,
  whose :func:`~brdfnorm.parallel.threads.scope` every stage reads) E_avg runs beside E.
* DFG (``channels=("dfg",)``): the split-sum pair ∫ f cos (1 − (1 − V·H)⁵) dL (the coefficient of f0 in Schlick's
  Fresnel) and ∫ f cos (1 − V·H)⁵ dL (of f90), with the Fresnel off. For a model with a ``fresnel`` parameter and
  ``f0``/``f90`` these are exactly ``fresnel=schlick`` with (f0, f90) = (1, 0) and (0, 1); any other model is
  weighted as given (:class:`SchlickWeighted`) — its own Fresnel, if it has one, must be switched off by its
  parameters (e.g. ``f0=1`` for ``examples/ggx.brdf``), which is recorded in ``meta["dfg"]``. Where the other axes
  are ``alpha`` or ``roughness``, a third channel DFG_cloth (:mod:`.cloth`, the sheen lobe's albedo).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import validate
from ..engine.compiled.backend import scope as backend_scope
from ..engine.machinery.interval import GaussKronrod, adaptive_interval
from ..engine.methods import albedo
from ..errors import ArgumentError
from ..models.base import Model
from ..parallel.threads import albedo_warnings_ignored, beside, cell_tasks, current, local_threads, run_tasks, scoped
from ..validate import DEFAULT_RTOL
from . import glass
from .axes import axis_parameter, checked_axes, per_cell
from .cloth import DESCRIPTION as CLOTH_DESCRIPTION
from .cloth import cloth_model
from .lookup import GRIDS, Lut, grid_values, plain_params  # noqa: F401 — re-exported
from .quadrature import (  # noqa: F401 — rule_error and its constants re-exported
    RULE_CONVERGING,
    RULE_POWER,
    RULE_SAFETY,
    clenshaw_curtis,
    estimate,
    floored,
    learn_noise,
    rule_error,
)
from .splitsum import SchlickWeighted, split_sum_models  # noqa: F401 — re-exported (audit.reference)

CHANNELS = ("dfg",)
#: Cells per batched albedo call: large enough to amortize numpy's overhead, small enough for a progress bar
#: that moves and for memory that stays bounded (the integrator holds a few hundred nodes per cell).
CHUNK_CELLS = 256
#: Cells per progress step of a table (whatever the number of threads: the batches, and so the values, stay the same).
BLOCK_CELLS = 4 * CHUNK_CELLS
#: Panels the μ integral of E_avg may split into (per value of the other axes) before it gives up.
MAX_AVG_PANELS = 400
#: E_avg's nested Clenshaw–Curtis rule in x = √μ: first and largest number of intervals (see average_over_mu).
CC_FIRST = 16
CC_MAX = 64
#: The smallest μ at which E_avg's quadrature evaluates the albedo (nodes below it use it; see average_over_mu).
MU_FLOOR = 1e-7
#: E_avg's node albedos are asked NODE_SHARE·rtol divided by their share of the integral (n·w·4x³ for the n-interval
#: rule: 1 for an average node), where that share is below 1, in steps of NODE_RTOL_STEP, never looser than
#: NODE_RTOL_MAX (see _node_albedos). The routes' estimates come back 10–50× under what was asked, so that
#: NODE_SHARE = 2.5 still leaves their sum at 10–80 % of rtol·E_avg (the 32 × 32 examples/ggx.brdf table; at 1/4, the
#: old setting, at 2–10 %: E_avg took 17.9 M evaluations against 14.3 M now, for the same albedos).
NODE_RTOL_STEP = 10.0
NODE_RTOL_MAX = 1e-4
NODE_SHARE = 2.5
#: The same for the adaptive route's panels (_average_adaptive), where a node's weight is the density 4x³ and
#: bisection does not shrink the nodes' estimates: their sum is kept within a quarter of rtol·(E_avg + ∫ |E|).
PANEL_SHARE = 0.25
#: A combination whose rule error is within RULE_SHARE·rtol·|E_avg| but whose total is not has its heaviest nodes
#: asked again, each for TIGHTEN_FILL of an equal share of what is left (see _tighten), instead of a finer rule
#: (whose new nodes would not shrink the old nodes' estimates) or the adaptive route afresh.
RULE_SHARE = 0.5
TIGHTEN_FILL = 0.5
#: Passes of _tighten per rule (a node's first estimate may be far under what it was asked; the second pass takes
#: what the first left).
TIGHTEN_PASSES = 2
#: A combination whose node albedo came back "rounding-limited" (the shader's float64 noise above the node's
#: tolerance) asks its later nodes for no less than this times that node's relative estimate: a tolerance below
#: the noise only makes the route refine until its noise test stops it (at roughness 0.05, α = 0.0025, of
#: examples/ggx.brdf: 65 000–350 000 evaluations per node at rtol/4 = 2.5e-11 against 11 000–21 000 at 1e-10,
#: with the same estimates, 5–8e-11, which are the noise bound).
NOISE_FLOOR_FACTOR = 1.0

@dataclass(frozen=True)
class CellResult:
    """Albedo of a flat batch of K cells: value and error (K, C), evaluations and convergence (K,)."""

    value: np.ndarray
    error: np.ndarray
    evaluations: np.ndarray
    converged: np.ndarray
    reflected: np.ndarray | None = None  # (K, C) the parts of a BSDF's albedo (models that transmit)
    transmitted: np.ndarray | None = None
    reason: np.ndarray | None = None  # (K,) why a cell did not converge ("" where it did), as albedo says


def compute_cells(model: Model, theta: np.ndarray, params: Mapping[str, np.ndarray], *, rtol: float,
                  method: str = "auto", over: str = "light", threads: int | None = None) -> CellResult:
    """E for K cells: view angles ``theta`` (K,) radians and per-cell parameter values (K,) — one albedo call per
    task of at most CHUNK_CELLS cells (strided subsets, :func:`brdfnorm.parallel.threads.cell_tasks`), the tasks on
    ``threads`` threads of this process (None: those of the caller's :func:`brdfnorm.parallel.threads.scope`; the
    tasks, and so the values, the same for any number of threads).

    A pure function of its arguments (the unit of work a process pool or a cluster computes).
    """
    theta = np.asarray(theta, dtype=float).ravel()
    flat = {name: np.asarray(v, dtype=float).ravel() for name, v in params.items()}

    def chunk(cells: np.ndarray):
        bound = model.with_params(**per_cell(model, {name: v[cells] for name, v in flat.items()}))
        return albedo(bound, theta[cells], over=over, rtol=rtol, method=method)

    tasks = cell_tasks(theta.size, CHUNK_CELLS)  # (the same for any number of threads: so are the values)
    with albedo_warnings_ignored():  # convergence is reported per cell by the caller, not once per chunk
        parts = run_tasks(chunk, tasks, current() if threads is None else threads)
    back = np.argsort(np.concatenate(tasks), kind="stable")  # the cells' order from the tasks'
    keys = ("value", "error", "evaluations", "converged", "reflected", "transmitted", "reason")
    return CellResult(*(None if getattr(parts[0], k) is None else np.concatenate([getattr(r, k) for r in parts])[back]
                        for k in keys))


def _single_channel(value: np.ndarray, error: np.ndarray, model: Model) -> tuple[np.ndarray, np.ndarray]:
    """Channel 0 of (K, C) results; several channels only when they are all equal (a grey lobe)."""
    if value.shape[-1] > 1 and not np.array_equal(value, np.broadcast_to(value[..., :1], value.shape)):
        raise ArgumentError(f"{model.name} has {value.shape[-1]} channels with different albedos; tabulate one "
                            "channel at a time (set its colour parameters equal)", where="model")
    return value[..., 0], error[..., 0]


ProgressCallback = Callable[[int, int], None]


def _theta_of(direction_axis: str, values: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(values, -1.0, 1.0)) if direction_axis == "mu" else values


def _tabulate(model: Model, shape, theta_grid, param_grids, rtol, method, done, total, progress, spread=None,
              name="E"):
    """E, its error, convergence and evaluation counts over the full grid (and a BSDF's parts E_R, E_T).

    With ``spread`` (``workers``, ``scheduler``, ``checkpoint``) the cells go to :mod:`brdfnorm.parallel` — local
    processes or a Dask cluster, each table resumable in its own checkpoint directory — where the model has a
    source to travel as (built-ins and ``.brdf`` files; the split-sum weightings stay in this process).
    Otherwise in this process, CHUNK_CELLS cells per albedo call on the scope's threads (:func:`compute_cells`).
    The values are the same either way."""
    K = int(np.prod(shape))
    theta_flat = np.broadcast_to(theta_grid, shape).ravel()
    flat = {n: np.broadcast_to(g, shape).ravel() for n, g in param_grids.items()}
    transmits = getattr(model, "transmits", False)
    job = None
    if spread is not None:
        from ..parallel import CellsJob, albedo_cells

        try:
            job = CellsJob.of(model, theta_flat, 0.0, flat, rtol=rtol, method=method)
        except ArgumentError:
            job = None
    if job is not None:
        checkpoint = spread.get("checkpoint")
        cells = albedo_cells(job, workers=spread.get("workers"), scheduler=spread.get("scheduler"),
                             checkpoint=None if checkpoint is None else Path(checkpoint) / name,
                             on_progress=None if progress is None else (lambda d, t: progress(done + d, total)))
        value, error = _single_channel(cells.value.reshape(K, -1), cells.error.reshape(K, -1), model)
        parts = {"E_R": cells.reflected.reshape(K, -1)[:, 0], "E_T": cells.transmitted.reshape(K, -1)[:, 0]} \
            if transmits else {}
        return (value.reshape(shape), error.reshape(shape), cells.converged.reshape(shape),
                cells.evaluations.reshape(shape), done + K, {n: p.reshape(shape) for n, p in parts.items()})
    value, error = np.empty(K), np.empty(K)
    # A BSDF's parts: reflection (E_R) and transmission (E_T), E = E_R + E_T.
    parts = {"E_R": np.empty(K), "E_T": np.empty(K)} if transmits else {}
    converged, evaluations = np.empty(K, dtype=bool), np.empty(K, dtype=np.int64)
    for start in range(0, K, BLOCK_CELLS):
        cells = slice(start, min(K, start + BLOCK_CELLS))
        result = compute_cells(model, theta_flat[cells], {n: v[cells] for n, v in flat.items()}, rtol=rtol,
                               method=method)
        value[cells], error[cells] = _single_channel(result.value, result.error, model)
        if parts:
            parts["E_R"][cells] = result.reflected[:, 0]
            parts["E_T"][cells] = result.transmitted[:, 0]
        converged[cells], evaluations[cells] = result.converged, result.evaluations
        done += cells.stop - cells.start
        if progress is not None:
            progress(done, total)
    return (value.reshape(shape), error.reshape(shape), converged.reshape(shape), evaluations.reshape(shape),
            done, {name: part.reshape(shape) for name, part in parts.items()})


def _node_albedos(model: Model, mu: np.ndarray, weight: np.ndarray, node_params: Mapping[str, np.ndarray],
                  rtol: float, method: str, floor: np.ndarray | None = None,
                  tolerance: np.ndarray | None = None, share: float = PANEL_SHARE
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """E at max(μ, MU_FLOOR) for E_avg's nodes μ (N,) with per-node parameter values: (value, error, ok, noisy,
    tolerance asked).

    A node's albedo enters the integral through its ``weight`` (N,): its share of the integral relative to an
    average node of its rule (n·w·4x³ for the n-interval rule in x = √μ; the density 4x³ for a panel's rule). It
    is asked ``share``·rtol/min(1, weight) (at most NODE_RTOL_MAX), which keeps Σ w·4x³·error ≤
    share·rtol·(E_avg + mean |E| over the nodes) — rounded down to powers of NODE_RTOL_STEP so that the nodes
    go in a few batched calls (the grazing ones, the costliest albedos, are the loosest); or ``tolerance`` (N,)
    where given (:func:`_tighten`). ``floor`` (N,): a relative tolerance below which a node is not asked, its
    combination's float64 noise (see average_over_mu), rounded up to a power of two.

    ``ok``: the node's estimate is final — converged, or stopped "rounding-limited" (the route then carries its
    rounding-noise bound in the estimate, which more nodes cannot shrink); ``noisy``: the latter."""
    if tolerance is None:
        ratio = 1.0 / np.minimum(1.0, np.maximum(weight, 1e-300))
        base = share * rtol
        cap = np.log(NODE_RTOL_MAX / base) / np.log(NODE_RTOL_STEP)
        level = np.clip(np.floor(np.log(ratio) / np.log(NODE_RTOL_STEP)), 0, max(np.ceil(cap), 0))
        tolerance = np.maximum(base, np.minimum(base * NODE_RTOL_STEP**level, NODE_RTOL_MAX))
    tolerance = floored(tolerance, floor)
    theta = np.arccos(np.clip(np.maximum(mu, MU_FLOOR), 0.0, 1.0))
    value, error = np.empty(mu.size), np.empty(mu.size)
    converged, noisy = np.empty(mu.size, dtype=bool), np.zeros(mu.size, dtype=bool)
    for step in np.unique(tolerance):
        nodes = np.flatnonzero(tolerance == step)
        cells = compute_cells(model, theta[nodes], {n: v[nodes] for n, v in node_params.items()}, rtol=float(step),
                              method=method)
        value[nodes], error[nodes] = _single_channel(cells.value, cells.error, model)
        converged[nodes] = cells.converged
        if cells.reason is not None:
            noisy[nodes] = ~cells.converged & (cells.reason == "rounding-limited")
    return value, error, converged | noisy, noisy, tolerance


@scoped
def average_over_mu(model: Model, params: Mapping[str, np.ndarray], *, rtol: float, method: str = "auto",
                    max_panels: int = MAX_AVG_PANELS, threads: int | None = None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """E_avg = 2∫₀¹ E(μ) μ dμ = ∫₀¹ 4x³ E(x²) dx (x = √μ) for M parameter combinations (name -> (M,)).

    First nested Clenshaw–Curtis in x with CC_FIRST, 2·CC_FIRST, … CC_MAX intervals: a combination is settled
    when the rule's error estimate (:func:`rule_error`: |Q_2n − Q_n|, the error of Q_n, or less where two
    successive differences show the rule converging) plus the albedo error estimates through |weights| is within
    rtol·|Q_2n| (Q_2n is kept). In x the weight 4x³ vanishes where E has its boundary layer (μ ≲ α), so a smooth
    E needs 32–64 albedos. Combinations not settled by CC_MAX (kinks, e.g. a critical angle) go to
    :func:`_average_adaptive` afresh. MU_FLOOR as there. Each node's albedo is asked for its share n·w·4x³ of
    the rule it first enters (NODE_SHARE, :func:`_node_albedos`; the share does not change when the rule doubles);
    where the rule has settled, or its differences may be the nodes' errors, but the sum of the nodes' estimates
    keeps a combination open, the heaviest nodes are asked again (:func:`_tighten`). Each batch of albedos on
    ``threads`` threads of this process (None: the caller's :func:`brdfnorm.parallel.threads.scope`;
    :func:`compute_cells`).

    The node at μ = 1 goes first: where it comes back "rounding-limited" (the shader's float64 noise above its
    tolerance, e.g. examples/ggx.brdf at roughness 0.05) its relative estimate becomes its combination's floor,
    below which no later node is asked (NOISE_FLOOR_FACTOR) — the noise bound is then in every node's estimate,
    and the combination converges where their sum through the weights is within rtol. A node's estimate counts
    whether it converged or stopped rounding-limited; a combination with a node stopped otherwise (budget,
    stalled) is reported unconverged. Returns (value (M,), error estimate (M,), converged (M,), albedo integrals
    computed).
    """
    M = len(next(iter(params.values()))) if params else 1
    flat = {n: np.broadcast_to(np.asarray(v, dtype=float).ravel(), (M,)) for n, v in params.items()}
    n = CC_FIRST
    x, w = clenshaw_curtis(n)
    # Per node (x = 0 has weight 4x³ = 0: never evaluated): value, error, the tolerance asked, and whether its
    # estimate is final (ok) or the route's rounding-noise bound (noisy).
    node = {"value": np.zeros((M, n + 1)), "error": np.zeros((M, n + 1)), "asked": np.full((M, n + 1), np.inf),
            "ok": np.ones((M, n + 1), dtype=bool), "noisy": np.zeros((M, n + 1), dtype=bool)}
    open_ = np.ones(M, dtype=bool)
    noise = np.zeros(M)  # per combination: the largest relative estimate of its rounding-limited nodes
    integrals = 0

    def fill(rows: np.ndarray, columns: np.ndarray, share: np.ndarray, tolerance: np.ndarray | None = None) -> None:
        """Node albedos at ``columns`` of ``rows`` (or the (rows, columns) pairs where ``columns`` is 2-D)."""
        nonlocal integrals
        rows_, columns_ = np.broadcast_arrays(rows[:, None], columns if columns.ndim == 2 else columns[None, :])
        rows_, columns_ = rows_.ravel(), columns_.ravel()
        mu = x[columns_] ** 2
        result = _node_albedos(model, mu, share.ravel(), {k: v[rows_] for k, v in flat.items()}, rtol, method,
                               NOISE_FLOOR_FACTOR * noise[rows_],
                               tolerance=None if tolerance is None else tolerance.ravel(), share=NODE_SHARE)
        learn_noise(noise, rows_, *result[:2], result[3])
        for key, part in zip(("value", "error", "ok", "noisy", "asked"), result, strict=True):
            node[key][rows_, columns_] = part
        integrals += rows_.size

    def level_share(columns: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """The nodes' shares of the rule they enter (n·w·4x³), one row per combination."""
        return np.broadcast_to(n * w[columns] * 4.0 * x[columns] ** 3, (rows.size, columns.size))

    # The node at μ = 1 first: where the shader's noise is above the nodes' tolerance it shows there (see
    # NOISE_FLOOR_FACTOR), before the other nodes are asked for what the noise does not allow.
    everyone = np.arange(M)
    fill(everyone, np.array([n]), level_share(np.array([n]), everyone))
    fill(everyone, np.arange(1, n), level_share(np.arange(1, n), everyone))
    total, total_error = np.zeros(M), np.zeros(M)
    # The first rule's every other and every fourth node: |Q_n − Q_n/2| and |Q_n/2 − Q_n/4| for free.
    first, half, quarter = ((node["value"][:, ::step] @ (w_ * 4.0 * x_**3)) for step, (x_, w_) in
                            ((1, (x, w)), (2, clenshaw_curtis(n // 2)), (4, clenshaw_curtis(n // 4))))
    change, earlier_change = np.abs(first - half), np.abs(half - quarter)
    while n < CC_MAX and open_.any():
        n *= 2
        x, w = clenshaw_curtis(n)
        for key, coarse in node.items():  # (the new nodes of closed combinations are never read)
            node[key] = np.full((M, n + 1), {"asked": np.inf, "ok": True}.get(key, 0), dtype=coarse.dtype)
            node[key][:, ::2] = coarse
        rows = np.flatnonzero(open_)
        fill(rows, np.arange(1, n + 1, 2), level_share(np.arange(1, n + 1, 2), rows))
        weight = w * 4.0 * x**3  # dμ 2μ = 4x³ dx
        coarse_weight = clenshaw_curtis(n // 2)[1] * 4.0 * x[::2] ** 3
        fine, difference, rule, nodes = estimate(node, rows, weight, coarse_weight, change, earlier_change)
        # Where the rule has settled, or its differences may be the nodes' errors, but the nodes' estimates have
        # not, the few nodes that hold most of their sum are asked again, tighter (:func:`_tighten`): cheaper than
        # a finer rule, whose new nodes would not shrink them.
        for _ in range(TIGHTEN_PASSES):
            goal = rtol * np.abs(fine)
            redo = (rule + nodes > goal) & ((rule <= RULE_SHARE * goal) | (nodes >= rule))
            if not (redo.any() and _tighten(node, rows[redo], goal[redo] - np.minimum(rule, RULE_SHARE * goal)[redo],
                                            weight, noise, fill)):
                break
            fine, difference, rule, nodes = estimate(node, rows, weight, coarse_weight, change, earlier_change)
        total[rows], total_error[rows] = fine, rule + nodes
        change[rows], earlier_change[rows] = difference, change[rows]
        open_[rows] = total_error[rows] > rtol * np.abs(fine)
    largest_e = np.abs(node["value"]).max(axis=1)
    total_error += MU_FLOOR**2 * largest_e  # nodes below MU_FLOOR evaluated there
    albedo_ok = node["ok"].all(axis=1)
    converged = albedo_ok & ~open_
    rest = np.flatnonzero(open_)
    if rest.size:
        total[rest], total_error[rest], converged[rest], count = _average_adaptive(
            model, {k: v[rest] for k, v in flat.items()}, rtol=rtol, method=method, max_panels=max_panels,
            noise=noise[rest])
        integrals += count
    return total, total_error, converged, integrals


def _tighten(node: dict[str, np.ndarray], rows: np.ndarray, budget: np.ndarray, weight: np.ndarray,
             noise: np.ndarray, fill: Callable) -> bool:
    """Ask again, tighter, the nodes of ``rows`` whose share of Σ |weight|·error exceeds TIGHTEN_FILL·budget/n
    (``budget`` (R,): what the rule's error leaves of rtol·|E_avg|), each for that allowance through its weight
    and value, rounded down to a power of NODE_RTOL_STEP. Nodes already asked that tightly, or whose estimate is
    their combination's float64 noise (``noisy``; see average_over_mu), are left. Returns whether any was asked."""
    count = weight.size - 1
    allowance = TIGHTEN_FILL * budget[:, None] / count
    share = node["error"][rows] * np.abs(weight)
    with np.errstate(divide="ignore", invalid="ignore"):
        wanted = allowance / (np.abs(weight) * np.abs(node["value"][rows]))
        wanted = NODE_RTOL_STEP ** np.floor(np.log(wanted) / np.log(NODE_RTOL_STEP))
    floor = NOISE_FLOOR_FACTOR * noise[rows][:, None]
    wanted = np.where(np.isfinite(wanted) & (wanted > 0), wanted, np.inf)
    wanted = floored(wanted, np.broadcast_to(floor, wanted.shape))
    again = (share > allowance) & ~node["noisy"][rows] & (wanted < node["asked"][rows]) & (weight > 0)
    if not again.any():
        return False
    which, columns = np.nonzero(again)
    fill(rows[which], columns[:, None], np.ones((which.size, 1)), wanted[which, columns][:, None])
    return True


def _average_adaptive(model: Model, params: Mapping[str, np.ndarray], *, rtol: float, method: str = "auto",
                      max_panels: int = MAX_AVG_PANELS, noise: np.ndarray | None = None
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """E_avg = 2∫₀¹ E(μ) μ dμ for M parameter combinations (``params``: name -> (M,)), adaptive G7/K15.

    In x = √μ the integral is ∫₀¹ 4x³ E(x²) dx: the weight vanishes where E has its boundary layer (μ ≲ α for a
    height-correlated microfacet lobe), so that layer needs no refinement. Globally adaptive (as QUADPACK):
    while a combination's summed panel errors exceed rtol·|E_avg|, its worst panels (error ≥ ¼ of its largest)
    are halved (:func:`brdfnorm.engine.machinery.interval.adaptive_interval`, ``policy="global"``). A panel's error
    is |K15 − G7| plus the albedo error estimates through the K15 weights, and at least half its parent's bisection
    discrepancy (a kink inside a panel can give K15 and G7 one shared error); albedos are computed to rtol/4,
    looser where the weight 4x³ is below 1 (rtol/(4·4x³), at most NODE_RTOL_MAX). Nodes
    below μ = MU_FLOOR are evaluated at MU_FLOOR (a lobe may refuse grazing directions); that changes the
    integral by at most MU_FLOOR²·max|E|, which is added to the error. ``noise`` (M,): the combinations' noise
    floors as far as :func:`average_over_mu` learned them (rounding-limited nodes as there).
    Returns (value (M,), error estimate (M,), converged (M,), albedo integrals computed).
    """
    M = len(next(iter(params.values()))) if params else 1
    flat = {n: np.asarray(v, dtype=float).ravel() for n, v in params.items()}
    albedo_converged, largest_e = np.ones(M, dtype=bool), np.zeros(M)
    noise = np.zeros(M) if noise is None else np.array(noise, dtype=float)
    integrals = 0

    def integrand(owner: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        nonlocal integrals
        mu, density = x * x, 4.0 * x**3  # dμ 2μ = 4x³ dx
        which = np.broadcast_to(owner[:, None], x.shape)
        E, E_error, good, noisy, _ = _node_albedos(
            model, mu.ravel(), density.ravel(), {n: v[which.ravel()] for n, v in flat.items()}, rtol, method,
            NOISE_FLOOR_FACTOR * noise[which.ravel()])
        learn_noise(noise, which.ravel(), E, E_error, noisy)
        E, E_error, good = (a.reshape(x.shape) for a in (E, E_error, good))
        integrals += x.size
        albedo_converged[owner[~good.all(axis=1)]] = False
        np.maximum.at(largest_e, owner, np.abs(E).max(axis=1))
        return density * E, density * E_error

    averaged = adaptive_interval(GaussKronrod(integrand), np.zeros(M), np.ones(M), np.arange(M), M, rtol=rtol,
                                 policy="global", max_panels=max_panels)
    total, total_error = averaged.value, averaged.error
    floor_error = MU_FLOOR**2 * largest_e
    total_error = total_error + floor_error
    converged = albedo_converged & (total_error <= rtol * np.abs(total) + floor_error)
    return total, total_error, converged, integrals


@dataclass(frozen=True)
class Computed:
    """What :func:`compute_tables` returns: tables with their axes, per-cell convergence and counts."""

    tables: dict[str, np.ndarray]
    table_axes: dict[str, tuple[str, ...]]
    converged: np.ndarray  # over the full grid (E, and the DFG channels if asked)
    avg_converged: np.ndarray | None
    evaluations: int
    dfg: str | None


@scoped
def compute_tables(model: Model, axes: Mapping[str, Sequence[float]], *, clamp: Mapping[str, float] | None = None,
                   rtol: float = DEFAULT_RTOL, method: str = "auto", channels: Sequence[str] = (),
                   average: bool = True, progress: ProgressCallback | None = None,
                   spread: Mapping[str, object] | None = None, threads: int | None = None) -> Computed:
    """E, E_error, 1-E (and E_avg, E_avg_error over the direction axis; DFG_f0, DFG_f90 with their errors); the
    cells ``spread`` does not take, on ``threads`` threads of this process (None: the caller's
    :func:`brdfnorm.parallel.threads.scope`; :func:`compute_cells`)."""
    clamp = dict(clamp or {})
    for channel in channels:
        if channel not in CHANNELS:
            raise ArgumentError(f"unknown channel set {channel!r} (known: {', '.join(CHANNELS)})", where="channels")
    _, evaluated, direction = checked_axes(model, axes, clamp)
    names = list(evaluated)
    shape = tuple(len(evaluated[n]) for n in names)
    validate.batch_size(shape, where="axes")  # before any array of the table's size exists

    def along(name: str, values: np.ndarray, order: list[str]) -> np.ndarray:
        index = [1] * len(order)
        index[order.index(name)] = -1
        return values.reshape(index)

    theta_grid = along(direction, _theta_of(direction, evaluated[direction]), names)
    param_grids = dict(axis_parameter(model, n, along(n, evaluated[n], names)) for n in names if n != direction)
    others = [n for n in names if n != direction]
    avg_shape = tuple(len(evaluated[n]) for n in others)
    cells = int(np.prod(shape))
    total = cells * (1 + 3 * ("dfg" in channels)) + (int(np.prod(avg_shape)) if average else 0)
    done = 0
    combos = dict(axis_parameter(model, n, np.broadcast_to(along(n, evaluated[n], others), avg_shape).ravel())
                  for n in others) if average else {}
    glassy = getattr(model, "transmits", False)  # glass: the 3-D route of lut.glass, spread like the cells
    # E_avg beside E where both are computed here on more than one thread (they are independent): each stage's
    # batches wait at their ends for their slowest task, and the other stage's tasks fill those gaps. The
    # values do not change (the same albedo calls); progress is still given in stage order, from this thread.
    paired = average and spread is None and current() > 1 and not glassy
    avg_converged = None
    with contextlib.ExitStack() as stack:
        if paired:
            stack.enter_context(albedo_warnings_ignored())  # (before the second thread starts: see there)
            averaged = stack.enter_context(beside(average_over_mu, model, combos, rtol=rtol, method=method))
        E, E_error, converged, evaluations, done, parts = _tabulate(model, shape, theta_grid, param_grids, rtol,
                                                                    method, done, total, progress, spread, "E")
        if paired:
            avg, avg_error, avg_converged, _ = averaged()
    tables = {"E": E, "E_error": E_error, **parts}
    table_axes: dict[str, tuple[str, ...]] = {name: tuple(names) for name in tables}
    if average:
        if glassy:
            avg, avg_error, avg_converged, _ = glass.average(model, combos, rtol=rtol, generic=average_over_mu,
                                                             method=method, spread=spread)
        elif not paired:
            avg, avg_error, avg_converged, _ = average_over_mu(model, combos, rtol=rtol, method=method)
        tables["E_avg"], tables["E_avg_error"] = avg.reshape(avg_shape), avg_error.reshape(avg_shape)
        table_axes["E_avg"] = table_axes["E_avg_error"] = tuple(others)
        avg_converged = avg_converged.reshape(avg_shape)
        done += int(np.prod(avg_shape))
        if progress is not None:
            progress(done, total)
    tables["1-E"] = 1.0 - E
    table_axes["1-E"] = tuple(names)
    dfg = None
    if "dfg" in channels:
        dfg_models, dfg = split_sum_models(model)
        for name, weighted in dfg_models.items():
            value, error, ok, count, done, _ = _tabulate(weighted, shape, theta_grid, param_grids, rtol, method,
                                                         done, total, progress, spread, name)
            tables[name], tables[f"{name}_error"] = value, error
            table_axes[name] = table_axes[f"{name}_error"] = tuple(names)
            converged &= ok
            evaluations = evaluations + count
        cloth = cloth_model(param_grids)  # the third channel engines store beside the pair (lut.cloth)
        if cloth is not None:
            value, error, ok, count, done, _ = _tabulate(cloth[0], shape, theta_grid, cloth[1], rtol, "auto", done,
                                                         total, progress, spread, "DFG_cloth")
            tables["DFG_cloth"], tables["DFG_cloth_error"] = value, error
            table_axes["DFG_cloth"] = table_axes["DFG_cloth_error"] = tuple(names)
            converged &= ok
            evaluations = evaluations + count
            dfg += "; " + CLOTH_DESCRIPTION
    return Computed(tables, table_axes, converged, avg_converged, int(evaluations.sum()), dfg)


def compute(model: Model, axes: Mapping[str, Sequence[float]], *, clamp: Mapping[str, float] | None = None,
            rtol: float = DEFAULT_RTOL, method: str = "auto", channels: Sequence[str] = (), average: bool = True,
            grid: str | None = None, source: str | None = None, progress: ProgressCallback | None = None,
            workers: int | None = 1, scheduler: str | None = None, checkpoint: str | None = None,
            backend: str | None = None) -> Lut:
    """The energy tables of ``model`` over ``axes`` (name -> values; ``mu`` = cos θ_o or ``theta`` in radians,
    plus any float parameters), indexed in the order of ``axes``; ``source`` names the model as the user gave it
    (a built-in name or a ``.brdf`` path) in ``meta``. ``clamp`` raises axis values below a minimum
    before evaluation (μ ≥ 1e-4, α ≥ 1e-8 are the usual ones); ``grid`` only records how the values were made.
    ``workers`` (None: all cores), ``scheduler`` (a Dask address) and ``checkpoint`` (a directory) spread the
    cells as :func:`brdfnorm.parallel.albedo_cells` does; the default computes in this process. Under the compiled
    backend, ``workers=None`` computes every stage on threads of this process instead, one per core
    (:mod:`brdfnorm.parallel.threads`: no process to start; with a ``checkpoint`` the E cells still go to
    processes), and ``workers=N`` computes what no process takes (E_avg) on N threads. ``backend``
    ("numpy" or "compiled", :func:`brdfnorm.albedo`) computes every albedo of the tables. Where cells miss ``rtol``
    their values and honest estimates are kept, ``meta["unconverged"]`` counts them and ``meta["converged_mask"]``
    marks them (``{"E": ..., "E_avg": ...}``, nested lists over each table's axes).

    >>> import brdfnorm as bn
    >>> lut = compute(bn.load("blinn-phong"), {"mu": [0.5, 1.0], "n": [10.0, 100.0]}, rtol=1e-8)
    >>> lut["E"].shape, lut["E_avg"].shape
    ((2, 2), (2,))
    """
    from .. import __version__

    if method == "certified":  # bounds and digits: brdfnorm.lut.certified (which builds on this module)
        raise ArgumentError("certified tables come from brdfnorm.lut.certified.compute", where="method")
    with backend_scope(backend):
        threads = local_threads(workers, scheduler)
        # (the default workers on threads: processes only where a checkpoint or a scheduler asks, or N are asked)
        here = scheduler is None and checkpoint is None and (workers == 1 or (workers is None and threads > 1))
        spread = None if here else {"workers": workers, "scheduler": scheduler, "checkpoint": checkpoint}
        result = compute_tables(model, axes, clamp=clamp, rtol=rtol, method=method, channels=channels,
                                average=average, progress=progress, spread=spread, threads=threads)
    unconverged = int(np.count_nonzero(~result.converged))
    if result.avg_converged is not None:
        unconverged += int(np.count_nonzero(~result.avg_converged))
    aliased = {name: model.aliases[name] for name in axes if name in model.aliases}  # e.g. roughness → alpha
    fixed = {k: v for k, v in model.params.items() if k not in axes and k not in {t for t, _, _ in aliased.values()}}
    meta = {"model": source or model.name, "parameters": plain_params(fixed), "grid": grid, "clamp": dict(clamp or {}),
            "rtol": rtol, "method": method, "units": {"mu": "cos theta_o", "theta": "radians"},
            "brdfnorm": __version__, "unconverged": unconverged, "evaluations": result.evaluations}
    if unconverged:  # which cells missed rtol, as masks over their tables' axes (absent where every cell converged)
        meta["converged_mask"] = {"E": result.converged.tolist()}
        if result.avg_converged is not None:
            meta["converged_mask"]["E_avg"] = np.asarray(result.avg_converged).tolist()
    if result.dfg is not None:
        meta["dfg"] = result.dfg
    if aliased:
        meta["aliases"] = {name: text for name, (_, _, text) in aliased.items()}
    return Lut(result.tables, axes, meta, result.table_axes)
