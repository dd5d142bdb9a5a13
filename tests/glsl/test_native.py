"""The native backend of ``.brdf`` shaders (issue 39): one scalar Numba function per shader, whose values are the
numpy backend's (the reference) at random and special direction pairs and parameter values, for every example
and fixture; loops with the numpy backend's bounds; the per-user disk cache; and a fixed Gauss–Legendre product
rule over the compiled function agreeing with ``brdfnorm.albedo`` on the numpy path.
"""

from __future__ import annotations

import os
import stat
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers.paths import REPO
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

pytest.importorskip("numba")

import brdfnorm as bn  # noqa: E402 - after the skip: the backend needs Numba
from brdfnorm.brdffile import load_brdf, parse_brdf  # noqa: E402
from brdfnorm.errors import EvaluationError  # noqa: E402
from brdfnorm.glsl.native import cache, native_kernel  # noqa: E402

ROOT = REPO
SHADERS = sorted((ROOT / "examples").glob("*.brdf")) + sorted((ROOT / "tests" / "fixtures").glob("*.brdf"))
#: Cheap ones in the quick tier: a plain lobe, a per-lane do-while loop, a loop with break/continue on a parameter.
QUICK = ["ggx.brdf", "layered_series.brdf", "multi_lobe.brdf"]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def directions(rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Random pairs over the whole sphere (below the horizon too), then the special pairs: N, grazing, L = V,
    L = −V (0/0 in the half vector), the mirror pair (H = N), signed zeros and exact axes."""
    L, V = _unit(rng.normal(size=(count, 3))), _unit(rng.normal(size=(count, 3)))
    s = np.sqrt(0.5)
    special = [
        ([0, 0, 1], [0, 0, 1]), ([1, 0, 0], [0, 0, 1]), ([0, 0, 1], [1, 0, 0]), ([1, 0, 0], [-1, 0, 0]),
        ([s, 0, s], [s, 0, s]), ([s, 0, s], [-s, 0, -s]), ([s, 0, s], [-s, 0, s]), ([0, 0, -1], [0, 0, 1]),
        ([-0.0, -0.0, 1.0], [0.0, -0.0, 1.0]), ([0, 1, 0], [0, -1, 0]), ([0.6, 0.0, 0.8], [-0.6, 0.0, 0.8]),
        ([1e-300, 0, 1], [0, 1e-300, 1]), ([0, s, -s], [0, -s, s]),
    ]
    Ls, Vs = (np.array([p[k] for p in special], dtype=float) for k in (0, 1))
    return np.concatenate([L, _unit(Ls)]), np.concatenate([V, _unit(Vs)])


def random_params(model, rng: np.random.Generator) -> dict:
    """Each declared parameter drawn over its slider range (bools both ways, colours per channel)."""
    values = {}
    for p in model.parameters:
        if p.kind == "bool":
            values[p.name] = bool(rng.integers(2))
        elif p.kind == "color":
            values[p.name] = tuple(rng.uniform(0.0, 1.0, 3))
        else:
            values[p.name] = float(rng.uniform(p.minimum, p.maximum))
    return values


def native_values(kernel, L: np.ndarray, V: np.ndarray, params) -> np.ndarray:
    u = kernel.pack(params)
    return np.array([kernel.function(*l, *v, u) for l, v in zip(L, V, strict=True)])


def assert_same(native: np.ndarray, reference: np.ndarray, where: str) -> None:
    """Equal to 1e-13 of the value (or of the largest value, near a cancellation); NaN and ±inf where numpy."""
    assert np.array_equal(np.isnan(native), np.isnan(reference)), where
    infinite = np.isinf(reference)
    assert np.array_equal(native[infinite], reference[infinite]), where
    finite = np.isfinite(reference)
    scale = np.max(np.abs(reference[finite]), initial=0.0)
    np.testing.assert_allclose(native[finite], reference[finite], rtol=1e-13, atol=1e-13 * scale, err_msg=where)


def check_shader(path: Path, rng: np.random.Generator, count: int, draws: int) -> None:
    model = load_brdf(path)
    kernel = model.native_kernel()
    assert kernel is not None, f"{path.name}: the native backend must cover every example and fixture"
    assert kernel.channels == 3 and len(kernel.key) == 40
    L, V = directions(rng, count)
    for draw in range(draws):
        params = model.params if draw == 0 else model.with_params(**random_params(model, rng)).params
        with np.errstate(all="ignore"):
            reference = model.evaluate(L, V, params)
        assert_same(native_values(kernel, L, V, params), reference, f"{path.name} {params}")


@pytest.mark.parametrize("name", QUICK)
def test_native_values_are_the_numpy_backends(name):
    check_shader(ROOT / "examples" / name, np.random.default_rng(7), 200, 3)


@pytest.mark.slow
@pytest.mark.parametrize("path", SHADERS, ids=lambda p: p.name)
def test_every_example_and_fixture_compiles_to_the_numpy_backends_values(path):
    check_shader(path, np.random.default_rng(11), 600, 6)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.floats(0.0, np.pi), st.floats(-np.pi, np.pi), st.floats(0.0, np.pi), st.floats(-np.pi, np.pi),
    st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(1.0, 2.0),
)
def test_a_per_lane_loop_agrees_at_any_directions_and_parameters(tl, pl, tv, pv, rho, f0, eta):
    """layered_series sums a series whose length differs per direction pair (a do-while with a per-lane exit)."""
    model = load_brdf(ROOT / "examples" / "layered_series.brdf", rho=rho, f0=f0, eta=eta)
    L = np.array([[np.sin(tl) * np.cos(pl), np.sin(tl) * np.sin(pl), np.cos(tl)]])
    V = np.array([[np.sin(tv) * np.cos(pv), np.sin(tv) * np.sin(pv), np.cos(tv)]])
    with np.errstate(all="ignore"):
        reference = model.evaluate(L, V, model.params)
    assert_same(native_values(model.native_kernel(), L, V, model.params), reference, "layered_series")


def brdf_file(tmp_path: Path, body: str, params: str = "float n 1 100 10") -> Path:
    path = tmp_path / "shader.brdf"
    path.write_text(f"analytic\n::begin parameters\n{params}\n::end parameters\n::begin shader\n{body}\n"
                    "::end shader\n")
    return path


LOOP_BOUNDS = [
    ("float x = 0.0; while (true) { x += 1.0; } return vec3(x);", "loop exceeded 10000 iterations"),
    ("float x = 0.0; for (int i = 0; i < 200; i++) { for (int j = 0; j < 600; j++) { x += 1.0; } }"
     " return vec3(x);", "loops exceeded 100000 iterations in total"),
    ("#define A0 (x * 0.5)\n" + "".join(f"#define A{k} (A{k - 1} + A{k - 1})\n" for k in range(1, 9))
     + "float x = 1.0; for (int i = 0; i < 9000; i++) { x = A8; } return vec3(x);",
     r"loops ran more than 2000000 nodes in one evaluation \(\d+ per iteration"),
]


@pytest.mark.parametrize(("statements", "message"), LOOP_BOUNDS)
def test_loop_bounds_give_nan_where_numpy_raises(tmp_path, statements, message):
    """The compiled function returns NaN where the numpy backend raises its error (which names the loop): the
    caller evaluates that pair with numpy to report it as today."""
    path = brdf_file(tmp_path, f"vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {{\n{statements}\n}}")
    model = load_brdf(path)
    with pytest.raises(EvaluationError, match=message) as numpy_error:
        model.eval([0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
    assert f"{path}:" in str(numpy_error.value)
    kernel = model.native_kernel()
    assert np.isnan(kernel.function(0.0, 0.0, 1.0, 0.0, 0.0, 1.0, kernel.pack(model.params))).all()


@pytest.mark.slow
def test_a_loop_bound_inside_a_parallel_loop_shows_as_nan(tmp_path):
    """Inside a Numba prange an exception would be lost (the loop finishes as if nothing happened): the NaN of a
    bound hit reaches the caller's sums, next to finite values where the loop ends."""
    import numba

    statements = "float x = 0.0; while (L.z > 0.5) { x += 1.0; } return vec3(x);"
    model = load_brdf(brdf_file(tmp_path, f"vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {{ {statements} }}"))
    kernel = model.native_kernel()

    @numba.njit(parallel=True)
    def sweep(f, z, u, out):
        for i in numba.prange(z.size):
            out[i] = f(0.0, 0.0, z[i], 0.0, 0.0, 1.0, u)[0]

    z, out = np.linspace(0.0, 1.0, 101), np.zeros(101)
    sweep(kernel.function, z, kernel.pack(model.params), out)
    assert np.array_equal(np.isnan(out), z > 0.5) and np.all(out[z <= 0.5] == 0.0)


def test_integer_bit_operations_on_run_time_values_agree(tmp_path):
    """``%``, ``&``, ``|``, ``^``, ``<<``, ``>>`` and ``~`` on ints and uints computed from the directions and a
    parameter (negative values, zero divisors and shifts past 31 included) give the numpy backend's values."""
    body = """
    int a = int(L.x * 1000.0) - int(n);          // negative and positive
    int b = int(V.y * 7.0);                      // zero for some pairs: x % 0
    uint c = uint(abs(L.z) * 4e9);               // above 2^31
    int s = int(V.z * 40.0);                     // shift counts past 31
    float r = float(a % 13) + float(a % b) + float(a & b) + float(a | 255) + float(a ^ b) + float(~a);
    float q = float(c % 7u) + float(c >> 3u) + float(c << uint(s)) + float(a << s) + float(a >> s) + float(~c);
    return vec3(r, q, float((c & 0xFFu) ^ uint(b)));
    """
    model = load_brdf(brdf_file(tmp_path, f"vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {{{body}}}"))
    kernel = model.native_kernel()
    assert kernel is not None
    L, V = directions(np.random.default_rng(2), 300)
    for n in (10.0, 77.0):
        params = model.with_params(n=n).params
        assert_same(native_values(kernel, L, V, params), model.evaluate(L, V, params), f"n={n}")


@pytest.mark.parametrize("scale", ["1.0", "n", "1e-20", "1e20"])
def test_powers_with_small_integer_exponents_agree(tmp_path, scale):
    """pow(x, 3.0) … pow(x, 16.0) are products in the kernel (a scalar pow is slow): within 1e-15 of numpy's,
    NaN for x < 0 and 0 at x = 0 as Mesa's pow, overflowing to inf and underflowing as pow does."""
    terms = " + ".join(f"pow(x, {k}.0) * {1.0 / k!r}" for k in range(3, 17))
    body = f"float x = ({scale}) * L.z; return vec3({terms}, pow(x, 5.0), pow(x - 0.5 * ({scale}), 7.0));"
    model = load_brdf(brdf_file(tmp_path, f"vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {{ {body} }}"))
    L, V = directions(np.random.default_rng(4), 300)
    with np.errstate(all="ignore"):
        reference = model.evaluate(L, V, model.params)
    native = native_values(model.native_kernel(), L, V, model.params)
    assert_same(native, reference, scale)
    finite = np.isfinite(reference) & (np.abs(reference) > 1e-300)
    np.testing.assert_allclose(native[finite], reference[finite], rtol=1e-15)


def test_gauss_legendre_over_the_compiled_function_matches_albedo():
    """A fixed 2-D Gauss–Legendre product rule in (cos θ, φ), summed by a Numba loop calling the compiled
    shader, agrees with brdfnorm.albedo of the numpy backend (a smoke test of calling the kernel from compiled
    code; the engine has its own integration)."""
    import numba

    @numba.njit(cache=False)
    def integrate(f, u, vx, vy, vz, mu, wmu, phi, wphi):
        total = np.zeros(3)
        for i in range(mu.size):
            s = np.sqrt(1.0 - mu[i] * mu[i])
            for j in range(phi.size):
                r, g, b = f(s * np.cos(phi[j]), s * np.sin(phi[j]), mu[i], vx, vy, vz, u)
                w = wmu[i] * wphi[j] * mu[i]
                total[0] += w * r
                total[1] += w * g
                total[2] += w * b
        return total

    model = load_brdf(ROOT / "examples" / "ggx.brdf", roughness=0.6)
    kernel = model.native_kernel()
    x, w = np.polynomial.legendre.leggauss(160)
    mu, wmu = 0.5 * (x + 1.0), 0.5 * w
    phi, wphi = np.pi * (x + 1.0), np.pi * w
    theta = 0.7
    value = integrate(kernel.function, kernel.pack(model.params), np.sin(theta), 0.0, np.cos(theta), mu, wmu, phi,
                      wphi)
    reference = bn.albedo(model, theta, rtol=1e-9).value
    np.testing.assert_allclose(value, reference, rtol=1e-6)


def test_the_module_is_cached_per_user_and_read_back(tmp_path, monkeypatch):
    """Written under BRDFNORM_CACHE_DIR in a 0700 directory, named by the key, with Numba's machine code beside
    it; read again (a new process in effect: the in-memory table cleared), it compiles nothing."""
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(cache, "_loaded", {})
    text = (ROOT / "examples" / "phong.brdf").read_text()
    kernel = native_kernel(parse_brdf(text, "first.brdf"))
    directory = tmp_path / "cache" / "glsl"
    for d in (tmp_path / "cache", directory):
        assert stat.S_IMODE(os.stat(d).st_mode) == 0o700
    module = directory / f"brdf_{kernel.key}.py"
    assert module.is_file() and any((directory / "__pycache__").glob("*.nbi"))
    monkeypatch.setattr(cache, "_loaded", {})
    sys.modules.pop(f"brdfnorm_glsl_native_{kernel.key}", None)
    again = native_kernel(parse_brdf(text, "second.brdf"))  # another path: a new trace, the same source
    assert again.key == kernel.key and again.function is not kernel.function
    assert again.function.stats.cache_hits and not again.function.stats.cache_misses


def test_a_tampered_cache_file_is_replaced_by_the_generated_source(tmp_path, monkeypatch):
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(cache, "_loaded", {})
    text = (ROOT / "examples" / "lambert.brdf").read_text()
    kernel = native_kernel(parse_brdf(text, "a.brdf"))
    module = tmp_path / "glsl" / f"brdf_{kernel.key}.py"
    source = module.read_text()
    module.write_text("raise SystemExit('not ours')\n")
    monkeypatch.setattr(cache, "_loaded", {})
    sys.modules.pop(f"brdfnorm_glsl_native_{kernel.key}", None)
    assert native_kernel(parse_brdf(text, "b.brdf")).key == kernel.key
    assert module.read_text() == source


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX permissions")
def test_a_directory_others_may_write_to_is_not_used(tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(shared))
    monkeypatch.setattr(cache, "_loaded", {})
    monkeypatch.setattr(cache, "_warned", set())
    text = (ROOT / "examples" / "lambert.brdf").read_text().replace("0.8", "0.7")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        kernel = native_kernel(parse_brdf(text, "c.brdf"))
    assert any("not cached" in str(w.message) for w in caught)
    assert list(shared.iterdir()) == []
    model = load_brdf(ROOT / "examples" / "lambert.brdf")
    assert kernel.function(0.0, 0.0, 1.0, 0.0, 0.0, 1.0, kernel.pack(model.params)) is not None


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="symbolic links")
def test_a_symbolic_link_as_cache_directory_is_not_used(tmp_path, monkeypatch):
    """A link could point anywhere (another user's directory): the cache directory must be a directory itself."""
    (tmp_path / "elsewhere").mkdir(mode=0o700)
    (tmp_path / "link").symlink_to(tmp_path / "elsewhere")
    monkeypatch.setenv("BRDFNORM_CACHE_DIR", str(tmp_path / "link"))
    monkeypatch.setattr(cache, "_warned", set())
    with pytest.warns(RuntimeWarning, match="not cached"):
        assert cache.module_directory() is None
    assert list((tmp_path / "elsewhere").iterdir()) == []


@pytest.mark.slow
def test_a_second_process_compiles_nothing(tmp_path):
    """Two fresh interpreters on one cache directory (the benchmark's own measurement): the first compiles the
    shader, the second finds it in Numba's cache; and the benchmark's per-evaluation figures compare equal
    values."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import bench_glsl_native as bench
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    cold, warm = bench.compile_times(str(tmp_path))
    assert cold["cache_misses"] >= 1 and cold["cache_hits"] == 0
    assert warm["cache_misses"] == 0 and warm["cache_hits"] >= 1
    evaluation = bench.per_evaluation(2000, 1)
    assert evaluation["same_nan"] and evaluation["max_rel_difference"] < 1e-13
    assert evaluation["native_ns"] > 0 and evaluation["numpy_ns"] > 0


@pytest.mark.parametrize("body", [
    # an array written at a computed index in a loop: 64 values carried from one iteration to the next
    "float a[64]; for (int i = 0; i < 64; i++) a[i] = float(i) * L.z; float s = 0.0;"
    " for (int i = 0; i < 64; i++) s += a[i] * a[63 - i]; return vec3(s);",
    # 4 096 products once the macros are expanded: more lines than Numba compiles in a few seconds
    "#define A0 (L.z * V.z)\n" + "".join(f"#define A{k} (A{k - 1} + A{k - 1})\n" for k in range(1, 13))
    + "return vec3(A12);",
])
def test_shaders_numba_would_compile_for_long_stay_with_numpy(tmp_path, body):
    model = load_brdf(brdf_file(tmp_path, f"vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {{\n{body}\n}}"))
    assert model.native_kernel() is None
    assert np.isfinite(model.eval([0.0, 0.6, 0.8], [0.0, 0.0, 1.0])).all()


def test_a_table_over_a_shader_parameter_runs_compiled_within_the_numpy_tables_estimates():
    """A table's per-case parameter values reach ``pack`` as shape (1,) arrays (a roughness axis of ``lut``):
    under the compiled backend they are packed, not refused, and the table equals the numpy backend's within the
    cells' estimates."""
    from brdfnorm import lut

    model = load_brdf(ROOT / "examples" / "ggx.brdf", f0=1.0)
    axes = {"mu": np.array([0.3, 0.9]), "roughness": np.array([0.4, 0.8])}
    tables = {b: lut.compute(model, axes, rtol=1e-8, backend=b) for b in ("numpy", "compiled")}
    kernel = model.native_kernel()
    one_case = {name: np.asarray(value)[None] if np.ndim(value) == 0 else value for name, value in model.params.items()}
    np.testing.assert_array_equal(kernel.pack(one_case), kernel.pack(model.params))
    a, b = tables["numpy"], tables["compiled"]
    assert not a.meta["unconverged"] and not b.meta["unconverged"]
    assert np.all(np.abs(a["E"] - b["E"]) <= a["E_error"] + b["E_error"])
