"""The half-vector route's global rule fused into one kernel for ``.brdf`` shaders
(brdfnorm.engine.compiled.global_rule.shader_global, the loop of global_rule.fused_loop, the shader a first-class
function): it is used, loaded from the cache in a new process rather than compiled for each shader, its values equal
the numpy driver's over the same compiled shader within their estimates, the generic route keeps the same cases,
a non-finite shader value flags its case as the numpy driver's does, its estimates bound the error against the
one-dimensional GGX integral (brdfnorm.engine.routes.azimuthal, no code in common), and a hostile shader's text
reaches neither the kernels' copy nor anything the fused rule runs."""

from __future__ import annotations

import inspect
import warnings

import numpy as np
import pytest
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.engine.compiled import drivers, global_rule

pytest.importorskip("numba")

MUS = np.array([1e-4, 3e-4, 0.01, 0.05, 0.3, 0.8, 1.0])
ROUGHNESS = np.array([0.05, 0.3, 1.0])


@pytest.fixture
def fused_calls(monkeypatch):
    """albedo(fused: bool, model, theta, **kwargs) under the compiled backend, the shader's fused kernel used (and
    seen used) or hidden (the numpy driver over the same compiled rectangle integrand); the generic route's kept
    cases and ``failed`` flags of each call are recorded."""
    kernel, rectangle, calls = global_rule.integrate, drivers.slope_rectangle, []

    def integrate(*args):
        calls.append(args[-1][0] == "shader")
        return kernel(*args)

    def albedo(fused: bool, model, theta, **kwargs):
        flags = []

        def spy(native, geometry, F, rows, failed, linear, log_horizon):
            flags.append((failed, rows))
            integrand = rectangle(native, geometry, F, rows, failed, linear, log_horizon)
            if not fused:
                del integrand.fused
            return integrand

        # (the kernels loaded, and warmed, before the spy: the warm-up runs a rectangle integrand of its own)
        drivers.native_integrand(model.native_kernel(), np.zeros((1, 3)), [np.zeros(1)], True)
        monkeypatch.setattr(global_rule, "integrate", integrate)
        monkeypatch.setattr(drivers, "slope_rectangle", spy)
        before = len(calls)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = bn.albedo(model, theta, method="quadrature", backend="compiled", **kwargs)
        assert any(calls[before:]) == fused
        return result, [(f.copy(), np.array(r)) for f, r in flags]

    return albedo


def _same(flags, other) -> bool:
    """The same flags of the same route cases, call for call."""
    return len(flags) == len(other) and all(np.array_equal(f, g) and np.array_equal(r, s)
                                            for (f, r), (g, s) in zip(flags, other, strict=True))


@pytest.mark.parametrize("name, params", [("ggx.brdf", {"f0": 1.0}), ("charlie.brdf", {})])
def test_the_fused_rule_equals_the_numpy_driver_within_the_estimates(fused_calls, kept, name, params):
    model = bn.load(str(EXAMPLES / name), roughness=ROUGHNESS[:, None], **params)
    theta = np.arccos(MUS)[None, :]
    fused, flags_fused = fused_calls(True, model, theta, rtol=1e-10)
    kept_fused = [k.copy() for k in kept]
    kept.clear()
    driver, flags_driver = fused_calls(False, model, theta, rtol=1e-10)
    assert len(kept) == len(kept_fused) and all(np.array_equal(a, b) for a, b in zip(kept, kept_fused, strict=True))
    assert sum(k.sum() for k in kept) >= 0.5 * MUS.size * ROUGHNESS.size  # the route carries the batch
    assert _same(flags_fused, flags_driver)
    assert np.all(fused.converged) and np.all(driver.converged)
    assert np.all(np.abs(fused.value - driver.value) <= fused.error + driver.error)


def test_the_fused_kernel_is_compiled_once_for_every_shader(tmp_path):
    # a new process with an empty kernel cache, a shader it has never seen: the fused kernel loads from Numba's
    # cache of the package (its type holds no shader), only the small kernels of the shader's own copy compile
    import subprocess
    import sys

    code = ("import numpy as np, brdfnorm as bn\n"
            "from brdfnorm.engine.compiled import global_rule\n"
            f"m = bn.load({str(EXAMPLES / 'ggx.brdf')!r}, roughness=np.array([0.2, 0.7]), f0=0.5)\n"
            "r = bn.albedo(m, np.arccos([0.05, 0.6])[:, None], method='quadrature', backend='compiled')\n"
            "s = global_rule.shader_global\n"
            "print(len(s.overloads), sum(s.stats.cache_hits.values()), sum(s.stats.cache_misses.values()))\n")
    env = {**__import__("os").environ, "BRDFNORM_CACHE_DIR": str(tmp_path)}
    runs = [subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
            for _ in range(2)]
    # the first run may compile it (a fresh clone's first shader); the second loads it, in a new process
    assert runs[1].split() == ["1", "1", "0"], runs


def test_a_non_finite_shader_value_flags_its_case(fused_calls, kept):
    # examples/ggx.brdf at the tables' clamp μ = 1e-4: at some roughnesses the shader is not finite at a node
    # (0/0 at the horizon; halfvector_generic.MU_MIN_NARROW). Both drivers flag the same cases, and the route keeps
    # none of those.
    model = bn.load(str(EXAMPLES / "ggx.brdf"), roughness=np.linspace(0.05, 1.0, 32), f0=1.0)
    theta = np.arccos(1e-4)
    fused, flags_fused = fused_calls(True, model, theta, rtol=1e-10)
    kept_fused = [k.copy() for k in kept]
    kept.clear()
    driver, flags_driver = fused_calls(False, model, theta, rtol=1e-10)
    assert sum(f.sum() for f, _ in flags_fused) >= 4  # the flag path is exercised
    assert _same(flags_fused, flags_driver)
    assert all(np.array_equal(a, b) for a, b in zip(kept, kept_fused, strict=True))
    # (one route call per engine call here; its rectangle integrands, global and panels, share the flags)
    assert len(kept) == 1 and not kept[0][flags_fused[0][1][flags_fused[0][0]]].any()
    assert np.all(np.abs(fused.value - driver.value) <= fused.error + driver.error)


@pytest.mark.parametrize("rtol", [1e-6, 1e-10])
def test_the_fused_estimates_bound_the_error_against_the_one_dimensional_integral(fused_calls, kept, rtol):
    roughness = np.exp(np.random.default_rng(39).uniform(np.log(0.05), 0.0, 24))
    mu = np.exp(np.random.default_rng(40).uniform(np.log(1e-4), 0.0, 24))
    model = bn.load(str(EXAMPLES / "ggx.brdf"), roughness=roughness, f0=1.0)
    result, _ = fused_calls(True, model, np.arccos(mu), rtol=rtol)
    reference = bn.albedo(bn.load("ggx", alpha=roughness**2, shadowing="separable"), np.arccos(mu), rtol=1e-12)
    assert reference.method == "azimuthal"
    assert sum(k.sum() for k in kept) >= 12
    error = np.abs(result.value[:, 0] - reference.value.ravel())
    assert np.all(error <= result.error[:, 0] + reference.error.ravel()), (error / result.error[:, 0]).max()
    assert np.all(result.error[:, 0] <= rtol * result.value[:, 0])
    if rtol > 1e-9:
        assert error.max() > 1e-13  # the errors are visible at this tolerance: the check can fail


HOSTILE = '''analytic
::begin parameters
float global_grid 0.05 1 0.3
float shader 0 1 1
::end parameters
::begin shader
// """; import os; os.system("touch PWNED") #
float fused_loop(float _slope_value, float np) { return _slope_value * _slope_value / (3.14159265358979 * np * np); }
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    float __exec = dot(N, L);
    float failed = dot(N, V);
    if (__exec <= 0.0 || failed <= 0.0) return vec3(0.0);
    float a2 = global_grid * global_grid;
    float d = dot(N, normalize(L + V));
    d = d * d * (a2 - 1.0) + 1.0;
    return vec3(shader * fused_loop(global_grid, d) / (4.0 * failed * __exec + 1e-300));
}
::end shader
'''


def test_a_hostile_shader_reaches_nothing_the_fused_rule_runs(fused_calls, tmp_path):
    import numba

    path = tmp_path / "hostile.brdf"
    path.write_text(HOSTILE)
    model = bn.load(str(path), global_grid=ROUGHNESS[:, None])
    theta = np.arccos(MUS[1:])[None, :]
    fused, _ = fused_calls(True, model, theta, rtol=1e-9)
    reference = bn.albedo(model, theta, method="quadrature", backend="numpy", rtol=1e-9)
    assert np.all(np.abs(fused.value - reference.value) <= fused.error + reference.error)
    kernel = model.native_kernel()
    copy = drivers.kernels_file(kernel.key, numba.__version__).read_text(encoding="utf-8")
    template = inspect.getsource(__import__("brdfnorm.engine.compiled.kernels", fromlist=["_"]))
    assert copy == f"# brdfnorm compiled kernels for shader key {kernel.key!r} (generated; safe to delete)\n" + template
    assert all(c in "0123456789abcdef" for c in kernel.key)
    shader = inspect.getsource(kernel.function.py_func)
    for word in ("os.system", "PWNED", "__exec", "failed", "global_grid", "fused_loop", "_slope_value"):
        assert word not in shader.split("\n", 1)[1], word


@pytest.mark.parametrize("level", range(1, 12))
def test_the_kernels_weight_tables_are_fejers_second_rule(level):
    # (by FFT, global_rule.fejer_fft, against the direct sum of the numpy driver, tensor_rule.fejer)
    from brdfnorm.engine.machinery.tensor_rule import fejer

    nodes, weights = fejer(level)
    fast_nodes, fast_weights = global_rule.fejer_fft(level)
    assert np.array_equal(nodes, fast_nodes)
    assert np.abs(fast_weights - weights).max() <= 1e-16 and abs(fast_weights.sum() - 1.0) <= 1e-15
    assert np.array_equal(global_rule._WEIGHTS[level][:weights.size], fast_weights)


def test_a_shader_the_fused_rule_cannot_take_goes_to_the_panels(monkeypatch, capsys):
    from numba.core.errors import TypingError

    def refuse(*args):
        raise TypingError("no such signature")

    model = bn.load(str(EXAMPLES / "ggx.brdf"), roughness=np.array([0.1, 0.5]), f0=1.0)
    theta = np.arccos([0.02, 0.5, 0.9])[:, None]
    fused = bn.albedo(model, theta, method="quadrature", backend="compiled", rtol=1e-10)
    monkeypatch.setattr(global_rule, "shader_kernel", refuse)
    panels = bn.albedo(model, theta, method="quadrature", backend="compiled", rtol=1e-10)
    assert "the fused global rule does not compile for this shader (TypingError)" in capsys.readouterr().err
    assert np.all(panels.converged) and np.all(panels.evaluations >= fused.evaluations)
    assert panels.evaluations.sum() > 1.5 * fused.evaluations.sum()  # (the panels are dearer than the rule)
    assert np.all(np.abs(panels.value - fused.value) <= panels.error + fused.error)
