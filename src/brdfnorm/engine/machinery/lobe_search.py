"""The lobe search of the generic route: where each case's integrand peaks, how wide each peak is — the main peak
and every separated one the lattice sees.

What it computes
----------------
For K cases of an integrand g(ω) ≥ 0 over the upper hemisphere with no model hint (a ``.brdf`` shader, a fitted
model), :func:`search_lobes` samples one equal-area Fibonacci lattice (1024 directions, spacing h ≈ √(2π/1024) ≈
0.078 rad) plus a few directions where a peak is likely (the mirror direction), and returns

- the **main peak** (:func:`estimate_lobe`): the largest sample, its width the |g|-weighted RMS angle (or twice that
  of the samples above half the peak), zoomed into on ever smaller polar caps while the lobe is narrower than the
  lattice — what the lobe-aligned coordinates of :mod:`brdfnorm.engine.routes.hemisphere` are built about;
- the **separated peaks** (:class:`Peaks`): strict local maxima of the same samples, and of the samples of every cap
  the main peak's zoom takes (above each of their :data:`NEIGHBOURS` nearest neighbours, the neighbour tables of the
  fixed lattice and of the unit cap computed once), that are separated from every higher sample — the samples above
  half the candidate's value that are joined to it reach none higher (its half-level component; a sample on a slope
  or a ridge of a higher peak, or on a noisy plateau, reaches one; a main peak at a likely direction off the lattice
  counts as joined to the samples within one spacing of it), and g on :data:`ARC_POINTS` points of the great-circle
  arc to the main peak falls below half the candidate's value (a ridge thinner than the samples along the arc does
  not), and so does the largest of g on the parallel arcs beside it at each of those points (:data:`OFFSETS`: a
  curved ridge leaves the arc), and so does g on the paths about N between the two polar angles
  (:data:`RING_OFFSETS`: a ring about N leaves every great-circle arc). Each separated candidate is zoomed into
  as the main peak is (starting on a cap of
  :data:`CANDIDATE_RADIUS` spacings of its samples, so that the zoom cannot climb onto another peak; its core only
  the samples joined to it) unless its half-level component already spans several samples; candidates that end
  within :data:`MERGE_WIDTHS` widths (the smaller) of a kept peak are merged into it, and at most :data:`MAX_PEAKS`
  peaks per case are kept, ranked by the contribution estimate c ≈ g·2π·w². A separated peak beyond that cap, or
  whose c is below ``negligible`` times the main peak's, is not integrated about its own pole: :data:`CHARGE` · c
  joins the case's error estimate (``charge``), never dropped. A case with separated peaks has its main peak
  measured again, its core only the samples joined to it (another lobe above half its value elsewhere on the first
  cap is not its core).

Every evaluation the separated-peak search spends (arcs, zooms) is counted per case (``evaluations``); the lattice
and the main peak's first zoom are not (they were not before, and single-peak cases keep their counts but for the
arcs: a grazing lobe's sliver, thinner than the caps' spacing across it, shows them a few strict local maxima that
only the arc rejects, 16 to 112 evaluations at 80–88° on the examples).

What it cannot see: a lobe narrower than the samples' spacing that no sample lands on (0, or below the tails of
another lobe, at every lattice and cap direction); a bump on a broad base whose valley stays above half its top
(it is on the base's slope). docs/numerics.md says what that means for an albedo.

The integration of a case with several peaks is :mod:`brdfnorm.engine.machinery.partition`'s.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache

import numpy as np

from ..routes.hemisphere import lobe_frame
from .directions import angle_between, norm

#: Integrand signature: (ω (M, 3), case index (M,)) -> (M, C).
Integrand = Callable[[np.ndarray, np.ndarray], np.ndarray]
#: What a search is shown of each chunk of samples: (case indices (k,), directions (k, m, 3), max |g| (k, m)).
Seen = Callable[[np.ndarray, np.ndarray, np.ndarray], None]

#: Lattice directions of the search.
SAMPLES = 1024
#: Nearest lattice neighbours a local maximum must exceed.
NEIGHBOURS = 8
#: Points of the great-circle arc from a candidate to the main peak where g is evaluated.
ARC_POINTS = 16
#: The parallel arcs tested beside the arc to the main peak, as shares of its length (the arc itself is tested
#: first; a curved ridge, Ashikhmin-Shirley's n_u = 1.6, n_v = 5 112 at θ_o = 49°, leaves it).
OFFSETS = np.array([-4, -3, -2, -1, 1, 2, 3, 4]) / 32.0
#: The paths about N tested beside the one at the candidate's and the main peak's polar angles, in polar angle (rad):
#: fine enough for a ring 0.003 rad thick, wide enough for one that the view tilts by 0.02 rad.
RING_OFFSETS = np.array([0.0, -0.001, 0.001, -0.002, 0.002, -0.004, 0.004, -0.008, 0.008, -0.016, 0.016, -0.024, 0.024])
#: A candidate is separated where g falls below this share of its value between it and any higher sample.
SEPARATION = 0.5
#: Starting radius of a candidate's zoom, in lattice spacings.
CANDIDATE_RADIUS = 1.5
#: Candidates per case and sample set given arcs (the largest first, of those the free half-level test leaves: a noisy
#: plateau has many strict local maxima, none separated); the others are charged (see _candidates).
MAX_CANDIDATES = 64
#: Peaks per case (the main one included) integrated about their own poles.
MAX_PEAKS = 8
#: Peaks closer than this many widths (the smaller: a narrow lobe separated from a broad one a few of the broad one's
#: widths away is a peak of its own) are one.
MERGE_WIDTHS = 3.0
#: A peak beyond :data:`MAX_PEAKS` is charged this multiple of its contribution estimate g·2π·w².
CHARGE = 4.0
#: Points of the polar cap a zoom samples (its centre besides).
CAP_POINTS = 256


@dataclass(frozen=True)
class Peaks:
    """The separated peaks of K cases besides each case's main one: per peak its ``case``, ``direction`` (3,),
    ``width`` and sampled ``value`` (flat, E peaks); per case the error ``charge`` of the peaks beyond the cap and the
    ``evaluations`` the search spent on them (K,)."""

    case: np.ndarray
    direction: np.ndarray
    width: np.ndarray
    value: np.ndarray
    charge: np.ndarray
    evaluations: np.ndarray

    def count(self, cases: int) -> np.ndarray:
        """Peaks per case (K,), the main one included."""
        return 1 + np.bincount(self.case, minlength=cases)


def fibonacci_hemisphere(count: int) -> np.ndarray:
    """``count`` nearly uniform directions on the upper hemisphere (equal-area Fibonacci lattice)."""
    i = np.arange(count) + 0.5
    z = 1.0 - i / count  # equal-area: z uniform in (0, 1)
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


@cache
def lattice_neighbours(count: int) -> tuple[np.ndarray, np.ndarray]:
    """The :data:`NEIGHBOURS` nearest neighbours of each direction of :func:`fibonacci_hemisphere` (count, k), and
    the symmetric neighbour lists (count, d) (i is j's neighbour or j is i's; padded with i itself), computed once
    per lattice."""
    return _neighbour_lists(fibonacci_hemisphere(count))


def _nearest(points: np.ndarray) -> np.ndarray:
    """The :data:`NEIGHBOURS` nearest other points of each of ``points`` (count, dimensions), nearest first: by
    squared distances summed over the differences, all pairs (a lattice of 1 024 points: ~10 ms, no scipy.spatial
    to import, which cost 30–70 ms a process; the same neighbours as its ``cKDTree`` gives, tests/engine)."""
    distance = np.zeros((points.shape[0], points.shape[0]))
    for x in points.T:  # (one coordinate at a time: a (count, count) array, not (count, count, dimensions))
        distance += (x[:, None] - x[None, :]) ** 2
    np.fill_diagonal(distance, -1.0)  # (each point first, dropped below)
    closest = np.argpartition(distance, NEIGHBOURS, axis=1)[:, :NEIGHBOURS + 1]
    order = np.lexsort((closest, np.take_along_axis(distance, closest, axis=1)), axis=1)
    return np.take_along_axis(closest, order, axis=1)[:, 1:]


def _neighbour_lists(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nearest (:func:`_nearest`) and the symmetric neighbour lists of ``points``: each pair (i, j) and (j, i)
    encoded as i·count + j, made unique and sorted by numpy (each row's neighbours in ascending order)."""
    count = points.shape[0]
    nearest = _nearest(points)
    i = np.repeat(np.arange(count, dtype=np.intp), NEIGHBOURS)
    j = nearest.ravel().astype(np.intp)
    pairs = np.unique(np.concatenate([i * count + j, j * count + i]))
    first, second = np.divmod(pairs, count)
    length = np.bincount(first, minlength=count)
    width = int(length.max())
    symmetric = np.repeat(np.arange(count, dtype=np.intp)[:, None], width, axis=1)  # padded with i itself
    symmetric[first, np.arange(pairs.size) - np.repeat(np.cumsum(length) - length, length)] = second
    nearest.flags.writeable = symmetric.flags.writeable = False
    return nearest, symmetric


def _magnitudes(integrand: Integrand, omega: np.ndarray, case: np.ndarray) -> np.ndarray:
    """max over channels of |g| (0 where not finite) at ``omega`` (k, m, 3) for the cases ``case`` (k,): (k, m)."""
    index = np.broadcast_to(case[:, None], omega.shape[:2])
    with np.errstate(all="ignore"):
        g = np.abs(np.asarray(integrand(omega.reshape(-1, 3), index.ravel()), dtype=float))
    g[~np.isfinite(g)] = 0.0
    return _largest(g.T).reshape(omega.shape[:2])


def _above_neighbours(g: np.ndarray, nearest: np.ndarray) -> np.ndarray:
    """Per row of samples ``g`` (k, m), no NaN among them, which are above all their neighbours ``nearest`` (m, n):
    ``g > g[:, nearest].max(axis=-1)``, each neighbour compared only with the samples above the ones before it
    (a sample above its first neighbour is one in two; strict maxima are few)."""
    k, m = g.shape
    flat = g.ravel()
    where = np.flatnonzero(g > g[:, nearest[:, 0]])
    value, sample = flat[where], where % m
    start = where - sample
    for column in nearest.T[1:]:
        above = value > flat[start + column[sample]]
        where, value, sample, start = where[above], value[above], sample[above], start[above]
    strict = np.zeros(g.size, dtype=bool)
    strict[where] = True
    return strict.reshape(k, m)


def _largest(columns) -> np.ndarray:
    """The elementwise maximum of the c ≥ 1 arrays ``columns`` (an array's first axis, or a list), no NaN among them:
    the values of a ``.max`` over their axis, as c − 1 maxima of whole arrays (a reduction over a short last axis
    runs its loop per element: a quarter of the search's CPU in the 32 × 32 ``ggx.brdf`` table, before)."""
    largest = columns[0]
    for column in columns[1:]:
        largest = np.maximum(largest, column)
    return largest


def _angles(omega: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Angles (k, m) between ``omega`` (k, m, 3) and ``centre`` (k, 3)."""
    return angle_between(omega, centre[:, None, :])


def _within(omega: np.ndarray, centre: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """``_angles(omega, centre) < radius[:, None]`` for unit directions ``omega`` (k, m, 3), ``centre`` (k, 3):
    the angles computed only where the dot product ω·c ≥ |c|(cos r − 10⁻⁹) (every angle below r, with a margin
    far above rounding; the others are farther than r)."""
    dot = np.einsum("kmi,ki->km", omega, centre)
    floor = norm(centre) * (np.cos(np.minimum(radius, np.pi)) - 1e-9)
    at, sample = np.nonzero(dot >= floor[:, None])
    near = np.zeros(dot.shape, dtype=bool)
    near[at, sample] = angle_between(omega[at, sample], centre[at]) < radius[at]
    return near


def _locate(omega: np.ndarray, g: np.ndarray,
            graph: tuple[np.ndarray, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The largest sample's direction (k, 3) and the width about it (k,) from samples ``g`` (k, m) at ``omega``.
    With ``graph`` = (neighbour lists, spacing), the core is only the samples above half the peak joined to it (the
    first ``symmetric.shape[0]`` samples by the lists, the others, likely directions, to those within ``spacing``):
    for a case with separated peaks, whose other lobes may be above half the peak elsewhere."""
    rows = np.arange(g.shape[0])
    top = np.argmax(g, axis=1)
    best = omega[rows, top]
    angle = _angles(omega, best)
    total = g.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt((g * angle**2).sum(axis=1) / total)
    # The RMS angle of the samples above half the peak measures the core: heavy tails (GGX at grazing views) make
    # the RMS angle of all samples far wider than the core that rounding noise lives in. (0 where only the peak
    # sample is above half: the core is unresolved, and zoomed into.)
    core = g >= 0.5 * g.max(axis=1, keepdims=True)
    if graph is not None:
        symmetric, spacing = graph
        n = symmetric.shape[0]
        start = np.zeros_like(core[:, :n])
        on = top < n
        start[rows[on], top[on]] = True
        start[~on] = angle[~on, :n] < spacing
        joined = np.zeros_like(core)
        joined[:, :n] = _component(core[:, :n], start & core[:, :n], symmetric)
        joined[rows, top] = True
        core = joined
    core_rms = np.sqrt(np.where(core, angle**2, 0.0).sum(axis=1) / np.maximum(core.sum(axis=1), 1))
    return best, np.where(total > 0, np.minimum(rms, 2.0 * core_rms), 1.0)


def _component(mask: np.ndarray, start: np.ndarray, symmetric: np.ndarray) -> np.ndarray:
    """Per row, the samples of ``mask`` (k, m) joined to those of ``start`` (k, m) through samples of ``mask`` on the
    neighbour lists ``symmetric`` (m, d): the connected components (one pass of
    :func:`scipy.sparse.csgraph.connected_components`) of the graph on the samples of ``mask | start`` of all rows,
    an edge between two of a row's samples that the lists join, that hold a sample of ``start``. (A flood from
    ``start`` through ``mask`` reaches exactly these, the lists being symmetric: a start sample outside ``mask``
    passes the flood on as any reached one does.)"""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    k, m = mask.shape
    node = (mask | start).ravel()
    where = np.flatnonzero(node)
    if where.size == 0:
        return np.zeros_like(start)
    index = np.full(node.size, -1, dtype=np.intp)
    index[where] = np.arange(where.size)
    row, sample = np.divmod(where, m)
    other = index[(row * m)[:, None] + symmetric[sample]]  # (nodes, d): each neighbour's node, -1 where none
    edge = other >= 0
    # The rows of the graph's CSR arrays are the nodes in order, so they come straight from ``other``; the graph is
    # symmetric, so its strong components are its components (and scipy builds no transpose for them).
    indptr = np.concatenate([[0], np.cumsum(edge.sum(axis=1))])
    graph = csr_matrix((np.ones(int(indptr[-1])), other[edge], indptr), shape=(where.size, where.size))
    labels = connected_components(graph, directed=True, connection="strong")[1]
    reached = np.zeros(labels.max() + 1, dtype=bool)
    reached[labels[start.ravel()[where]]] = True
    reach = np.zeros(node.size, dtype=bool)
    reach[where] = reached[labels]
    return reach.reshape(k, m)


def _sample(integrand: Integrand, directions_of: Callable[[np.ndarray], np.ndarray], count: int,
            subset: np.ndarray, max_nodes_per_call: int, graph: tuple[np.ndarray, float] | None = None,
            seen: Seen | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_locate` on ``count`` directions per case of ``subset`` (``directions_of(cases)`` (k, count, 3)), in
    bounded chunks, with the neighbour lists and spacing ``graph`` of those directions where given;
    ``seen(cases, omega, g)`` is shown each chunk's samples."""
    per_call = max(1, max_nodes_per_call // count)
    peaks, widths = [], []
    for start in range(0, subset.size, per_call):
        case = subset[start:start + per_call]
        omega = directions_of(case)
        g = _magnitudes(integrand, omega, case)
        if seen is not None:
            seen(case, omega, g)
        best, width = _locate(omega, g, graph)
        peaks.append(best)
        widths.append(width)
    return np.concatenate(peaks), np.concatenate(widths)


@cache
def _cap() -> tuple[np.ndarray, np.ndarray, float]:
    """Polar angles and azimuths of a cap of unit radius (its centre first: a zoom that finds nothing else above 0
    keeps the peak so far rather than moving to an arbitrary point), and its mean spacing (area ≈ π)."""
    cap = fibonacci_hemisphere(CAP_POINTS)
    angle = np.concatenate([[0.0], np.arccos(cap[:, 2]) / (np.pi / 2)])
    phi = np.concatenate([[0.0], np.arctan2(cap[:, 1], cap[:, 0])])
    return angle, phi, float(np.sqrt(np.pi / CAP_POINTS))


def _zoom(integrand: Integrand, peak: np.ndarray, width: np.ndarray, unresolved: np.ndarray, radius: np.ndarray,
          max_nodes_per_call: int, spent: np.ndarray | None = None,
          seen: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], None] | None = None,
          joined: bool = False) -> None:
    """Zoom into the lobes ``unresolved`` (indices into ``peak`` (k, 3) and ``width`` (k,), updated in place): a
    polar lattice on a cap of ``radius`` about the peak relocates it and measures it again, and the cap shrinks
    threefold until the lobe spans several of its points. ``spent`` (k,), where given, counts the evaluations;
    ``seen(indices, omega, g, spacing)`` is shown each cap's samples and their spacing; ``joined``: the core is the
    samples above half the peak joined to it on the cap (:func:`_locate`)."""
    cap_angle, cap_phi, cap_spacing = _cap()
    while unresolved.size and radius[unresolved].max() > 1e-10:
        around_peak = _cap_lattice(peak, unresolved, radius, cap_angle, cap_phi)
        shown = None if seen is None else lambda i, omega, g: seen(i, omega, g, cap_spacing * radius[i])
        peak[unresolved], width[unresolved] = _sample(integrand, around_peak, cap_angle.size, unresolved,
                                                      max_nodes_per_call, (_cap_neighbours()[1], 0.0) if joined
                                                      else None, shown)
        if spent is not None:
            spent[unresolved] += cap_angle.size
        resolved = width[unresolved] >= 2.0 * cap_spacing * radius[unresolved]
        radius[unresolved] /= 3.0
        unresolved = unresolved[~resolved]


def estimate_lobe(integrand: Integrand, cases: int, samples: int = SAMPLES, max_nodes_per_call: int = 1_500_000,
                  candidates: np.ndarray | None = None,
                  seen: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], None] | None = None,
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Find the peak direction and angular width of each case's integrand by sampling (no model hint).

    A Fibonacci lattice of ``samples`` directions locates the maximum of |g| to within the lattice spacing
    h ≈ √(2π/samples), together with ``candidates`` (K, m, 3), directions where a peak is likely (the mirror
    direction: a lobe narrower than h, Blinn-Phong at n = 1e7, underflows to 0 at every lattice point, and an
    integrand that is 0 at every sample would be integrated to 0 with a zero error estimate). The
    |g|-weighted RMS angle about the maximum estimates the width. A lobe narrower than the
    lattice (the RMS, or twice the RMS angle of the samples above half the peak, < 2h) is then zoomed into: a
    polar lattice on a cap of radius 3h around the peak relocates it and measures it again, and the cap shrinks
    threefold until the lobe spans several of its points (GGX at roughness 0.01 is 1e-4 rad wide; at α = 1e-8,
    1e-8 rad). The width is the smaller of the two RMS measures. The quadrature's efficiency
    depends on these numbers, and so does where :func:`rounding_noise` looks for noise (which is why the core,
    not the tails, must be found); the adaptivity and the quadrature error estimate do not.
    ``seen(cases, omega, g, spacing)`` is shown every sample, chunk by chunk, with the spacing of its lattice or cap
    (the separated-peak search reads them).
    """
    spacing = np.sqrt(2.0 * np.pi / samples)
    grid = fibonacci_hemisphere(samples)
    extra = np.zeros((cases, 0, 3)) if candidates is None else np.asarray(candidates, dtype=float)

    def lattice(case: np.ndarray) -> np.ndarray:
        return np.concatenate([np.broadcast_to(grid, (case.size,) + grid.shape), extra[case]], axis=1)

    shown = None if seen is None else lambda case, omega, g: seen(case, omega, g, np.full(case.size, spacing))
    peak, width = _sample(integrand, lattice, samples + extra.shape[1], np.arange(cases), max_nodes_per_call,
                          seen=shown)
    _zoom(integrand, peak, width, np.flatnonzero(width < 2.0 * spacing), np.full(cases, 3.0 * spacing),
          max_nodes_per_call, seen=seen)
    return peak, np.clip(width, 1e-12, 1.0), np.full(cases, np.pi)


def search_lobes(integrand: Integrand, cases: int, samples: int = SAMPLES, max_nodes_per_call: int = 1_500_000,
                 candidates: np.ndarray | None = None, negligible: float = 0.0,
                 axial: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, Peaks]:
    """:func:`estimate_lobe`'s main peak per case (poles, widths, supports) and the separated :class:`Peaks`
    besides it (the module's docstring says how they are found): the candidates come from the lattice's samples and
    from those of every cap the main peak's zoom samples. A peak whose contribution estimate is below
    ``negligible`` times the main peak's is charged, not kept (a bump in the far tails of the lobes: its own
    sub-case would integrate a crescent of their tails about a pole it does not centre). ``axial`` (K,): the cases
    whose integrand is rotation-invariant about N, which have no separated peaks (none is searched for): every
    maximum off N is a ring, and its samples — strict maxima of their neighbours, the arcs between them dipping
    below the ring — would be taken for peaks (the sheen lobe at normal incidence, a ring 0.003 rad above the
    horizon: six peaks and a charge of half the albedo)."""
    found = []
    searched = np.ones(cases, dtype=bool) if axial is None else ~np.asarray(axial, dtype=bool)

    def seen(case: np.ndarray, omega: np.ndarray, g: np.ndarray, spacing: np.ndarray) -> None:
        nearest, symmetric = _cap_neighbours() if g.shape[1] == CAP_POINTS + 1 else lattice_neighbours(samples)
        on = g[:, :nearest.shape[0]]  # (the lattice's samples, not the likely directions after them)
        strict = _above_neighbours(on, nearest) & (on > 0) & searched[case][:, None]
        # Not the main peak's own sample (where the main peak is a likely direction off the lattice, the lattice's
        # largest sample is a candidate: the arc test says whether it lies on the main peak's slope).
        best = np.argmax(g, axis=1)
        own = np.flatnonzero(best < on.shape[1])
        strict[own, best[own]] = False
        some = strict.any(axis=1)
        if some.any():
            # A main peak off the lattice counts as a sample joined to those within one spacing of it.
            top = omega[some, best[some]]
            near = _within(omega[some, :on.shape[1]], top, spacing[some])
            ceiling = np.where(near, g[some, best[some]][:, None], on[some])
            found.append(_candidates(case[some], omega[some, :on.shape[1]], on[some], ceiling, strict[some],
                                     symmetric, spacing[some]))

    poles, widths, supports = estimate_lobe(integrand, cases, samples, max_nodes_per_call, candidates, seen)
    case, direction, level, width, spacing, untested, untested_charge = (
        (np.concatenate(part) for part in zip(*found, strict=True)) if found
        else (np.zeros(0, dtype=np.intp), np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros(0),
              np.zeros(0, dtype=np.intp), np.zeros(0)))
    peaks = _confirmed(integrand, cases, poles, widths, case, direction, level, width, spacing, max_nodes_per_call,
                       negligible)
    np.add.at(peaks.charge, untested, untested_charge)  # candidates beyond MAX_CANDIDATES: charged, not dropped
    # A case with separated peaks has its main peak measured again, its core only the samples joined to it (another
    # lobe above half the peak within the first cap made Blinn-Phong's width 0.205 for 0.0064: the rules about it
    # then missed its core).
    multi = np.unique(peaks.case)
    if multi.size:
        spent = np.zeros(cases, dtype=np.int64)
        _zoom(integrand, poles, widths, multi, np.full(cases, 3.0 * np.sqrt(2.0 * np.pi / samples)),
              max_nodes_per_call, spent, joined=True)
        widths = np.clip(widths, 1e-12, 1.0)
        peaks = replace(peaks, evaluations=peaks.evaluations + spent)
    return poles, widths, supports, peaks


def _candidates(case: np.ndarray, omega: np.ndarray, g: np.ndarray, ceiling: np.ndarray, strict: np.ndarray,
                symmetric: np.ndarray, spacing: np.ndarray) -> tuple[np.ndarray, ...]:
    """Of the strict local maxima ``strict`` (k, m) of samples ``g`` at ``omega`` (k, m, 3), those whose half-level
    component (on the neighbour lists ``symmetric``) reaches no higher sample (nor a sample whose ``ceiling``, the
    highest value it touches, is higher), the largest :data:`MAX_CANDIDATES` per row: their case, direction, value,
    width (twice the RMS angle of that component; 0 where it is that sample alone) and their samples' ``spacing``;
    and the case and :data:`CHARGE` · g·2π·max(width, spacing)² of each one beyond them. (The component test comes
    first and costs no evaluation: a noisy plateau's many strict maxima, each reaching a higher sample, must not
    crowd out a lone sample of a narrow lobe elsewhere.)"""
    row, index = np.nonzero(strict)
    order = np.lexsort((-g[row, index], row))
    row, index = row[order], index[order]
    level = g[row, index]
    start = np.zeros(g[row].shape, dtype=bool)
    start[np.arange(row.size), index] = True
    reach = _component(g[row] >= SEPARATION * level[:, None], start, symmetric)
    alone = ~np.any(reach & (ceiling[row] > level[:, None]), axis=1)
    row, index, level, reach = row[alone], index[alone], level[alone], reach[alone]
    direction = omega[row, index]
    squared = np.zeros(reach.shape)  # (the angles of the component's samples alone: the others' terms are 0)
    at, sample = np.nonzero(reach)
    squared[at, sample] = angle_between(omega[row[at], sample], direction[at]) ** 2
    width = 2.0 * np.sqrt(squared.sum(axis=1) / np.maximum(reach.sum(axis=1), 1))
    keep = np.arange(row.size) - np.searchsorted(row, row) < MAX_CANDIDATES  # (rows in order, values descending)
    over = CHARGE * 2.0 * np.pi * level * np.maximum(width, spacing[row]) ** 2
    return (case[row][keep], direction[keep], level[keep], width[keep], spacing[row][keep], case[row][~keep],
            over[~keep])


def _confirmed(integrand: Integrand, cases: int, poles: np.ndarray, widths: np.ndarray, case: np.ndarray,
               direction: np.ndarray, level: np.ndarray, width: np.ndarray, spacing: np.ndarray,
               max_nodes_per_call: int, negligible: float) -> Peaks:
    """The candidates that the arc to their case's main peak separates from it, zoomed into and merged."""
    evaluations = np.zeros(cases, dtype=np.int64)
    # The arc to the main peak: a ridge thinner than the samples joins them there.
    t = np.arange(1, ARC_POINTS + 1) / (ARC_POINTS + 1)
    arc = direction[:, None, :] * (1.0 - t)[:, None] + poles[case][:, None, :] * t[:, None]
    arc /= np.maximum(norm(arc), 1e-300)[..., None]
    on_arc = _magnitudes(integrand, arc, case) if case.size else np.zeros((0, ARC_POINTS))
    np.add.at(evaluations, case, ARC_POINTS)
    apart = on_arc.min(axis=1, initial=np.inf) < SEPARATION * level
    case, direction, level, width, spacing = (case[apart], direction[apart], level[apart], width[apart],
                                              spacing[apart])
    # A curved ridge leaves the arc: the parallel arcs beside it, up to an eighth of its length away, where the arc
    # dipped (at each of its points the largest of them must dip too).
    across = np.cross(direction, poles[case])
    across /= np.maximum(norm(across), 1e-300)[..., None]
    length = angle_between(direction, poles[case])
    arc = arc[apart]
    beside = (arc[:, None] + (OFFSETS[None, :, None, None] * length[:, None, None, None]) * across[:, None, None, :])
    beside = (beside / norm(beside)[..., None]).reshape(case.size, OFFSETS.size * ARC_POINTS, 3)
    on_side = _magnitudes(integrand, beside, case).reshape(case.size, OFFSETS.size, ARC_POINTS) if case.size \
        else np.zeros((0, OFFSETS.size, ARC_POINTS))
    np.add.at(evaluations, case, OFFSETS.size * ARC_POINTS)
    apart = on_side.max(axis=1).min(axis=1, initial=np.inf) < SEPARATION * level
    case, direction, level, width, spacing = (case[apart], direction[apart], level[apart], width[apart],
                                              spacing[apart])
    # A ring about N leaves every great-circle arc: the path at the candidate's and the main peak's polar angles
    # (interpolated) between their azimuths, and paths beside it in polar angle (RING_OFFSETS), where the arcs dipped
    # (the sheen lobe near normal incidence: a ring 0.003 rad thick above the horizon, tilted by the view).
    polar = np.arccos(np.clip(direction[:, 2], -1.0, 1.0)), np.arccos(np.clip(poles[case][:, 2], -1.0, 1.0))
    azimuth = np.arctan2(direction[:, 1], direction[:, 0])
    turn = np.angle(np.exp(1j * (np.arctan2(poles[case][:, 1], poles[case][:, 0]) - azimuth)))
    theta = np.clip((polar[0][:, None] + t * (polar[1] - polar[0])[:, None])[:, None, :]
                    + RING_OFFSETS[None, :, None], 0.0, np.pi / 2)
    phi = (azimuth[:, None] + t * turn[:, None])[:, None, :]
    ring = np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)),
                    axis=-1).reshape(case.size, RING_OFFSETS.size * ARC_POINTS, 3)
    on_ring = _magnitudes(integrand, ring, case).reshape(case.size, RING_OFFSETS.size, ARC_POINTS) if case.size \
        else np.zeros((0, RING_OFFSETS.size, ARC_POINTS))
    np.add.at(evaluations, case, RING_OFFSETS.size * ARC_POINTS)
    apart = on_ring.max(axis=1).min(axis=1, initial=np.inf) < SEPARATION * level
    case, direction, width, spacing = case[apart], direction[apart].copy(), width[apart], spacing[apart]

    def at_case(omega: np.ndarray, peak: np.ndarray) -> np.ndarray:
        return integrand(omega, case[peak])

    spent = np.zeros(case.size, dtype=np.int64)
    _zoom(at_case, direction, width, np.flatnonzero(width < 2.0 * spacing), CANDIDATE_RADIUS * spacing,
          max_nodes_per_call, spent, joined=True)
    np.add.at(evaluations, case, spent)
    width = np.clip(width, 1e-12, 1.0)
    value = _magnitudes(at_case, direction[:, None, :], np.arange(case.size))[:, 0] if case.size else np.zeros(0)
    np.add.at(evaluations, case, 1)
    main = _magnitudes(integrand, poles[case][:, None, :], case)[:, 0] if case.size else np.zeros(0)
    np.add.at(evaluations, case, 1)
    small = value * width**2 < negligible * main * widths[case]**2
    charge = np.zeros(cases)
    np.add.at(charge, case[small], CHARGE * 2.0 * np.pi * (value * width**2)[small])
    keep = ~small
    return _merged(case[keep], direction[keep], width[keep], value[keep], poles, widths, charge, evaluations)


@cache
def _cap_neighbours() -> tuple[np.ndarray, np.ndarray]:
    """:func:`lattice_neighbours` of the zoom's cap (its centre and :data:`CAP_POINTS` points), in the plane of
    its polar coordinates."""
    angle, phi, _ = _cap()
    return _neighbour_lists(np.stack([angle * np.cos(phi), angle * np.sin(phi)], axis=-1))


def _merged(case: np.ndarray, direction: np.ndarray, width: np.ndarray, value: np.ndarray, poles: np.ndarray,
            widths: np.ndarray, charge: np.ndarray, evaluations: np.ndarray) -> Peaks:
    """Candidates merged into a kept peak within :data:`MERGE_WIDTHS` widths (the smaller; the main peak first, then
    by value), at most :data:`MAX_PEAKS` per case by contribution; the others' contributions charged."""
    kept = np.zeros(case.size, dtype=bool)
    contribution = value * 2.0 * np.pi * width**2
    for c in np.unique(case):
        mine = np.flatnonzero(case == c)
        mine = mine[np.argsort(-value[mine], kind="stable")]
        centres, sizes = [poles[c]], [widths[c]]
        for i in mine:
            apart = [angle_between(direction[i], p) > MERGE_WIDTHS * min(
                width[i], w) for p, w in zip(centres, sizes, strict=True)]
            if all(apart):
                kept[i] = True
                centres.append(direction[i])
                sizes.append(width[i])
        chosen = mine[kept[mine]]
        over = chosen[np.argsort(-contribution[chosen], kind="stable")][MAX_PEAKS - 1:]
        kept[over] = False
        charge[c] += CHARGE * contribution[over].sum()
    return Peaks(case[kept], direction[kept], width[kept], value[kept], charge, evaluations)


def _cap_lattice(peak: np.ndarray, cases: np.ndarray, radius: np.ndarray, cap_angle: np.ndarray,
                 cap_phi: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """Directions of a polar lattice (unit-radius angles ``cap_angle``, azimuths ``cap_phi``) scaled to each
    case's ``radius`` and rotated onto its ``peak``, as a function of case indices drawn from ``cases``."""
    P, T, B = lobe_frame(peak[cases])
    position = np.empty(radius.size, dtype=np.intp)
    position[cases] = np.arange(cases.size)
    cos_phi, sin_phi = np.cos(cap_phi)[None, :, None], np.sin(cap_phi)[None, :, None]

    def directions(case: np.ndarray) -> np.ndarray:
        i = position[case]
        angle = cap_angle[None, :] * radius[case][:, None]
        radial = cos_phi * T[i][:, None] + sin_phi * B[i][:, None]
        omega = np.cos(angle)[..., None] * P[i][:, None] + np.sin(angle)[..., None] * radial
        omega[..., 2] = np.maximum(omega[..., 2], 1e-9)
        return omega / norm(omega)[..., None]

    return directions
