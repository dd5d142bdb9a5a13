"""Issue 39, "honesty kept", for the rectangle driver (brdfnorm.engine.machinery.panels.adaptive_rectangles) of the
half-vector and dielectric routes: estimates found smaller than their true errors, each against an independent
reference — the 1-D polar integral of helpers.references.phong_like_reference (scipy's quad), math.fsum."""

from __future__ import annotations

import math

import numpy as np
from helpers.honesty import BACKENDS, honesty_ratio
from helpers.references import phong_like_reference

import brdfnorm as bn
from brdfnorm.engine.machinery.kinks import SURPRISE, surprised
from brdfnorm.engine.machinery.panels import per_case


@BACKENDS
def test_modified_phong_with_a_weak_edge_singularity_is_not_settled_on_a_surprised_panel(backend):
    # max(cos α, 0)^1.735 at the support edge crosses a half-vector panel obliquely: its |K − G| was 4.0e-10, its
    # quarters differed by 3.8e-9 and its true error was 1.2e-8; the case stopped 2.1× outside its estimate.
    n, theta = 1.735, np.radians(18.95)
    model = bn.load("modified-phong").with_params(n=np.array([n]))
    exact = phong_like_reference(n, theta, original=False)
    assert honesty_ratio(model, theta, exact, 1e-8, backend) <= 1.0


def test_surprised_marks_a_confirmation_several_times_above_the_pair_estimate():
    err = np.array([[1e-10, 1e-12], [1e-10, 1e-12], [1e-10, 1e-12]])
    change = np.array([[SURPRISE * 0.5e-10, 0.0], [SURPRISE * 2e-10, 0.0], [0.0, SURPRISE * 1e-11]])
    assert surprised(change, err / 2, err / 2).tolist() == [False, True, True]


def test_per_case_sums_many_panels_without_a_running_sum_error():
    # One case's value spread over 200 000 panels next to a large one (a lobe refined into a long tail of small
    # panels): a running sum (np.add.at) was 1.4e-14 off math.fsum here, far above the 50ε∫|g| of the estimates.
    rng = np.random.default_rng(3)
    values = rng.uniform(0.0, 1e-5, (200_000, 2))
    values[0] = 0.9
    case = rng.integers(0, 3, values.shape[0])
    total = per_case(4, case, values)
    for k in range(3):
        for c in range(2):
            exact = math.fsum(values[case == k, c])
            assert abs(total[k, c] - exact) <= 4 * np.finfo(float).eps * exact
    assert np.all(total[3] == 0.0)
