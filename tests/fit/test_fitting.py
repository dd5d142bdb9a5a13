"""brdfnorm.fit and ``brdfnorm fit``: exact recovery, minimax against an LP, auto, seed 003, 2-D Blinn-Phong."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest
from scipy import integrate
from scipy.optimize import linprog

import brdfnorm
from brdfnorm.errors import ArgumentError
from brdfnorm.fit import METRICS, fit, parse_form
from brdfnorm.models.closed_forms import blinn_phong_albedo_normal
from brdfnorm.normalization import normalize

# -- exact recovery ------------------------------------------------------------------------------------------

X = np.linspace(0.5, 10.0, 60)

EXACT = [
    ("linear", [2.0, 3.0], lambda x: 2.0 + 3.0 * x),
    ("poly:3", [1.0, -0.5, 0.25, 0.01], lambda x: 1.0 - 0.5 * x + 0.25 * x**2 + 0.01 * x**3),
    ("rational:2/1", [1.0, 2.0, 0.5, 0.3], lambda x: (1 + 2 * x + 0.5 * x**2) / (1 + 0.3 * x)),
    ("rational-sqrt:2/1", [0.7, 0.2, 0.05, 0.4],
     lambda x: (0.7 + 0.2 * np.sqrt(x) + 0.05 * x) / (1 + 0.4 * np.sqrt(x))),
    ("hyperbola", [0.2, 0.5, 3.0, 1.5], lambda x: 0.2 + 0.5 * np.sqrt((x - 3.0) ** 2 + 1.5**2)),
]


@pytest.mark.parametrize("metric", METRICS)
@pytest.mark.parametrize(("form", "coefficients", "function"), EXACT, ids=[e[0] for e in EXACT])
def test_each_form_recovers_known_coefficients(form, coefficients, function, metric):
    result = fit(X, function(X), form=form, metric=metric)
    assert result.form == form
    np.testing.assert_allclose(result.coefficients, coefficients, rtol=1e-6, atol=1e-9)
    assert result.max_rel_error < 1e-8
    # The callable and the expression use the coefficients in the same order.
    np.testing.assert_allclose(result(X), function(X), rtol=1e-8)


def test_two_variable_forms_recover_known_coefficients():
    x, t = np.meshgrid(np.linspace(1, 100, 15), np.linspace(0.05, 1.0, 9))
    # (p00 + p01 t + (p10 + p11 t)·√x) / (1 + q01 t + (q10 + q11 t)·√x)
    p = [0.5, 0.1, 0.2, 0.3]
    q = [0.4, 0.05, 0.02]
    u = np.sqrt(x)
    y = (p[0] + p[1] * t + (p[2] + p[3] * t) * u) / (1 + q[0] * t + (q[1] + q[2] * t) * u)
    result = fit(x, y, t, form="rational-sqrt:1/1@1", metric="rel-lsq")
    np.testing.assert_allclose(result.coefficients, p + q, rtol=1e-6)
    assert result.variables == ["x", "t"] and result.range["t"] == [0.05, 1.0]
    # τ variant: the second variable is t·√x.
    tau = t * u
    y = (1.0 + 0.5 * tau + 0.2 * u) / (1.0 + 0.1 * tau)
    result = fit(x, y, t, form="rational-sqrt:1/0@1~tau", metric="rel-lsq")
    np.testing.assert_allclose(result.coefficients, [1.0, 0.5, 0.2, 0.0, 0.1], atol=1e-8)


# -- minimax ----------------------------------------------------------------------------------------------------


def _lp_minimax(basis: np.ndarray, y: np.ndarray) -> float:
    """Discrete minimax relative error of a linear family as a linear programme (an independent solver)."""
    A = basis / y[:, None]
    k = A.shape[1]
    ones = np.ones((len(y), 1))
    A_ub = np.vstack([np.hstack([A, -ones]), np.hstack([-A, -ones])])
    b_ub = np.concatenate([np.ones(len(y)), -np.ones(len(y))])
    cost = np.zeros(k + 1)
    cost[-1] = 1.0
    solution = linprog(cost, A_ub=A_ub, b_ub=b_ub, bounds=[(None, None)] * (k + 1), method="highs")
    assert solution.success
    return solution.x[-1]


def _alternations(error: np.ndarray, tolerance: float) -> int:
    """Sign alternations among the samples where |error| is within ``tolerance`` of its maximum."""
    peak = np.abs(error).max()
    signs = np.sign(error[np.abs(error) >= peak * (1 - tolerance)])
    return 1 + int(np.sum(signs[1:] != signs[:-1]))


@pytest.mark.parametrize("degree", [1, 3, 5])
def test_minimax_polynomial_equioscillates_and_matches_linear_programming(degree):
    n = np.linspace(1.0, 512.0, 400)
    alpha = 1.0 / blinn_phong_albedo_normal(n)
    result = fit(n, alpha, form=f"poly:{degree}", metric="minimax-rel")
    error = result(n) / alpha - 1.0
    k = degree + 1
    # Chebyshev: the best approximation from a k-dimensional Haar space alternates at ≥ k + 1 points.
    assert _alternations(error, 1e-6) >= k + 1
    scaled = n / n.max()
    lp = _lp_minimax(np.stack([scaled**i for i in range(k)], axis=1), alpha)
    assert result.max_rel_error == pytest.approx(lp, rel=1e-6)
    # And it beats least squares on the maximum, as it must.
    assert result.max_rel_error < fit(n, alpha, form=f"poly:{degree}", metric="rel-lsq").max_rel_error


def test_minimax_rational_equioscillates():
    n = np.linspace(1.0, 512.0, 400)
    alpha = 1.0 / blinn_phong_albedo_normal(n)
    result = fit(n, alpha, form="rational:2/1", metric="minimax-rel")
    error = result(n) / alpha - 1.0
    assert _alternations(error, 1e-5) >= 4 + 1  # P + Q + 2 for a non-degenerate rational of type (2, 1)
    assert result.max_rel_error < fit(n, alpha, form="rational:2/1", metric="rel-lsq").max_rel_error


def test_auto_picks_the_smallest_adequate_form():
    x = np.linspace(1.0, 20.0, 80)
    y = (1.0 + 0.4 * x + 0.01 * x**2) / (1.0 + 0.05 * x)  # exact for 4-coefficient rational:2/1
    result = fit(x, y, form="auto", target=1e-9)
    assert len(result.coefficients) == 4 and result.max_rel_error <= 1e-9
    smaller = [entry for entry in result.tried if entry["coefficients"] < 4]
    assert smaller and all(entry["max_rel_error"] > 1e-9 for entry in smaller)
    assert max(entry["coefficients"] for entry in result.tried) == 4


def test_bad_forms_and_inputs_are_one_line_argument_errors():
    for spec in ("poly:x", "poly", "rational:2", "rational-sqrt:a/b", "cubic", "linear:2", "hyperbola:1"):
        with pytest.raises(ArgumentError, match="form"):
            parse_form(spec)
    with pytest.raises(ArgumentError, match="@D"):
        parse_form("rational:2/1", two_d=True)
    with pytest.raises(ArgumentError, match="two-variable"):
        parse_form("rational:2/1@2")
    with pytest.raises(ArgumentError, match="one variable"):
        parse_form("hyperbola", two_d=True)
    with pytest.raises(ArgumentError, match="metric"):
        fit(X, X + 1, form="linear", metric="l1")
    with pytest.raises(ArgumentError, match="differ in size"):
        fit(X, X[:-1], form="linear")
    with pytest.raises(ArgumentError, match="only"):
        fit(X[:3], X[:3] + 1, form="poly:5")


# -- seed 003 -------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def seed003_alpha() -> tuple[np.ndarray, np.ndarray]:
    """α(n) = 1/E(V = N) of the Gaussian Blinn-Phong lobe at n = 1, 2, ..., 512 (seed 003's integer grid)."""
    n = np.arange(1.0, 513.0)
    result = normalize(brdfnorm.load("blinn-phong-gaussian"), at="normal", sweep={"n": n}, rtol=1e-10)
    return n, result.factor[:, 0, 0]


def test_seed003_samples_match_an_independent_integral(seed003_alpha):
    """At V = N, N·H = cos(θ/2): E = 2π ∫ exp(−((cos(θ/2) − 1)/(c − 1))²) cos θ sin θ dθ (seed 003)."""
    n, alpha = seed003_alpha
    for i in (0, 15, 511):
        c = 0.04 ** (1.0 / n[i])
        value, _ = integrate.quad(lambda t, c=c: np.exp(-(((np.cos(t / 2) - 1) / (c - 1)) ** 2)) * np.cos(t)
                                  * np.sin(t), 0.0, np.pi / 2, epsabs=0.0, epsrel=1e-13, limit=200)
        assert alpha[i] == pytest.approx(1.0 / (2 * np.pi * value), rel=1e-9)


def test_seed003_linear_fit_reproduces_the_published_coefficients(seed003_alpha):
    n, alpha = seed003_alpha
    result = fit(n, alpha, form="linear", metric="abs-lsq", names=("n", "t"))
    assert [f"{c:.8f}" for c in result.coefficients] == ["0.17287429", "0.01388682"]
    assert result.max_rel_error == pytest.approx(0.421, abs=0.001)
    assert result.argmax == {"n": 1.0}


@pytest.mark.slow
def test_auto_on_the_seed003_sweep_meets_the_target(seed003_alpha):
    n, alpha = seed003_alpha
    result = fit(n, alpha, form="auto", target=1e-3)
    assert result.max_rel_error <= 1e-3 and len(result.coefficients) <= 8
    # Independently re-evaluated on the samples, and every cheaper candidate tried missed the target.
    assert np.max(np.abs(result(n) / alpha - 1)) == pytest.approx(result.max_rel_error)
    assert all(e["max_rel_error"] > 1e-3 for e in result.tried if e["coefficients"] < len(result.coefficients))


# -- two variables: seed 002's view-dependent Blinn-Phong --------------------------------------------------

#: The shader-sized 2-D form that reaches the issue's goal: a rational of type (5, 2) in u = √n whose coefficients
#: are quartics in τ = cos θ_o·√n (44 coefficients, 43 FMAs + sqrt + mul + div).
VIEW_FORM = "rational-sqrt:5/2@4~tau"


@pytest.mark.slow
def test_blinn_phong_view_fit_meets_the_goal_on_a_different_denser_grid(tmp_path):
    from brdfnorm.fit.codegen import emit

    model = brdfnorm.load("blinn-phong")
    n = np.geomspace(1.0, 1e4, 49)
    theta = np.radians(np.linspace(0.0, 89.0, 46))
    samples = normalize(model, at="view", sweep={"n": n}, theta=theta, rtol=1e-10)
    x = np.broadcast_to(n[:, None], samples.factor.shape[:2])
    result = fit(x, samples.factor[..., 0], np.cos(samples.theta), form=VIEW_FORM, metric="minimax-rel",
                 names=("n", "cos_theta_o"))
    assert result.max_rel_error <= 1e-3 and not result.warnings
    assert result.operations == {"fma": 43, "mul": 1, "div": 1, "sqrt": 1}
    # The emitted Python, imported from a file, on n and θ between the fitted ones (and up to 89°).
    path = tmp_path / "view_norm.py"
    path.write_text(emit(result, "python", "blinn-phong"))
    spec = importlib.util.spec_from_file_location("view_norm", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    formula = module.brdfnorm_blinn_phong_norm
    n_dense = np.geomspace(1.0, 1e4, 97)[1::2]
    theta_dense = np.radians(np.append(np.linspace(0.0, 89.0, 91)[1::2], [88.5, 89.0]))
    reference = normalize(model, at="view", sweep={"n": n_dense}, theta=theta_dense, rtol=1e-10)
    error = formula(n_dense[:, None], np.cos(reference.theta)) / reference.factor[..., 0] - 1.0
    assert np.max(np.abs(error)) <= 1e-3
    # At θ = 0 against seed 000's closed form, on yet another grid.
    n_fine = np.geomspace(1.0, 1e4, 301)
    assert np.max(np.abs(formula(n_fine, 1.0) * blinn_phong_albedo_normal(n_fine) - 1.0)) <= 1e-3


# -- command line ---------------------------------------------------------------------------------------------


def test_cli_seed003_json(run_cli):
    code, out, err = run_cli("fit", "blinn-phong-gaussian", "--sweep", "n=1:512:512", "--form", "linear",
                         "--metric", "abs-lsq", "--at", "normal", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert [f"{c:.8f}" for c in data["coefficients"]] == ["0.17287429", "0.01388682"]
    assert data["max_rel_error"] == pytest.approx(0.421, abs=0.001) and data["argmax"] == {"n": 1.0}
    assert {"form", "expression", "max_abs_error", "metric", "samples", "tried"} <= data.keys()
    assert data["samples"] == 512 and data["form"] == "linear" and "0.0138868" in data["expression"]


def test_cli_emits_code_writes_it_and_plots(tmp_path, run_cli):
    code_path, plot_path = tmp_path / "norm.py", tmp_path / "fit.png"
    code, out, err = run_cli("fit", "blinn-phong", "--sweep", "n=1:100:40", "--form", "rational:2/1",
                         "--emit", "python", "-o", str(code_path), "--plot", str(plot_path), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert code_path.read_text() == data["code"] and "def brdfnorm_blinn_phong_norm(n):" in data["code"]
    assert plot_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # The fit reproduces the closed form α = 1/E at the samples to its stated error.
    n = np.linspace(1, 100, 40)
    coefficients = data["coefficients"]
    fitted = (coefficients[0] + coefficients[1] * n + coefficients[2] * n**2) / (1 + coefficients[3] * n)
    assert np.max(np.abs(fitted * blinn_phong_albedo_normal(n) - 1)) == pytest.approx(data["max_rel_error"])


@pytest.mark.parametrize(("argv", "where"), [
    (["--form", "poly:x"], "--form"),
    (["--form", "auto", "--emit", "rust"], "--emit"),
    (["--form", "linear", "--emit", "c", "-o", "/nonexistent-dir/x.c"], "/nonexistent-dir/x.c"),
    (["--form", "linear", "--sweep", "n=5:1:4"], "--sweep"),
    (["--form", "linear", "--sweep", "n=1:5:0"], "--sweep"),
    (["--form", "linear", "--at", "view"], "--theta"),
    (["--form", "linear", "--sweep", "q=1:5:5"], "blinn-phong"),
])
def test_cli_bad_input_is_one_line(argv, where, run_cli):
    args = ["fit", "blinn-phong", "--sweep", "n=1:5:5", *argv]
    code, out, err = run_cli(*args)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith(f"error: {where}")
