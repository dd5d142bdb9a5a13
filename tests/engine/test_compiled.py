"""The compiled backend (issue 39): the built-in lobes' compiled kernels give their numpy values, the compiled
engine gives the numpy engine's albedos within their estimates and bounds the true error against independent
references, any njit function with the NativeKernel interface goes through the same kernels, and where a kernel
cannot compile or Numba is missing the numpy backend computes with a one-line notice."""

from __future__ import annotations

import os
import stat
import warnings

import numpy as np
import pytest
from helpers.references import phong_like_reference

import brdfnorm as bn
from brdfnorm.engine.compiled import backend
from brdfnorm.errors import ArgumentError, EvaluationError
from brdfnorm.models.base import Model, NativeKernel, normal_lobe

numba = pytest.importorskip("numba")

LOBES = [
    ("lambert", {"reflectance": 0.7}),
    ("phong", {"n": 30.0}),
    ("modified-phong", {"n": 0.0}),
    ("blinn-phong", {"n": 200.0}),
    ("blinn-phong-gaussian", {"n": 50.0}),
    ("burley", {"roughness": 0.8, "reflectance": 0.9}),
    ("oren-nayar", {"sigma": 0.3, "reflectance": 0.8}),
    ("fon", {"roughness": 0.7, "reflectance": 0.9}),
    ("eon", {"roughness": 0.4, "reflectance": 0.8}),
    ("eon", {"roughness": 1.0, "reflectance": 1.0, "fon_albedo": "approx"}),
    ("charlie", {"roughness": 0.6, "color": [0.9, 0.5, 0.2]}),
    ("charlie", {"alpha": 0.05, "shadowing": "neubelt"}),
    ("charlie", {"roughness": 0.3, "terminator": True}),
    ("ggx", {"alpha": 0.2}),
    ("ggx", {"alpha_x": 0.1, "alpha_y": 0.5, "fresnel": "conductor", "eta": [0.2, 0.9, 1.1], "k": [3.0, 2.5, 2.2]}),
    ("beckmann", {"alpha": 0.6, "shadowing": "separable", "fresnel": "schlick"}),
    ("beckmann", {"alpha": 0.05, "fresnel": "dielectric", "eta": [1.3, 1.5, 2.0]}),
]


def _directions(rng, count):
    v = rng.normal(size=(count, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[: count // 2, 2] = np.abs(v[: count // 2, 2])  # half in the upper hemisphere, the rest anywhere
    return v


@pytest.mark.parametrize(("name", "params"), LOBES)
def test_compiled_lobes_equal_their_numpy_evaluation(name, params, rng):
    model = bn.load(name, **params)
    kernel = model.native_kernel()
    assert kernel is not None and kernel.channels == model.channels
    L, V = _directions(rng, 400), _directions(rng, 400)
    V[:50] = L[:50] * np.array([-1.0, -1.0, 1.0])  # mirror pairs: the specular peak
    u = kernel.pack(model.params)
    compiled = np.array([kernel.function(*L[i], *V[i], u) for i in range(len(L))])
    with np.errstate(all="ignore"):
        expected = model.evaluate(L, V, model.params)
    both = np.isfinite(expected)
    assert np.array_equal(both, np.isfinite(compiled))
    np.testing.assert_allclose(compiled[both], expected[both], rtol=1e-12, atol=1e-300)


def test_lobes_without_a_kernel_say_so():
    assert bn.load("ggx", ms="kulla-conty").native_kernel() is None
    assert bn.load("ggx-dielectric").native_kernel() is None


@pytest.mark.parametrize(("name", "params"), LOBES[:8] + LOBES[10:11] + LOBES[14:15])
def test_compiled_albedos_agree_with_numpy_within_the_estimates(name, params):
    model = bn.load(name, **params)
    theta = np.array([0.0, 0.7, 1.3, 1.55])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reference = bn.albedo(model, theta, method="quadrature", rtol=1e-9, backend="numpy")
        compiled = bn.albedo(model, theta, method="quadrature", rtol=1e-9, backend="compiled")
    assert np.all(np.abs(compiled.value - reference.value) <= compiled.error + reference.error)
    np.testing.assert_array_equal(compiled.converged, reference.converged)


@pytest.mark.parametrize(("n", "theta", "original"), [(20.0, 0.4, True), (500.0, 1.2, False), (8.0, 1.5, True)])
def test_compiled_estimates_bound_the_true_error(n, theta, original):
    model = bn.load("phong" if original else "modified-phong", n=n)
    truth = phong_like_reference(n, theta, original=original)
    for over in ("light",) if original else ("light", "view"):  # the modified lobe is reciprocal
        result = bn.albedo(model, theta, method="quadrature", rtol=1e-10, over=over, backend="compiled")
        assert abs(result.value[0] - truth) <= result.error[0], (over, result.value, truth, result.error)


class Clone(Model):
    """Modified Phong with a hand-written compiled kernel: the engine must use that kernel."""

    name = "clone"

    def evaluate(self, L, V, params):
        rv = -L[..., 0] * V[..., 0] - L[..., 1] * V[..., 1] + L[..., 2] * V[..., 2]
        return (np.maximum(rv, 0.0) ** 10.0)[..., None]

    def lobe(self, fixed, params, over):
        return normal_lobe(fixed)

    def native_kernel(self):
        @numba.njit(cache=False)
        def cosine_power(lx, ly, lz, vx, vy, vz, u):
            return (max(-lx * vx - ly * vy + lz * vz, 0.0) ** u[0],)

        return NativeKernel(cosine_power, 1, lambda params: np.array([10.0]), "test:clone")


def test_a_hand_written_kernel_goes_through_the_compiled_engine(monkeypatch):
    from brdfnorm.engine import methods

    seen = []
    real = methods.with_native

    def spy(problem, chosen):
        problem = real(problem, chosen)
        seen.append(problem.native)
        return problem

    monkeypatch.setattr(methods, "with_native", spy)
    result = bn.albedo(Clone(), 0.0, rtol=1e-11, backend="compiled")
    assert seen and seen[0] is not None
    assert abs(result.value[0] - 2 * np.pi / 12) <= result.error[0] <= 1e-11


def test_a_kernel_that_does_not_compile_falls_back_to_numpy_with_one_notice(capsys):
    class Broken(Clone):
        def native_kernel(self):
            @numba.njit(cache=False)
            def broken(lx, ly, lz, vx, vy, vz, u):
                return (object(),)

            return NativeKernel(broken, 1, lambda params: np.zeros(1), "test:broken")

    first = bn.albedo(Broken(), 0.0, rtol=1e-11, backend="compiled")
    second = bn.albedo(Broken(), 0.3, rtol=1e-11, backend="compiled")
    lines = [line for line in capsys.readouterr().err.splitlines() if "test:broken" in line]
    assert len(lines) == 1 and lines[0].endswith("using the numpy backend")
    assert abs(first.value[0] - 2 * np.pi / 12) <= first.error[0] and second.converged.all()


def test_nonfinite_values_are_reported_or_zeroed_under_the_compiled_backend():
    class HalfNaN(Clone):
        def native_kernel(self):
            @numba.njit(cache=False)
            def half_nan(lx, ly, lz, vx, vy, vz, u):
                return (np.nan if lx > 0 else 1.0 / np.pi,)

            return NativeKernel(half_nan, 1, lambda params: np.zeros(1), "test:half-nan")

    with pytest.raises(EvaluationError, match=r"L=\(.*\), V=\(0, 0, 1\)"):
        bn.albedo(HalfNaN(), 0.0, backend="compiled")
    with pytest.warns(UserWarning, match="non-finite"):
        result = bn.albedo(HalfNaN(), 0.0, nonfinite="zero", rtol=1e-9, backend="compiled")
    assert abs(result.value[0] - 0.5) < 1e-9 and abs(result.nonfinite_fraction - 0.5) < 1e-9


def test_the_backend_is_chosen_by_argument_then_environment(monkeypatch):
    monkeypatch.setenv(backend.ENVIRONMENT, "numpy")
    assert backend.resolve() == "numpy" and backend.resolve("compiled") == "compiled"
    with backend.scope("compiled"):
        assert backend.resolve() == "compiled"
    monkeypatch.setenv(backend.ENVIRONMENT, "fast")
    with pytest.raises(ArgumentError, match="BRDFNORM_BACKEND: unknown backend 'fast'"):
        backend.resolve()
    with pytest.raises(ArgumentError, match="unknown backend"):
        bn.albedo(bn.load("lambert"), 0.0, backend="gpu")


def test_without_numba_the_numpy_backend_computes(monkeypatch):
    monkeypatch.setattr(backend, "numba_available", lambda: False)
    monkeypatch.delenv(backend.ENVIRONMENT, raising=False)
    assert backend.resolve() == "numpy"
    result = bn.albedo(bn.load("oren-nayar"), 0.5, method="quadrature")
    assert result.converged.all()


def test_the_kernel_cache_directory_is_private(monkeypatch, tmp_path):
    from brdfnorm.engine.compiled import drivers

    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path / "cache"))
    path = drivers.cache_directory()
    for directory in (path, path.parent):
        assert directory.is_dir() and stat.S_IMODE(os.stat(directory).st_mode) & 0o077 == 0


def test_the_cli_takes_a_backend(monkeypatch, run_cli):
    monkeypatch.delenv(backend.ENVIRONMENT, raising=False)  # restored after the test: --backend sets it
    code, out, _ = run_cli("albedo", "oren-nayar", "--theta", "30", "--backend", "numpy", "--csv")
    assert code == 0 and os.environ[backend.ENVIRONMENT] == "numpy" and ",quadrature," in out
    code, _, err = run_cli("albedo", "lambert", "--theta", "30", "--backend", "gpu")
    assert code == 2 and err.startswith("error: ")
