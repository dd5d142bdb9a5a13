"""The rounding-noise survey (:func:`brdfnorm.engine.machinery.rounding.surveyed_noise`): where it stands for the
probe its amplitude is never below the probe's, where the noise can matter it is the probe's exactly, and its
nodes are the probe's (a case that needs the whole probe evaluates each of its 576 nodes once)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers.paths import EXAMPLES, FIXTURES

import brdfnorm as bn
from brdfnorm.engine.machinery import rounding
from brdfnorm.engine.routes import hemisphere


class _Observed(Exception):
    pass


def _probe_inputs(model, theta, **keywords):
    """(integrand, frame, widths, supports, epsilon, anisotropic) of the hemisphere route's probe for ``theta``."""
    seen = []

    def observed(integrand, frame, widths, supports, rtol, max_nodes_per_call=1_500_000, epsilon=None,
                 anisotropic=None):
        seen.append((integrand, frame, widths, supports, epsilon, anisotropic))
        raise _Observed

    with pytest.MonkeyPatch.context() as patch, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        patch.setattr(hemisphere, "surveyed_noise", observed)
        with pytest.raises(_Observed):
            bn.albedo(model, np.atleast_1d(theta), method="quadrature", rtol=1e-9, backend="numpy", **keywords)
    return seen[0]


def _counted(integrand):
    count = []

    def counting(omega, case):
        count.append(omega.shape[0])
        return integrand(omega, case)
    return counting, count


def test_where_the_survey_stands_its_amplitude_is_above_the_probes():
    integrand, frame, widths, supports, epsilon, _ = _probe_inputs(bn.load("blinn-phong", n=100.0),
                                                                   np.radians([0.0, 30.0, 60.0, 86.0]))
    counting, count = _counted(integrand)
    amplitude, evaluations = rounding.surveyed_noise(counting, frame, widths, supports, 1e-9, epsilon=epsilon)
    probe = rounding.rounding_noise(integrand, frame, widths, supports, epsilon=epsilon)
    assert evaluations.tolist() == [rounding.SURVEY_EVALUATIONS] * 4 == [96] * 4
    assert sum(count) == 4 * 96
    assert np.all(amplitude >= probe) and np.all(amplitude <= rounding.SURVEY_MARGIN * probe * 4)


@pytest.mark.parametrize(("n", "rtol"), [(1e9, 1e-9), (1e4, 1e-12), (100.0, 0.0)])
def test_where_the_noise_can_matter_it_is_the_probes_exactly(n, rtol):
    integrand, frame, widths, supports, epsilon, _ = _probe_inputs(bn.load("blinn-phong", n=n),
                                                                   np.radians([0.0, 45.0, 86.0]))
    counting, count = _counted(integrand)
    amplitude, evaluations = rounding.surveyed_noise(counting, frame, widths, supports, rtol, epsilon=epsilon)
    probe = rounding.rounding_noise(integrand, frame, widths, supports, epsilon=epsilon)
    assert np.array_equal(amplitude, probe)
    assert evaluations.tolist() == [rounding.PROBE_EVALUATIONS] * 3 == [576] * 3
    assert sum(count) == 3 * 576  # the survey's nodes are reused


def test_an_anisotropic_lobe_takes_the_whole_probe():
    # examples/ashikhmin_shirley.brdf: the probe's rays at 1 width cross the lobe's narrow axis, where they see up
    # to ~10 times what the survey's rays do (random views, docs/performance.md).
    model = bn.load(str(EXAMPLES / "ashikhmin_shirley.brdf"), nu=10.0, nv=3000.0)
    integrand, frame, widths, supports, epsilon, anisotropic = _probe_inputs(model, np.radians([70.0]), phi=0.7)
    assert anisotropic is not None and anisotropic.all()
    amplitude, evaluations = rounding.surveyed_noise(integrand, frame, widths, supports, 1e-9, epsilon=epsilon,
                                                     anisotropic=anisotropic)
    assert np.array_equal(amplitude, rounding.rounding_noise(integrand, frame, widths, supports, epsilon=epsilon))
    assert evaluations.tolist() == [576]


def _families(rng, count):
    views = np.radians(np.concatenate([rng.uniform(0.0, 85.0, count - count // 3), rng.uniform(85.0, 89.9,
                                                                                               count // 3)]))
    for name in ("blinn-phong", "phong", "modified-phong"):
        yield bn.load(name).with_params(n=np.exp(rng.uniform(0.0, np.log(1e8), count))), rng.permutation(views)
    yield (bn.load(str(EXAMPLES / "beckmann.brdf")).with_params(alpha=np.exp(rng.uniform(np.log(1e-3), 0.0, count))),
           rng.permutation(views))
    yield (bn.load(str(EXAMPLES / "ggx.brdf")).with_params(roughness=np.exp(rng.uniform(np.log(0.03), 0.0, count)),
                                                           f0=np.ones(count)), rng.permutation(views))
    yield (bn.load(str(FIXTURES / "ggx_naive.brdf")).with_params(alpha=np.exp(rng.uniform(np.log(1e-5), 0.0,
                                                                                          count))),
           rng.permutation(views))
    yield (bn.load(str(EXAMPLES / "oren_nayar.brdf")).with_params(sigma=rng.uniform(0.05, 1.5, count),
                                                                  rho=np.full(count, 0.8)), rng.permutation(views))
    n = np.exp(rng.uniform(0.0, np.log(2e4), count))
    yield (bn.load(str(FIXTURES / "off_plane_lobes.brdf")).with_params(
        n=n, m=n * rng.uniform(1.5, 30.0, count), weight=np.exp(rng.uniform(np.log(0.01), np.log(10.0), count)),
        azimuth=rng.uniform(-1.0, 1.0, count)), rng.permutation(views))


@pytest.mark.slow
def test_the_margin_covers_the_probe_on_random_isotropic_lobes(rng):
    """The survey's margin (4) against the largest probe / survey amplitude over random lobes of eight families
    (2.1 measured over five seeds of 60 cases each), less the rounding floor's share: what the survey reports
    where it stands is at least 1.5 times the probe's."""
    worst = 0.0
    for model, theta in _families(rng, 30):
        integrand, frame, widths, supports, epsilon, anisotropic = _probe_inputs(model, theta)
        isotropic = ~anisotropic
        amplitude, _ = rounding.surveyed_noise(integrand, frame, widths, supports, 1.0, epsilon=epsilon,
                                               anisotropic=anisotropic)  # (rtol 1: the survey stands everywhere)
        probe = rounding.rounding_noise(integrand, frame, widths, supports, epsilon=epsilon)
        assert np.all(probe <= amplitude)
        # (where the survey's amplitude is its measurement, not the plateau charge or the clamp at 1)
        measured = isotropic[:, None] & (amplitude > rounding._floored(np.zeros_like(amplitude), widths, epsilon))
        worst = max(worst, float((probe / amplitude)[measured].max(initial=0.0)))
    print(f"largest probe / survey amplitude: {worst * rounding.SURVEY_MARGIN:.3g}")
    assert 0.0 < worst <= 1 / 1.5, worst
