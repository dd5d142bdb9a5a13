"""brdfnorm.lut: tables against independent routes, every format's round trip, the command line's contract."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest
from scipy import integrate

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.errors import ArgumentError, TableFileError
from brdfnorm.lut import formats
from brdfnorm.lut.table import grid_values

MU = [0.05, 0.3, 0.7, 1.0]
N = [2.0, 30.0, 400.0]


@pytest.fixture(scope="module")
def table() -> lut.Lut:
    return lut.compute(bn.load("blinn-phong"), {"mu": MU, "n": N}, rtol=1e-10, channels=["dfg"], grid="node")


def test_cells_are_the_albedo_in_axis_order(table):
    assert list(table.axes) == ["mu", "n"] and table["E"].shape == (4, 3) and table["E_avg"].shape == (3,)
    for j, n in enumerate(N):
        direct = bn.albedo(bn.load("blinn-phong", n=n), np.arccos(MU), method="quadrature", rtol=1e-12)
        assert np.allclose(table["E"][:, j], direct.value[:, 0], rtol=5e-10, atol=0)
        assert np.all(np.abs(table["E"][:, j] - direct.value[:, 0]) <= table["E_error"][:, j] + direct.error[:, 0])
    assert np.array_equal(table["1-E"], 1.0 - table["E"])
    assert table.meta["unconverged"] == 0 and table.meta["tables"]["E_avg"] == ["n"]


@pytest.mark.slow
def test_e_avg_against_quadpack_over_an_independent_albedo_route(table):
    """E_avg = 2∫ E(μ) μ dμ by QUADPACK over the cubature route, while the table used the series route in μ
    nodes of its own G7/K15 panels: they agree within the estimates, and the estimate is not too small."""
    for j, n in enumerate(N):
        model = bn.load("blinn-phong", n=n)

        def integrand(mu, model=model):
            return 2 * mu * bn.albedo(model, np.arccos(mu), method="quadrature", rtol=1e-13).value.ravel()[0]

        reference, quad_error = integrate.quad(integrand, 0.0, 1.0, epsabs=0, epsrel=1e-12, limit=200)
        error = abs(table["E_avg"][j] - reference)
        assert error <= table["E_avg_error"][j] + 1e-12 * abs(reference), (n, error, table["E_avg_error"][j])
        assert error <= 2e-10 * reference


@pytest.mark.parametrize("case", ["lambert", "constant"])
def test_e_avg_closed_forms(case):
    """Lambert: E = E_avg = reflectance; Blinn-Phong n = 0 (f = 1): E = E_avg = π."""
    model, expected = (bn.load("lambert", reflectance=0.7), 0.7) if case == "lambert" else (
        bn.load("blinn-phong", n=0.0), np.pi)
    result = lut.compute(model, {"theta": [0.0, 1.2]}, rtol=1e-12)
    assert abs(result["E_avg"] - expected) <= max(float(result["E_avg_error"]), 4e-16 * expected)
    assert result["E_avg"].shape == ()


def test_dfg_pair_sums_to_e_and_matches_an_independent_split(table):
    total = table["DFG_f0"] + table["DFG_f90"]
    assert np.all(np.abs(total - table["E"]) <= table["DFG_f0_error"] + table["DFG_f90_error"] + table["E_error"]
                  + 1e-15)
    # DFG_f90 of Lambert by scipy dblquad over (θ_L, φ_L) with the Schlick weight computed from H itself.
    model = bn.load("lambert", reflectance=1.0)
    result = lut.compute(model, {"mu": [0.4]}, rtol=1e-11, channels=["dfg"], average=False)
    V = np.array([np.sqrt(1 - 0.4**2), 0.0, 0.4])

    def g(phi, theta):
        L = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
        H = (L + V) / np.linalg.norm(L + V)
        return (1 / np.pi) * (1 - V @ H) ** 5 * L[2] * np.sin(theta)

    reference, _ = integrate.dblquad(g, 0, np.pi / 2, 0, 2 * np.pi, epsabs=0, epsrel=1e-12)
    assert abs(result["DFG_f90"][0] - reference) <= result["DFG_f90_error"][0] + 1e-12 * reference
    assert "Fresnel" in result.meta["dfg"]


def test_grids():
    assert np.allclose(grid_values(0, 1, 4, "node"), [0, 1 / 3, 2 / 3, 1])
    assert np.allclose(grid_values(0, 1, 4, "texel"), [0.125, 0.375, 0.625, 0.875])
    with pytest.raises(ArgumentError):
        grid_values(0, 1, 4, "corner")


def test_refusals():
    model = bn.load("blinn-phong")
    with pytest.raises(ArgumentError, match="clamp"):
        lut.compute(model, {"mu": [0.0, 1.0]})
    with pytest.raises(ArgumentError, match="view direction"):
        lut.compute(model, {"n": [1.0, 2.0]})
    with pytest.raises(bn.BrdfnormError):
        lut.compute(model, {"mu": [1.0], "roughness": [0.1]})
    with pytest.raises(bn.BrdfnormError):
        lut.compute(model, {"mu": [1.0], "n": [-1.0]})


# -- formats ------------------------------------------------------------------------------------------------

EXACT = ("npz", "json", "csv")
FLOAT32 = ("exr", "h", "glsl", "hlsl")


@pytest.mark.parametrize("fmt", [*EXACT, *FLOAT32])
def test_round_trip(table, tmp_path, fmt):
    options = {"channel_names": "brdfnorm"} if fmt == "exr" else {}  # nine tables: more than R, G, B, A
    path = lut.save(table, tmp_path / f"t.{fmt}", tables=list(table), **options)
    back = lut.load(path)
    assert list(back) == list(table) and list(back.axes) == list(table.axes)
    assert back.table_axes == table.table_axes
    for name, values in table.axes.items():
        assert np.array_equal(back.axes[name], values)  # axes travel as float64 in every format
    for name in table:
        expected = table[name] if fmt in EXACT else table[name].astype(np.float32).astype(float)
        assert np.array_equal(back[name], expected), (fmt, name)  # float64 bit-exact; float32 to nearest
        assert back[name].dtype == (np.float64 if fmt in EXACT else np.float32)  # the precision the file holds
    assert back.meta["model"] == "blinn-phong" and back.meta["rtol"] == 1e-10


def test_exr_half(table, tmp_path):
    back = lut.load(lut.save(table, tmp_path / "t.exr", half=True))
    assert np.array_equal(back["E"], table["E"].astype(np.float16).astype(float))
    assert back["E"].dtype == np.float16


def test_png_quantization(table, tmp_path):
    back = lut.load(lut.save(table, tmp_path / "t.png"))
    assert list(back) == ["E", "DFG_f0", "DFG_f90"]  # the grid's values as R, G, B (E_avg is its own image)
    for name in back:
        span = table[name].max() - table[name].min()
        error = np.max(np.abs(back[name] - table[name]))
        assert 0 < error <= span / 131070 * (1 + 1e-9), name
    one_axis = lut.load(lut.save(table, tmp_path / "avg.png", tables=["E_avg"]))
    assert one_axis["E_avg"].shape == (3,)
    three = lut.compute(bn.load("lambert"), {"mu": [0.5, 1.0], "reflectance": [0.2, 0.4]}, rtol=1e-8)
    assert three["E"].shape == (2, 2)
    with pytest.raises(ArgumentError, match="at most 4"):
        formats.dumps(table, "png", tables=["E", "1-E", "E_error", "DFG_f0", "DFG_f90"])
    with pytest.raises(ArgumentError, match="own"):  # E_avg has other axes than E: its own file
        formats.dumps(table, "png", tables=["E", "E_avg"])
    broadcast = lut.load(lut.save(table, tmp_path / "b.png", tables=["E", "E_avg"], broadcast_average=True))
    assert broadcast["E_avg"].shape == (3,)
    assert np.max(np.abs(broadcast["E_avg"] - table["E_avg"])) <= np.ptp(table["E_avg"]) / 131070 * (1 + 1e-9)


def test_png_holds_three_axes_as_an_atlas(tmp_path):  # more in tests/test_anisotropy_png.py
    cube = lut.Lut({"E": np.arange(8.0).reshape(2, 2, 2)}, {"mu": [0.5, 1], "n": [1, 2], "x": [0, 1]}, {})
    path = lut.save(cube, tmp_path / "cube.png")
    assert np.max(np.abs(lut.load(path)["E"] - cube["E"])) <= 7 / 131070 * (1 + 1e-9) and b"atlas" in path.read_bytes()


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) on this machine")
def test_c_header_compiles_with_hostile_names(table, tmp_path):
    hostile = lut.Lut(dict(table), table.axes, {**table.meta, "model": "evil*/ \\\n??/ #include <x> \u00e9"},
                      table.table_axes)
    (tmp_path / "t.h").write_text(formats.dumps(hostile, "h", tables=list(table)))
    (tmp_path / "main.c").write_text('#include "t.h"\n#include "t.h"\nint main(void) {\n'
                                     "  return (int)(lut_E[2][3] + lut_one_minus_E[0][0] + lut_E_avg[1]"
                                     " + lut_DFG_f0[0][0]) * 0;\n}\n")
    done = subprocess.run(["cc", "-std=c99", "-Wall", "-Werror", "-trigraphs", "-o", str(tmp_path / "a.out"),
                           str(tmp_path / "main.c")], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert lut.load(tmp_path / "t.h").meta["model"] == hostile.meta["model"]


@pytest.mark.skipif(shutil.which("glslangValidator") is None, reason="glslangValidator not installed")
def test_glsl_passes_glslang(table, tmp_path):
    code = formats.dumps(table, "glsl", tables=list(table))
    shader = ("#version 330\n" + code + "out vec4 colour;\nvoid main() {\n"
              "  colour = vec4(lut_E[lut_E_size1 * 2 + 3], lut_E_avg[1], lut_one_minus_E[0], 1.0);\n}\n")
    (tmp_path / "t.frag").write_text(shader)
    done = subprocess.run(["glslangValidator", str(tmp_path / "t.frag")], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def test_hlsl_layout(table):
    code = formats.dumps(table, "hlsl")
    # x = mu (4 values) runs fastest, y = n (3 values) is size0: lut_E[n][mu], flattened row-major
    assert "static const float lut_E[12] = {" in code and "static const int lut_E_size0 = 3;" in code
    assert "static const int lut_E_size1 = 4;" in code and "E_error" not in code and "one_minus" not in code


@pytest.mark.parametrize("fmt", list(formats.FORMATS))
def test_damaged_files_are_one_error_naming_the_file(table, tmp_path, fmt):
    path = tmp_path / f"bad.{fmt}"
    data = formats.dumps(table, fmt, tables=["E"] if fmt == "png" else list(table),
                         channel_names="brdfnorm" if fmt == "exr" else "rgba")
    raw = data.encode() if isinstance(data, str) else data
    path.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(TableFileError, match="bad"):
        lut.load(path)
    path.write_bytes(b"")
    with pytest.raises(TableFileError):
        lut.load(path)


def test_csv_error_names_the_line(table, tmp_path):
    lines = formats.dumps(table, "csv").splitlines()
    lines[5] = lines[5].replace(",", ",x", 1)
    path = tmp_path / "t.csv"
    path.write_text("\n".join(lines))
    with pytest.raises(TableFileError) as caught:
        lut.load(path)
    assert caught.value.line == 6 and str(caught.value).startswith(f"{path}:6:")


# -- command line -------------------------------------------------------------------------------------------

def test_cli_writes_npz_and_texel_grid(tmp_path, run_cli):
    out = tmp_path / "E.npz"
    code, stdout, stderr = run_cli("lut", "blinn-phong", "--axis", "mu=0:1:4", "--axis", "n=1,10",
                                   "--clamp", "mu=1e-4", "--grid", "texel", "--rtol", "1e-9", "-o", str(out))
    assert code == 0 and stdout == "" and "8 cells" in stderr
    table = lut.load(out)
    assert np.allclose(table.axes["mu"], [0.125, 0.375, 0.625, 0.875]) and table.meta["grid"] == "texel"
    direct = bn.albedo(bn.load("blinn-phong", n=10.0), np.arccos(0.125), rtol=1e-12).value.ravel()[0]
    assert abs(table["E"][0, 1] - direct) <= 1e-9 * direct


def test_cli_theta_in_degrees_and_stdout(run_cli):
    code, stdout, stderr = run_cli("lut", "lambert", "--axis", "theta=0,60", "-o", "-", "--format", "json")
    assert code == 0 and "wrote" not in stderr
    document = json.loads(stdout)
    assert document["axes"]["theta"] == [0.0, 60.0]  # the units the command line took, and the metadata says so
    assert document["meta"]["units"]["theta"] == "degrees"
    assert np.allclose(document["tables"]["E"], 1.0)


def test_cli_clamp_at_zero(tmp_path, run_cli):
    out = tmp_path / "E.csv"
    code, _, stderr = run_cli("lut", "blinn-phong", "--axis", "mu=0:1:3", "--axis", "n=0:10:2",
                              "--clamp", "mu=1e-4", "--clamp", "n=1", "-o", str(out))
    assert code == 0, stderr
    table = lut.load(out)
    assert table.axes["n"][0] == 0.0 and table.meta["clamp"] == {"mu": 1e-4, "n": 1.0}
    direct = bn.albedo(bn.load("blinn-phong", n=1.0), np.arccos(1e-4), rtol=1e-12).value.ravel()[0]
    assert abs(table["E"][0, 0] - direct) <= 1e-9 * direct


@pytest.mark.parametrize("argv, where", [
    (["--axis", "mu=0:1:3", "-o", "x.npz"], "--axis"),  # μ = 0 without a clamp
    (["--axis", "mu=0.5,1", "--axis", "q=1,2", "-o", "x.npz"], "q"),
    (["--axis", "mu=0.5,1", "-o", "-"], "--format"),
    (["--axis", "mu=0.5,1", "-o", "-", "--format", "npz"], "--format"),
    (["--axis", "mu=0.5,1", "-o", "x.tiff"], "--output"),
    (["--axis", "mu=0.5,1", "-o", "x.npz", "--half"], "--half"),
    (["--axis", "mu=0.5,1", "--axis", "mu=1", "-o", "x.npz"], "--axis"),
    (["--axis", "mu=1:0:3", "-o", "x.npz"], "--axis mu"),
    (["--axis", "mu=0.5,1", "-o", "/nonexistent/x.npz"], "/nonexistent"),
    (["--axis", "mu=0.5,1", "--channels", "rgb", "-o", "x.npz"], "--channels"),
    (["--axis", "mu=0.5,1", "--grid", "corner", "-o", "x.npz"], "--grid"),
])
def test_cli_bad_input(tmp_path, monkeypatch, argv, where, run_cli):
    monkeypatch.chdir(tmp_path)
    code, stdout, stderr = run_cli("lut", "blinn-phong", *argv)
    assert code == 2 and stdout == ""
    assert stderr.startswith("error: ") and stderr.count("\n") == 1 and where in stderr, stderr
    assert list(tmp_path.iterdir()) == []


def test_cli_unconverged_cells_are_written_named_and_exit_3(tmp_path, monkeypatch, run_cli):
    """Computed work is never thrown away (issue 39): cells that miss --rtol are written with their estimates and a
    mask, named on stderr, exit 3; --strict refuses (exit 1, nothing written); --allow-unconverged exits 0."""
    from brdfnorm.lut import table as table_module

    real = table_module.albedo

    def stubborn(*args, **kwargs):
        result = real(*args, **kwargs)
        return type(result)(**{**result.__dict__, "converged": np.zeros_like(result.converged)})

    monkeypatch.setattr(table_module, "albedo", stubborn)
    out = tmp_path / "E.json"
    # (--workers 1: the E cells too are computed by lut.table, which the stub replaces, whatever the backend and cores)
    argv = ["lut", "lambert", "--axis", "mu=0.5,1", "--workers", "1", "-o", str(out)]
    code, _, stderr = run_cli(*argv, "--strict")
    assert code == 1 and "did not reach" in stderr and not out.exists()
    code, _, stderr = run_cli(*argv)
    table = lut.load(out)
    assert code == 3 and table.meta["unconverged"] == 3
    assert table.meta["converged_mask"] == {"E": [False, False], "E_avg": False}
    assert "did not reach --rtol 1e-10, written with their error estimates" in stderr
    assert stderr.rstrip().endswith(": mu=0.5; mu=1; E_avg") and np.isclose(table["E_avg"], 1.0)
    code, _, stderr = run_cli(*argv, "--allow-unconverged")
    assert code == 0 and lut.load(out).meta["unconverged"] > 0


# -- fits of a table ----------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def ggx_table(tmp_path_factory):
    """E(μ, α) of GGX (height-correlated, F = 1) on a 7×6 grid from the tests' own half-vector reference."""
    from helpers.ggx_reference import ggx_albedo

    mu, alpha = np.linspace(0.05, 1.0, 7), np.linspace(0.2, 1.0, 6)
    E = np.array([[ggx_albedo(m, a, nodes=24) for a in alpha] for m in mu])
    path = tmp_path_factory.mktemp("fit") / "E.npz"
    lut.save(lut.Lut({"E": E}, {"mu": mu, "alpha": alpha}, {"model": "ggx"}), path)
    return path, mu, alpha, E


def test_fit_table_front_and_chosen_form(ggx_table):
    from brdfnorm.lut.fitting import fit_table

    path, mu, alpha, E = ggx_table
    result = fit_table(lut.load(path), target=1e-12, max_coefficients=7, metric="abs-lsq")
    counts = [entry["coefficients"] for entry in result.front]
    errors = [entry["max_abs_error"] for entry in result.front]
    assert counts == sorted(counts) and errors == sorted(errors, reverse=True) and len(counts) >= 2
    assert result.variables == ("mu", "alpha") and result.best.warnings  # the target is out of reach
    # the reported error is the fit's error on the table, evaluated here independently of the fit module
    M, A = np.meshgrid(mu, alpha, indexing="ij")
    assert np.isclose(np.max(np.abs(result.best(M.ravel(), A.ravel()) - E.ravel())), result.best.max_abs_error,
                      rtol=1e-9)
    loose = fit_table(lut.load(path), target=errors[0] * 1.0001, max_coefficients=7, metric="abs-lsq")
    assert len(loose.best.coefficients) == counts[0]  # the fewest coefficients that meet the target


def test_cli_fit_lut_emits_glsl_and_front_on_stderr(ggx_table, tmp_path, run_cli):
    path, *_ = ggx_table
    code, stdout, stderr = run_cli("fit", "--lut", str(path), "--form", "rational-sqrt:2/0@1",
                                   "--metric", "abs-lsq", "--emit", "glsl")
    assert code == 0, stderr
    assert "Pareto front" in stderr and "float brdfnorm_ggx_e(float mu, float alpha)" in stdout
    assert "Table E of ggx" in stdout and "Pareto" not in stdout
    if shutil.which("glslangValidator"):
        shader = "#version 330\n" + stdout + "out vec4 c;\nvoid main() { c = vec4(brdfnorm_ggx_e(0.5, 0.3)); }\n"
        (tmp_path / "f.frag").write_text(shader)
        done = subprocess.run(["glslangValidator", str(tmp_path / "f.frag")], capture_output=True, text=True)
        assert done.returncode == 0, done.stdout


def test_cli_fit_lut_refusals(ggx_table, tmp_path, run_cli):
    path, *_ = ggx_table
    code, _, stderr = run_cli("fit", "blinn-phong", "--lut", str(path))
    assert code == 2 and "--lut" in stderr
    one_axis = tmp_path / "one.npz"
    lut.save(lut.Lut({"E": np.ones(3)}, {"mu": [0.1, 0.5, 1.0]}, {}), one_axis)
    code, _, stderr = run_cli("fit", "--lut", str(one_axis))
    assert code == 2 and "two" in stderr and stderr.count("\n") == 1
    code, _, stderr = run_cli("fit", "--lut", str(tmp_path / "missing.npz"))
    assert code == 2 and "missing.npz" in stderr


def test_missed_cells_are_named_by_their_axis_values():
    from brdfnorm.cli.lut import missed_cells
    from brdfnorm.lut.table import Lut

    E = np.zeros((2, 3))
    mask = {"E": [[True, False, True], [True, True, False]], "E_avg": [True, True, False]}
    table = Lut({"E": E, "E_avg": np.zeros(3)}, {"mu": np.array([0.5, 1.0]), "alpha": np.array([0.1, 0.2, 0.3])},
                {"converged_mask": mask}, {"E": ("mu", "alpha"), "E_avg": ("alpha",)})
    assert missed_cells(table) == "mu=0.5, alpha=0.2; mu=1, alpha=0.3; E_avg at alpha=0.3"
    assert missed_cells(table, shown=1) == "mu=0.5, alpha=0.2 and 2 more"
