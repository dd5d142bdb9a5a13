"""The hemisphere kernel (:func:`brdfnorm.engine.compiled.kernels.hemisphere`) and its map and rules
(:mod:`brdfnorm.engine.compiled.hemimap`): each shader's copy compiles one version of each of its kernels (the
panels and the sums share one kernel: one compile), and the map and the rules are compiled as functions of their
own, once per machine, not copied into every shader's kernels."""

from __future__ import annotations

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.compiled import drivers, hemimap
from brdfnorm.engine.machinery.kronrod import GAUSS, KRONROD, NODES


@pytest.fixture
def native():
    """The compiled integrand of a lobe whose kernels the warm-up ran (compiled or loaded) in this process."""
    model = bn.load("blinn-phong", n=20.0)
    rows = [model.native_kernel().pack(model.params)]
    return drivers.native_integrand(model.native_kernel(), np.array([[0.0, 0.0, 1.0]]), rows, True)


def _kernels(module) -> dict:
    """The module's own compiled functions, but those inlined into others (compiled only there)."""
    return {name: value for name, value in vars(module).items() if hasattr(value, "targetoptions")
            and value.py_func.__module__ == module.__name__ and value.targetoptions.get("inline") != "always"}


def test_every_kernel_of_a_shader_has_one_version(native):
    kernels = _kernels(native.kernels)
    assert "hemisphere" in kernels and "hemisphere_panels" not in kernels and "hemisphere_sums" not in kernels
    one, zero, unit = np.zeros(1, dtype=np.int64), np.zeros(1), np.ones(1)
    frame = (np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    # both rules again, on other sizes: still the one version the warm-up compiled
    drivers.hemisphere_panels(native, np.zeros(2, dtype=np.int64), *(np.array([a, b]) for a, b in ((0, 1), (1, 2))),
                              zero, unit, frame, unit, np.full(1, np.pi), NODES, KRONROD, GAUSS)
    drivers.hemisphere_sums(native, one, zero, unit, zero, unit, frame, unit, np.full(1, np.pi), NODES[:3], NODES[:5],
                            np.ones(3), np.ones(5))
    versions = {name: len(kernel.signatures) for name, kernel in kernels.items()}
    assert versions == dict.fromkeys(kernels, 1)


def test_the_map_and_the_rules_are_functions_of_their_own():
    """Not inlined (their IR copied and typed again in every shader's kernel) but called, and cached on disk."""
    for function in (hemimap.azimuth, hemimap.node, hemimap.kronrod_rule, hemimap.tensor_rule):
        assert function.targetoptions.get("inline", "never") == "never" and function._cache.__class__.__name__ == (
            "FunctionCache")


def test_both_rules_agree_with_the_kronrod_sums_on_a_panel(native):
    """One panel by the Kronrod rule and by the tensor rule with the K15 weights: the same K15 ⊗ K15 sum."""
    one, zero, unit = np.zeros(1, dtype=np.int64), np.zeros(1), np.ones(1)
    frame = (np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    bounds = (zero, np.full(1, 2 * np.pi), zero, unit)
    value, *_ = drivers.hemisphere_panels(native, one, *bounds, frame, np.full(1, 0.3), np.full(1, np.pi / 2), NODES,
                                          KRONROD, GAUSS)
    total = drivers.hemisphere_sums(native, one, *bounds, frame, np.full(1, 0.3), np.full(1, np.pi / 2), NODES, NODES,
                                    KRONROD, KRONROD)
    assert value[0, 0] > 0 and abs(total[0, 0] - value[0, 0]) <= 1e-14 * value[0, 0]
