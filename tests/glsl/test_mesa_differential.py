"""Differential test: every ``examples/*.brdf`` evaluated by brdfnorm (float64 numpy) and by Mesa (llvmpipe).

Mesa compiles the file's own GLSL (see ``tests/helpers/mesa.py``) and runs it in float32 over random direction pairs
(L, V) in the open upper hemisphere; brdfnorm evaluates the same float32-representable pairs in float64. The
two must agree to float32 precision. Per pair and channel the tolerance is

    |mesa − ours| ≤ RTOL·|ours| + ATOL·max|ours| + sensitivity,

* ``RTOL`` = 1e-4: float32 carries 6e-8 relative per operation, and llvmpipe's exp2/log2 (hence pow, exp,
  log) are polynomial approximations good to a few 1e-7; a shader strings a few dozen operations together.
* ``ATOL``·max|ours|, ATOL = 1e-6: an absolute floor relative to the largest value of the batch, for values
  that float32 cannot resolve next to the peak — pow of tiny bases and exp of large negative arguments
  underflow (llvmpipe flushes denormals to zero) while float64 still gives 1e-40.
* ``sensitivity``: how much our float64 BRDF itself moves when every component of L, V and of the frame
  N, X, Y is perturbed by up to PERTURB = 8 float32 ulps (random, 4 tries) — a backward-error model of
  float32 rounding: the rounding of a dot product or of normalize() scales its result by 1 + O(ulp), as
  scaling N does, which input directions alone cannot mimic (normalize() removes their scale). It is large
  only where the lobe is ill-conditioned at float32 scale: pow(N·H, n) with n in the thousands (relative
  condition number n), differences of nearly equal numbers, or a pair within a few ulps of a branch edge of
  a discontinuous lobe (``banded_specular``). Elsewhere it is below RTOL and the test is a plain 1e-4
  relative comparison.

The examples avoid asin/acos: Mesa lowers them to a polynomial with ~4e-4 absolute error (measured), far from
float32 precision, so a lobe using them could not be compared at this tolerance (atan is good to ~2e-5).
The test is skipped, with the reason, only where no EGL OpenGL 4.3 context can be created at all.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import paths
from helpers.mesa import MesaBrdf, MesaUnavailable, context, uniform_values

from brdfnorm.brdffile import FRAME_N, FRAME_X, FRAME_Y, load_brdf, random_hemisphere

EXAMPLES = sorted(paths.EXAMPLES.glob("*.brdf"))
PAIRS = 4096
RTOL = 1e-4
ATOL = 1e-6
PERTURB = 8 * 2.0**-24
VARIANTS = ("default", "low", "high")


@pytest.fixture(scope="module")
def gl():
    try:
        return context()
    except MesaUnavailable as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="module")
def directions():
    rng = np.random.default_rng(20250403)
    L = random_hemisphere(rng, PAIRS).astype(np.float32)
    V = random_hemisphere(rng, PAIRS).astype(np.float32)
    # Also the special pairs: normal incidence and the mirror configuration.
    L[:3] = [[0, 0, 1], [0, 0, 1], [0.6, 0, 0.8]]
    V[:3] = [[0, 0, 1], [0.6, 0, 0.8], [-0.6, 0, 0.8]]
    return L.astype(np.float64), V.astype(np.float64), rng


def _toward(p, end: float, fraction: float = 0.5) -> float:
    """A value between the default and a slider end; geometric where the range spans decades."""
    start = float(p.default)
    if p.minimum is not None and p.minimum > 0 and p.maximum / p.minimum > 100:
        return float(np.exp(np.log(start) + fraction * (np.log(end) - np.log(start))))
    return start + fraction * (end - start)


def variant_values(parameters, variant: str) -> dict[str, object]:
    """Parameter values for a variant: the defaults, or every parameter moved toward its low/high end."""
    values: dict[str, object] = {}
    for p in parameters:
        if variant == "default":
            values[p.name] = p.default
        elif p.kind == "bool":
            values[p.name] = not p.default if variant == "low" else p.default
        elif p.kind == "color":
            values[p.name] = (1.0, 0.3, 0.05) if variant == "low" else (0.2, 0.5, 0.8)
        else:
            values[p.name] = _toward(p, p.minimum if variant == "low" else p.maximum)
    return values


_compiled: dict[Path, MesaBrdf] = {}


@pytest.mark.slow
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_numpy_evaluation_matches_mesa(gl, directions, path, variant):
    L, V, rng = directions
    if path not in _compiled:
        model = load_brdf(path)
        _compiled[path] = MesaBrdf(model.brdf_file)
    mesa = _compiled[path]
    values = variant_values(mesa.brdf.parameters, variant)
    model = load_brdf(path, **values)

    ours = model.eval(L, V)
    theirs = mesa(L.astype(np.float32), V.astype(np.float32), uniform_values(model.parameters, values))
    assert np.all(np.isfinite(ours)), "the examples are finite over the open hemisphere"
    assert np.all(np.isfinite(theirs)), "Mesa gave a non-finite value"

    sensitivity = np.zeros_like(ours)
    frame = [np.broadcast_to(axis, L.shape) for axis in (FRAME_N, FRAME_X, FRAME_Y)]
    for _ in range(4):
        perturbed = [a * (1 + PERTURB * rng.uniform(-1, 1, L.shape)) for a in (L, V, *frame)]
        sensitivity = np.maximum(sensitivity, np.abs(model.evaluate_in_frame(*perturbed) - ours))
    scale = np.max(np.abs(ours))
    tolerance = RTOL * np.abs(ours) + ATOL * scale + sensitivity
    difference = np.abs(theirs - ours)
    bad = np.argwhere(difference > tolerance)
    if bad.size:
        i, c = bad[np.argmax((difference - tolerance)[tuple(bad.T)])]
        pytest.fail(
            f"{path.name} ({variant}: {values}): {len(bad)} of {ours.size} values differ beyond float32 "
            f"precision; worst at L={L[i].tolist()}, V={V[i].tolist()}, channel {c}: ours {ours[i, c]!r}, "
            f"Mesa {theirs[i, c]!r}, tolerance {tolerance[i, c]:.3g}"
        )
    # Where the lobe is well conditioned the comparison is a plain relative one: most pairs must be there,
    # or the sensitivity term would be excusing a genuine disagreement.
    conditioned = sensitivity <= RTOL * np.abs(ours) + ATOL * scale
    assert conditioned.mean() > 0.5, f"only {conditioned.mean():.0%} of the values are well conditioned"
