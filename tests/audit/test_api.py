"""brdfnorm audit (issue 29), quick tier: 8×8 tables made by brdfnorm lut in known conventions, transformed, and
audited; every reader and --fix writer round-trips; bad input is one line and exit 2; formulas are parsed safely.

The independent route throughout: tables are made with ``lut.compute`` (the engine's cells at the requested grid),
the audit rebuilds its reference from its own convention space and must name the transformation."""

from __future__ import annotations

import json

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.audit import audit
from brdfnorm.audit.formula import ARGUMENTS, compile_expression
from brdfnorm.errors import ArgumentError

N = 8
T_NODE = np.linspace(0.0, 1.0, N)
T_TEXEL = (np.arange(N) + 0.5) / N


def _table(model="ggx", mu=T_TEXEL, alpha=T_NODE, **params):
    m = bn.load(model).with_params(**params) if params else bn.load(model)
    return lut.compute(m, {"mu": mu, "alpha": np.maximum(alpha, 1e-8)}, clamp={"mu": 1e-4}, rtol=1e-10,
                       average=False)["E"]


BASE = None


def _base():
    global BASE
    if BASE is None:
        BASE = _table()
    return BASE


def _quick(table, **kw):
    return audit(table, "ggx", dense=False, sweep=False, **kw)


def test_plain_table_names_its_convention():
    r = _quick(_base())
    c = r.best.convention
    assert r.fits and (c.direction_axis, c.direction, c.roughness, c.shadowing) == (0, "mu-texel", "alpha-node",
                                                                                   "height-correlated")
    assert c.meanings == ("E",) and r.best.channels[0].max < 1e-12
    assert not r.runners_up[0].fits and r.runners_up[0].score > 1e-3


@pytest.mark.parametrize("name, transform, check", [
    ("transpose", lambda e: e.T, lambda c: c.direction_axis == 1),
    ("flip mu", lambda e: e[::-1], lambda c: c.flips == (True, False)),
    ("flip alpha", lambda e: e[:, ::-1], lambda c: c.flips == (False, True)),
    ("1-E", lambda e: 1.0 - e, lambda c: c.meanings == ("1-E",)),
])
def test_transformations_are_named(name, transform, check):
    r = _quick(transform(_base()))
    assert r.fits and check(r.best.convention), (name, r.best.convention.text())
    assert r.best.channels[0].max < 1e-12


def test_node_grid_and_r_squared():
    e = _table(mu=T_NODE, alpha=T_NODE**2)
    r = _quick(e)
    c = r.best.convention
    assert r.fits and (c.direction, c.roughness, c.mu_floor) == ("mu-node", "r2-node", 1e-4)
    assert r.best.channels[0].max < 1e-12


def test_separable_shadowing_is_named():
    r = _quick(_table(shadowing="separable"))
    assert r.fits and r.best.convention.shadowing == "separable"


@pytest.mark.parametrize("dtype, scale, level", [("uint8", 255, 0.5 / 255), ("uint16", 65535, 0.5 / 65535),
                                                 ("float16", None, 2.0**-12)])
def test_quantized_tables_fit_at_their_storage_step(dtype, scale, level):
    e = _base()
    stored = np.rint(e * scale) / scale if scale else e.astype(np.float16).astype(float)
    r = _quick(stored, read={"dtype": dtype})
    # at 8 bits a neighbouring convention (mu-node) is within a code of most cells; the true one of every cell
    assert r.passes and r.best.convention.direction == "mu-texel" and not r.runners_up[0].clean
    assert r.best.channels[0].max <= level * 1.0001
    assert r.best.channels[0].tolerance < 20 * level  # the storage step sets the tolerance


def test_monte_carlo_noise_fits_at_the_noise_level():
    e = _table(mu=T_TEXEL, alpha=T_TEXEL)
    noisy = e + np.random.default_rng(3).normal(0.0, 1e-3, e.shape)
    r = _quick(noisy)
    c = r.best.convention
    assert r.fits and (c.direction, c.roughness) == ("mu-texel", "alpha-texel")
    assert 5e-4 < r.best.channels[0].rms < 2e-3 and r.best.channels[0].max < 5e-3


def test_another_model_fits_no_hypothesis(tmp_path, run_cli):
    e = _table(model="beckmann")
    r = _quick(e)
    assert not r.fits and r.best.channels[0].max > 1e-3
    path = tmp_path / "beckmann.npz"
    np.savez(path, E=e)
    code, out, err = run_cli("audit", str(path), "--model", "ggx", "--no-interpolation", "--no-sweep")
    assert code == 1 and "NO HYPOTHESIS FITS" in out


def test_pins_restrict_the_space():
    r = _quick(_base(), direction="mu-node")
    assert not r.fits and r.best.convention.direction == "mu-node"
    with pytest.raises(ArgumentError):
        _quick(_base(), direction="sideways")


# -- readers and --fix round trips --------------------------------------------------------------------------

def _write_js(path, e):
    codes = e.astype(np.float16).view(np.uint16).ravel()
    path.write_text("const LUT = new Uint16Array([" + ", ".join(f"0x{c:04x}" for c in codes) + "]);\n")


def _write_h(path, e):
    rows = ",\n".join("  {" + ", ".join(str(int(c)) for c in r) + "}" for r in np.rint(e * 65535))
    path.write_text(f"/* E */\nstatic const unsigned short kE[{N}][{N}] = {{\n{rows}\n}};\n")


def _write_glsl(path, e):
    values = ", ".join(f"{v:.9g}" for v in e.astype(np.float32).ravel())
    path.write_text(f"const float E_LUT[{N * N}] = float[{N * N}]({values});\n")


def _write_csv(path, e):
    path.write_text("\n".join(",".join(repr(float(v)) for v in row) for row in e) + "\n")


def _write_json(path, e):
    path.write_text(json.dumps({"name": "E", "data": e.tolist()}))


def _write_png(path, e):
    from brdfnorm.inputs.png import encode

    path.write_bytes(encode(np.rint(e * 255).astype(int)[..., None], 8))


def _write_raw(path, e):
    path.write_bytes(e.astype("<f4").tobytes())


CASES = [
    ("lut.js", _write_js, ["--dtype", "float16", "--shape", f"{N},{N}"], 2.0**-12),
    ("lut.h", _write_h, [], 0.5 / 65535),
    ("lut.glsl", _write_glsl, ["--shape", f"{N},{N}"], 2.0**-24),
    ("lut.csv", _write_csv, [], 1e-15),
    ("lut.json", _write_json, [], 1e-15),
    ("lut.png", _write_png, [], 0.5 / 255),
    ("lut.bin", _write_raw, ["--shape", f"{N},{N}", "--dtype", "float32"], 2.0**-24),
]


@pytest.mark.parametrize("name, writer, options, level", CASES, ids=[c[0] for c in CASES])
def test_reader_and_fix_round_trip(tmp_path, name, writer, options, level, run_cli):
    e = _base()[:, ::-1]  # the roughness axis reversed: the fix must keep the orientation
    path = tmp_path / name
    writer(path, e)
    fixed = tmp_path / ("fixed_" + name)
    code, out, err = run_cli("audit", str(path), *options, "--no-interpolation", "--no-sweep", "--json",
                             "--fix", "-o", str(fixed))
    assert code == 0, err
    result = json.loads(out)
    assert result["best"]["convention"]["flipped"] == [False, True]
    assert result["best"]["channels"][0]["max"] <= level * 1.0001 + 1e-15
    code, out, err = run_cli("audit", str(fixed), *options, "--no-interpolation", "--no-sweep", "--json")
    assert code == 0, err
    again = json.loads(out)
    assert again["best"]["text"] == result["best"]["text"]
    assert again["best"]["channels"][0]["max"] <= level * 1.0001 + 1e-15  # the fix is exact to its storage


def test_npz_and_exr_fix_round_trip(tmp_path, run_cli):
    e = _base()
    np.savez(tmp_path / "t.npz", E=e.astype(np.float32), other=np.arange(3.0))
    code, out, err = run_cli("audit", str(tmp_path / "t.npz"), "--array", "E", "--no-interpolation",
                             "--no-sweep", "--fix", "-o", str(tmp_path / "f.npz"))
    assert code == 0, err
    fixed = np.load(tmp_path / "f.npz")
    assert fixed["E"].dtype == np.float32 and np.max(np.abs(fixed["E"] - e)) <= 2.0**-24
    assert "brdfnorm_audit" in fixed and np.array_equal(fixed["other"], np.arange(3.0))
    pytest.importorskip("OpenEXR")
    import OpenEXR

    with OpenEXR.File({"type": OpenEXR.scanlineimage}, {"Y": (e + 0.01).astype(np.float16)}) as image:
        image.write(str(tmp_path / "t.exr"))
    code, out, err = run_cli("audit", str(tmp_path / "t.exr"), "--no-interpolation", "--no-sweep",
                             "--fix", "-o", str(tmp_path / "f.exr"))
    assert code == 1 and "nothing written" in err  # shifted by 0.01: nothing fits, so --fix refuses
    assert not (tmp_path / "f.exr").exists()


# -- bad input -----------------------------------------------------------------------------------------------

BAD = [
    ("trunc.h", "static const float t[4][4] = {{0.1, 0.2, 0.3, 0.4}, {0.5}};\n", [], "truncated"),
    ("huge.h", "static const float t[10000][10000] = {0.5, 0.5};\n", [], "more than"),
    ("shape.js", "const t = [0.1, 0.2, 0.3];\n", ["--shape", "2,2"], "needs 4"),
    ("cells.csv", "0.1,0.2\n0.3,abc\n", [], "not a number"),
    ("nan.csv", "nan,nan\nnan,nan\n", [], "no finite"),
    ("flat.js", "const t = [0.1, 0.2, 0.3, 0.4];\n", [], "--shape"),
    ("trunc.png", None, [], "truncated"),
    ("raw.bin", b"\x00" * 10, ["--shape", "2,2"], "bytes"),
]


@pytest.mark.parametrize("name, content, options, message", BAD, ids=[b[0] for b in BAD])
def test_bad_input_is_one_line_exit_2(tmp_path, name, content, options, message, run_cli):
    path = tmp_path / name
    if content is None:
        from brdfnorm.inputs.png import encode

        content = encode(np.full((8, 8, 1), 7), 8)[:60]
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    code, out, err = run_cli("audit", str(path), *options)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err
    assert message in err and (name in err or "--shape" in err)


def test_declared_shape_of_1e8_elements(tmp_path, run_cli):
    code, out, err = run_cli("audit", str(tmp_path / "x.bin"), "--shape", "10000,10000", "--dtype",
                             "float32")
    assert code == 2 and "more than" in err


def test_nan_cells_are_listed_and_do_not_fit():
    e = _base().copy()
    e[2, 3] = np.nan
    e[4, 4] = 1.5
    r = _quick(e)
    assert r.fits and not r.passes  # the convention is still named from the other cells
    assert {tuple(c["index"]) for c in r.wrong_cells["0"]["cells"]} == {(2, 3), (4, 4)}
    assert r.bad_cells["non_finite"]["cells"] == [[2, 3, 0]] and r.bad_cells["above_one"]["cells"] == [[4, 4, 0]]


# -- formulas ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("text", ["__import__('os').system('true')", "r.real", "(1).__class__", "2**1000",
                                  "pow(r, 1e9)", "open('x')", "[r for r in (1,)]", "'a'", "x + 1", "r if r else 1"])
def test_formula_refuses_anything_but_arithmetic(text, run_cli):
    with pytest.raises(ArgumentError):
        compile_expression(text, ARGUMENTS)
    code, out, err = run_cli("audit", "--formula", text)
    assert code == 2 and err.count("\n") == 1 and err.startswith("error: --formula")


def test_formula_error_is_measured_against_an_independent_e_avg(run_cli):
    code, out, err = run_cli("audit", "--formula", "1 + 0*r", "--quantity", "E_avg", "--json")
    assert code == 0, err
    (row,) = json.loads(out)["results"]
    alpha = np.linspace(0, 1, 65) ** 2
    exact = lut.compute(bn.load("ggx"), {"mu": [1.0], "alpha": np.maximum(alpha, 1e-8)}, rtol=1e-10)["E_avg"]
    assert row["max"] == pytest.approx(float(np.max(1.0 - exact)), abs=1e-7)


def test_formula_report_is_a_new_directory(tmp_path, run_cli):
    code, out, err = run_cli("audit", "--formula", "1 + 0*r", "--quantity", "E_avg", "--report",
                             str(tmp_path / "fig"))
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "fig").iterdir()) == [".brdfnorm-report", "formula_error_E_avg.png"]


def test_axis_values_given_outright(tmp_path, run_cli):
    alpha = np.linspace(0.05, 1.0, N)
    e = _table(mu=T_TEXEL, alpha=alpha)
    assert not _quick(e).fits  # α from 0.05 is no declared grid: never a silent guess
    r = _quick(e, axes={"alpha": alpha})
    assert r.fits and r.best.convention.roughness == "explicit" and r.best.channels[0].max < 1e-12
    np.savez(tmp_path / "t.npz", E=e)
    code, out, err = run_cli("audit", str(tmp_path / "t.npz"), "--axis", f"alpha=0.05:1:{N}", "--json",
                             "--no-interpolation")
    assert code == 0, err
    rows = json.loads(out)["resolution"]["0"]
    assert [row["size"] for row in rows] == [8, 16, 32, 64, 128] and rows[-1]["max"] < rows[0]["max"]


def test_e_avg_fit_example_glsl_and_expression_agree_with_lut(run_cli):
    code, out, err = run_cli("audit", "--formula", "examples/audit/e_avg_fit.glsl", "--function",
                             "EavgApprox", "--args", "roughness=r", "--quantity", "E_avg", "--json")
    assert code == 0, err
    (glsl,) = json.loads(out)["results"]
    with open("examples/audit/e_avg_fit.txt") as handle:
        expression = handle.read().strip()
    code, out, err = run_cli("audit", "--formula", expression, "--json")
    (python,) = json.loads(out)["results"]
    r = np.linspace(0, 1, glsl["points"])
    exact = lut.compute(bn.load("ggx"), {"mu": [1.0], "alpha": np.maximum(r * r, 1e-8)}, rtol=1e-10)["E_avg"]
    fitted = compile_expression(expression, ARGUMENTS)({"r": r})
    assert python["max"] == pytest.approx(glsl["max"], rel=1e-12)
    assert glsl["max"] == pytest.approx(float(np.max(np.abs(fitted - exact))), abs=1e-8)
    assert 1e-4 < glsl["max"] < 2e-4


def test_npz_declaring_a_huge_array_is_refused_before_loading(tmp_path, run_cli):
    import io
    import zipfile

    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (100000, 100000)})
    with zipfile.ZipFile(tmp_path / "big.npz", "w") as archive:
        archive.writestr("E.npy", header.getvalue() + b"\0" * 64)
    code, out, err = run_cli("audit", str(tmp_path / "big.npz"))
    assert code == 2 and "big.npz" in err and "more than" in err and err.count("\n") == 1


def test_deeply_nested_json_is_one_error(tmp_path, run_cli):
    (tmp_path / "deep.json").write_text("[" * 100000 + "]" * 100000)
    code, out, err = run_cli("audit", str(tmp_path / "deep.json"))
    assert code == 2 and "deep.json" in err and err.count("\n") == 1


def test_random_and_zero_channels_never_fit_and_the_fix_refuses(capsys, tmp_path):
    e = _base()
    rng = np.random.default_rng(2)
    data = np.stack([e, np.zeros_like(e), rng.random(e.shape)], axis=-1)
    r = _quick(data)
    fits = {c.channel: c.fits for c in r.best.channels}
    assert fits == {"0": True, "1": False, "2": False}
    assert [c.too_noisy for c in r.best.channels] == [False, False, True]
    assert r.unnamed == ["1", "2"] and r.fixed is None and not r.passes  # never a half-fixed table
    kept = _quick(data, channels="E,-,-")  # '-' keeps a channel as read: the rest is fixed
    assert kept.passes and np.array_equal(kept.fixed, data)


@pytest.mark.parametrize("ext, options", [("npz", ["--array", "E"]), ("json", ["--array", "tables.E"]),
                                          ("h", ["--array", "lut_E"]), ("exr", ["--array", "R"]),
                                          ("csv", ["--array", "E", "--shape", f"{N},{N}"]), ("png", [])])
def test_brdfnorm_lut_files_are_audited(tmp_path, ext, options, run_cli):
    path = tmp_path / f"own.{ext}"
    code, out, err = run_cli("lut", "ggx", "--axis", f"mu=0:1:{N}", "--axis", f"alpha=0:1:{N}", "--grid",
                             "texel", "--no-average", "-o", str(path), *(["--table", "E"] if ext == "png" else []))
    assert code == 0, err
    code, out, err = run_cli("audit", str(path), *options, "--no-sweep", "--no-interpolation", "--json")
    assert code == 0, err
    best = json.loads(out)["best"]
    assert (best["convention"]["direction"], best["convention"]["roughness"]) == ("mu-texel", "alpha-texel")
    assert best["channels"][0]["max"] <= 1e-5  # PNG: 16-bit codes over [lo, hi]; float32 formats: 6e-8


def test_interpolation_error_against_scipy_and_the_quadrature_route():
    """The GPU interpolation error: our multilinear interpolant equals scipy's RegularGridInterpolator (clamped
    to the samples, as clamp-to-edge does), and the exact value at the worst point agrees with the generic
    quadrature method (not the route the reference uses)."""
    from scipy.interpolate import RegularGridInterpolator

    from brdfnorm.audit import quality
    from brdfnorm.audit.conventions import Convention
    from brdfnorm.audit.reference import Reference

    e = _base()[:, ::-1]
    c = Convention(direction="mu-texel", roughness="alpha-node", flips=(False, True), meanings=("E",))
    points = quality.dense_points(c, e.shape, 4096)
    t = points[0]
    ours = quality.interpolate(e, c, t)
    grid = (T_TEXEL, T_NODE)
    scipy_values = RegularGridInterpolator(grid, e[:, ::-1])(np.stack([np.clip(t[0], T_TEXEL[0], T_TEXEL[-1]),
                                                                     np.clip(t[1], 0, 1)], axis=-1))
    assert np.max(np.abs(ours - scipy_values)) < 1e-14
    error = quality.dense_error(e, c, "E", Reference(bn.load("ggx")), points)
    assert error.points == 4096 and error.of_grid == 64 * 64
    worst = error.worst
    ggx = bn.load("ggx").with_params(alpha=max(worst["alpha"], 1e-8))
    exact = bn.albedo(ggx, np.arccos(worst["mu"]), rtol=1e-9, method="quadrature").value[0]
    k = int(np.argmin(np.abs(points[0][0] - worst["mu"]) + np.abs(points[0][1] - worst["alpha"])))
    assert abs(abs(ours[k] - exact) - error.max) < 1e-7


def test_resolution_sweep_matches_tables_made_by_lut():
    from brdfnorm.audit import quality
    from brdfnorm.audit.conventions import Convention
    from brdfnorm.audit.reference import Reference

    c = Convention(direction="mu-texel", roughness="r2-texel", meanings=("E",))
    reference = Reference(bn.load("ggx"))
    points = quality.dense_points(c, (N, N), 2048)
    rows = quality.sweep(c, "E", reference, points, 2, sizes=(8, 16))
    for row in rows:
        t = (np.arange(row["size"]) + 0.5) / row["size"]
        table = lut.compute(bn.load("ggx"), {"mu": t, "alpha": t * t}, rtol=1e-10, average=False)["E"]
        assert quality.dense_error(table, c, "E", reference, points).max == pytest.approx(row["max"], abs=1e-8)
    assert rows[1]["max"] < rows[0]["max"]


def test_channels_override(tmp_path):
    from brdfnorm.audit.readers import read_table

    np.savez(tmp_path / "t.npz", T=np.random.default_rng(0).random((8, 8, 4)))
    assert read_table(tmp_path / "t.npz").channel_names == ["0", "1", "2", "3"]
    as_grid = read_table(tmp_path / "t.npz", channels=False)
    assert as_grid.channel_names == ["0"] and as_grid.grid_shape == (8, 8, 4)
    np.savez(tmp_path / "u.npz", T=np.zeros((8, 8, 8)))
    assert read_table(tmp_path / "u.npz", channels=True).channel_names == [str(i) for i in range(8)]
