"""brdfnorm audit with local defects (issue 42), in every reader format: a three-channel table (E, 1 − E, E) made
by ``lut.compute`` in a known convention, then damaged — a 3×3 block 4 % too bright, one cell's first two
channels swapped, one NaN (a value above 1 where the format cannot hold NaN), and channel 2 stored transposed.

The audit must name the true convention, list exactly the damaged cells (computed here from the table before the
damage, the independent route), exit 1; ``--fix`` must write a file whose audit exits 0 and whose numbers differ
from the input's only in those cells, every other byte of a text file kept."""

from __future__ import annotations

import json
import re
import zipfile

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.audit.readers import read_table

N = 8
MU = (np.arange(N) + 0.5) / N
ALPHA = np.linspace(0.0, 1.0, N)
BLOCK = (slice(2, 5), slice(3, 6))
SWAP = (6, 1)
HOLE = (0, 7)
_CLEAN = None


def _clean() -> np.ndarray:
    global _CLEAN
    if _CLEAN is None:
        e = lut.compute(bn.load("ggx"), {"mu": MU, "alpha": np.maximum(ALPHA, 1e-8)}, clamp={"mu": 1e-4},
                        rtol=1e-10, average=False)["E"]
        _CLEAN = np.stack([e, 1.0 - e, e], axis=-1)
    return _CLEAN


def _damaged(nan: bool) -> np.ndarray:
    d = _clean().copy()
    d[..., 2] = d[..., 2].T.copy()
    d[BLOCK + (0,)] *= 1.04
    d[SWAP + (slice(0, 2),)] = d[SWAP + (slice(1, None, -1),)].copy()
    d[HOLE + (0,)] = np.nan if nan else 1.5
    return d


def _expected(stored: np.ndarray, threshold: float) -> dict[str, set]:
    """The damaged cells per channel: where the stored table differs from the clean one (NaN included)."""
    clean = _clean()
    out = {}
    for k in range(3):
        wrong = ~(np.abs(stored[..., k] - clean[..., k]) <= threshold)
        out[str(k)] = {tuple(int(i) for i in w) for w in np.argwhere(wrong)}
    return out


def _npy(array: np.ndarray) -> bytes:
    import io

    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, array)
    return buffer.getvalue()


def _write_npz(path, d):
    # members named like np.savez's own keywords ("file", "allow_pickle"): np.savez cannot write them
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("lut.npy", _npy(d.astype(np.float32)))
        archive.writestr("file.npy", _npy(np.arange(3)))
        archive.writestr("allow_pickle.npy", _npy(np.array([1.5])))


def _write_exr(path, d):
    OpenEXR = pytest.importorskip("OpenEXR")
    with OpenEXR.File({"type": OpenEXR.scanlineimage}, {c: d[..., k].astype(np.float32)
                                                        for k, c in enumerate("RGB")}) as image:
        image.write(str(path))


def _write_png(path, d):
    from brdfnorm.inputs.png import encode

    path.write_bytes(encode(np.rint(np.clip(d, 0, 1) * 65535).astype(int), 16))


def _write_csv(path, d):
    rows = [",".join(f"{v:.9g}" for v in row.ravel()) for row in d.astype(np.float32)]
    path.write_bytes(("\ufeff# split over (mu, alpha), two channels interleaved — ĉ\n" + "\n".join(rows) + "\n")
                     .encode("utf-8"))


def _write_json(path, d):
    path.write_text(json.dumps({"name": "E and 1-E", "data": d.tolist()}, indent=1))


def _write_h(path, d):
    values = ",\n  ".join(", ".join(f"{v:.9g}f" for v in row.ravel()) for row in d.astype(np.float32))
    path.write_bytes(("/* tabulated by hand, caf\xe9 */\nstatic const float kLut[8][8][3] = {\n  " + values
                      + "\n};\n").encode("latin-1"))


def _write_js(path, d):
    values = ", ".join(f"{v:.9g}" for v in d.astype(np.float32).ravel())
    path.write_text(f"// E and 1-E\nexport const LUT = new Float32Array([{values}]);\n")


#: (file name, writer, CLI options, NaN storable, damage threshold, numbers of a text file)
FORMATS = [
    ("t.npz", _write_npz, ["--array", "lut"], True, 1e-6, False),
    ("t.exr", _write_exr, [], True, 1e-6, False),
    ("t.png", _write_png, [], False, 2.0 / 65535, False),
    ("t.csv", _write_csv, ["--shape", f"{N},{N},3"], True, 1e-6, True),
    ("t.json", _write_json, ["--array", "data"], True, 1e-6, True),
    ("t.h", _write_h, [], False, 1e-6, True),
    ("t.js", _write_js, ["--shape", f"{N},{N},3"], False, 1e-6, True),
]

NUMBER = re.compile(r"-?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|NaN|nan")


def _skeleton(data: bytes) -> tuple[bytes, list[bytes]]:
    """A text file with its numbers replaced by '#' (and brdfnorm's metadata removed), and its numbers."""
    text = data.decode("latin-1")
    text = re.sub(r"/\* brdfnorm audit --fix: .*? \*/\n", "", text)
    text = re.sub(r"# \{\"brdfnorm\".*\n", "", text)
    at = text.find('"brdfnorm_audit": ')
    if at >= 0:
        _, end = json.JSONDecoder().raw_decode(text, at + len('"brdfnorm_audit": '))
        text = text[:at] + text[end + 2:]
    return NUMBER.sub("#", text).encode("latin-1"), NUMBER.findall(text)


@pytest.mark.parametrize("name, writer, options, nan, threshold, textual", FORMATS, ids=[f[0] for f in FORMATS])
def test_local_defects_are_named_listed_and_fixed(tmp_path, name, writer, options, nan, threshold, textual, run_cli):
    path = tmp_path / name
    writer(path, _damaged(nan))
    stored = read_table(str(path), **_read_options(options)).values
    expected = _expected(stored, threshold)
    fixed = tmp_path / ("fixed_" + name)
    code, out, err = run_cli("audit", str(path), *options, "--no-interpolation", "--no-sweep", "--json",
                             "--fix", "-o", str(fixed))
    assert code == 1, err
    result = json.loads(out)
    convention = result["best"]["convention"]
    assert (convention["axes"], convention["direction"], convention["roughness"], convention["shadowing"],
            convention["channels"]) == (["mu", "alpha"], "mu-texel", "alpha-node", "height-correlated",
                                         ["E", "1-E", "E"])
    assert result["verdict"] == "fits" and not result["passes"]
    names = result["channels"]
    expected = {names[int(k)]: v for k, v in expected.items()}
    listed = {k: {tuple(c["index"]) for c in v["cells"]} for k, v in result["wrong_cells"].items()}
    assert listed == expected
    assert result["wrong_cells"][names[2]]["layout"] == "transposed"
    block = [r for r in result["wrong_cells"][names[0]]["regions"] if r["from"] == [2, 3]]
    assert block and block[0]["to"] == [4, 5] and block[0]["cells"] == 9
    for cell in result["wrong_cells"][names[0]]["cells"]:  # every listed number checked against the clean table
        i = tuple(cell["index"])
        assert abs(cell["exact"] - _clean()[i + (0,)]) < 1e-8
        assert cell["at"] == pytest.approx({"mu": MU[i[0]], "alpha": ALPHA[i[1]]})
    # the fixed file: every cell within tolerance, and only the wrong cells changed
    code, out, err = run_cli("audit", str(fixed), *options, "--no-interpolation", "--no-sweep", "--json")
    assert code == 0, err
    again = json.loads(out)
    assert again["passes"] and again["best"]["text"] == result["best"]["text"]
    after = read_table(str(fixed), **_read_options(options)).values
    changed = {names[k]: {tuple(int(i) for i in w) for w in np.argwhere(~(after[..., k] == stored[..., k]))}
               for k in range(3)}
    assert changed == expected
    if textual:
        before_skeleton, before_numbers = _skeleton(path.read_bytes())
        after_skeleton, after_numbers = _skeleton(fixed.read_bytes())
        assert after_skeleton == before_skeleton  # every byte but the changed numbers (and the metadata) kept
        differing = sum(a != b for a, b in zip(before_numbers, after_numbers, strict=True))
        assert differing == sum(len(v) for v in expected.values())
    if name.endswith(".npz"):
        with zipfile.ZipFile(path) as a, zipfile.ZipFile(fixed) as b:
            assert {"file.npy", "allow_pickle.npy"} <= set(b.namelist())
            assert a.read("file.npy") == b.read("file.npy") and a.read("allow_pickle.npy") == b.read(
                "allow_pickle.npy")


def _read_options(options: list[str]) -> dict:
    out = {}
    for flag, value in zip(options[::2], options[1::2], strict=True):
        if flag == "--array":
            out["array"] = value
        elif flag == "--shape":
            out["shape"] = tuple(int(v) for v in value.split(","))
    return out


def test_fix_refuses_a_channel_it_cannot_name(tmp_path, run_cli):
    d = _clean()[..., :2].copy()
    d[..., 1] = np.random.default_rng(3).random((N, N))
    path = tmp_path / "t.npz"
    np.savez(path, lut=d)
    fixed = tmp_path / "fixed.npz"
    code, out, err = run_cli("audit", str(path), "--no-interpolation", "--no-sweep", "--fix", "-o",
                             str(fixed))
    assert code == 1 and "channel 1" in err and "nothing written" in err
    assert not fixed.exists()
    # '-' keeps the channel as read: the rest is then fixed and passes
    code, out, err = run_cli("audit", str(path), "--no-interpolation", "--no-sweep", "--as",
                             "channels=E,-", "--fix", "-o", str(fixed))
    assert code == 0, err
    assert np.array_equal(np.load(fixed)["lut"], d)


def test_tolerance_is_printed_and_can_be_set(tmp_path, run_cli):
    d = _clean()[..., :1].copy()
    d[3, 3, 0] += 2e-4
    path = tmp_path / "t.npz"
    np.savez(path, lut=d[..., 0])
    code, out, err = run_cli("audit", str(path), "--no-interpolation", "--no-sweep")
    assert code == 1 and "1 cell is wrong by up to 0.0002" in out and "(3, 3)" in out
    code, out, err = run_cli("audit", str(path), "--no-interpolation", "--no-sweep", "--tolerance", "1e-3")
    assert code == 0 and "tolerance 0.001 (--tolerance)" in out and "PASS" in out
    code, out, err = run_cli("audit", str(path), "--tolerance", "-1")
    assert code == 2 and err.startswith("error:") and "--tolerance" in err and err.count("\n") == 1


# -- fitted approximations: named as what they approximate, their error checked against lut.compute -----------

def _texel_grid(n):
    t = (np.arange(n) + 0.5) / n
    return t, np.meshgrid(t, t, indexing="ij")


def test_yocto_gl_fit_is_named_and_its_error_measured():
    from brdfnorm.audit import audit
    from brdfnorm.audit.approximations import _yocto

    t, (mu, r) = _texel_grid(8)
    table = _yocto(mu, r)[0].astype(np.float32).astype(float)
    result = audit(table, "ggx", read={"dtype": "float32"}, dense=False, sweep=False)
    found = result.approximation
    assert not result.passes and found["name"] == "yocto-gl-cosintegral" and found["within"] == 64
    exact = lut.compute(bn.load("ggx"), {"mu": t, "alpha": t * t}, clamp={"mu": 1e-4}, rtol=1e-10,
                        average=False)["E"]
    channel = found["channels"][0]
    assert channel["approximates"] == "E" and "height-correlated" in found["convention"]
    assert channel["max"] == pytest.approx(np.max(np.abs(table - exact)), rel=1e-6)
    assert channel["median"] == pytest.approx(np.median(np.abs(table - exact)), rel=1e-6)


@pytest.mark.slow
def test_karis_env_brdf_approx_is_named_and_its_error_measured(tmp_path, run_cli):
    from brdfnorm.audit.approximations import _karis

    t, (r, mu) = _texel_grid(16)
    table = np.stack(_karis(mu, r), axis=-1).astype(np.float32)
    np.savez(tmp_path / "karis.npz", lut=table)
    code, out, err = run_cli("audit", str(tmp_path / "karis.npz"), "--no-interpolation", "--no-sweep",
                             "--json")
    assert code == 1
    found = json.loads(out)["approximation"]
    assert found["name"] == "karis-envbrdfapprox" and found["within"] == 512
    dfg = lut.compute(bn.load("ggx").with_params(shadowing="separable"), {"alpha": t * t, "mu": t},
                      channels=["dfg"], clamp={"mu": 1e-4}, rtol=1e-9, average=False)
    for channel, name in zip(found["channels"], ("DFG_f0", "DFG_f90"), strict=True):
        error = np.abs(table[..., ["DFG_f0", "DFG_f90"].index(name)] - dfg[name])
        assert channel["approximates"] == name and channel["max"] == pytest.approx(np.max(error), rel=1e-4)
    # pinned to the split-sum meanings, the closest hypothesis is ranked by the median it prints: the true layout
    code, out, err = run_cli("audit", str(tmp_path / "karis.npz"), "--no-interpolation", "--no-sweep",
                             "--json", "--as", "channels=DFG_f0,DFG_f90")
    result = json.loads(out)
    assert code == 1 and result["best"]["convention"]["axes"] == ["roughness (alpha = r^2)", "mu"]
    assert all(result["best"]["median"] <= h["median"] for h in result["runners_up"])


def test_report_lists_every_wrong_cell_and_marks_them(tmp_path, run_cli):
    path = tmp_path / "t.npz"
    _write_npz(path, _damaged(True))
    expected = _expected(read_table(str(path), array="lut").values, 1e-6)
    report = tmp_path / "report"
    code, out, err = run_cli("audit", str(path), "--array", "lut", "--no-interpolation", "--no-sweep",
                             "--report", str(report))
    assert code == 1, err
    rows = (report / "wrong_cells.csv").read_text().splitlines()
    assert rows[0].split(",")[:5] == ["channel", "meaning", "region", "index0", "index1"]
    listed = {}
    for row in rows[1:]:
        cells = row.split(",")
        listed.setdefault(cells[0], set()).add((int(cells[3]), int(cells[4])))
    assert listed == expected
    for k in range(3):
        assert (report / f"error_map_{k}.png").stat().st_size > 1000
    # the text lists the block as one region of nine cells, with its axis values as stored
    code, out, err = run_cli("audit", str(path), "--array", "lut", "--no-interpolation", "--no-sweep")
    assert "region 2: 9 cells at [2..4, 3..5]" in out and "(2, 3) mu=0.3125 alpha=0.428571" in out


# -- raw binary with a header and C size expressions (the reader core of the hostile branch) ------------------

def _cli_has(option: str) -> bool:
    import inspect

    from brdfnorm.cli.audit import audit_command

    return any(option in (getattr(p.default, "param_decls", None) or ())
               for p in inspect.signature(audit_command).parameters.values())


@pytest.mark.skipif(not _cli_has("--offset"), reason="requires reader core (hostile branch): --offset")
def test_raw_binary_with_a_header_is_fixed_around_it(tmp_path, run_cli):
    d = _damaged(True)
    header = b"LUT1" + bytes(range(60))  # 64 bytes the fix must keep
    path = tmp_path / "t.bin"
    path.write_bytes(header + d.astype("<f4").tobytes())
    options = ["--offset", "64", "--shape", f"{N},{N},3", "--dtype", "float32"]
    fixed = tmp_path / "fixed.bin"
    code, out, err = run_cli("audit", str(path), *options, "--no-interpolation", "--no-sweep", "--json",
                             "--fix", "-o", str(fixed))
    assert code == 1, err
    result = json.loads(out)
    stored = np.frombuffer(path.read_bytes()[64:], dtype="<f4").reshape(N, N, 3).astype(float)
    expected = _expected(stored, 1e-6)
    assert {k: {tuple(c["index"]) for c in v["cells"]} for k, v in result["wrong_cells"].items()} == expected
    assert fixed.read_bytes()[:64] == header
    code, out, err = run_cli("audit", str(fixed), *options, "--no-interpolation", "--no-sweep")
    assert code == 0, err


def test_c_size_expression_gives_the_shape(tmp_path, run_cli):
    d = _damaged(False).astype(np.float32)
    values = ", ".join(f"{v:.9g}f" for v in d.ravel())
    path = tmp_path / "t.h"
    path.write_text(f"static const float kLut[{N} * {N} * 3] = {{ {values} }};\n")
    from brdfnorm.audit.readers import read_table
    from brdfnorm.errors import TableFileError

    try:
        read_table(str(path))
    except TableFileError as error:
        if "--shape" in str(error):
            pytest.skip("requires reader core (hostile branch): a size expression as the shape")
        raise
    code, out, err = run_cli("audit", str(path), "--no-interpolation", "--no-sweep", "--json")
    result = json.loads(out)
    assert code == 1 and result["shape"] == [N, N] and result["best"]["convention"]["direction"] == "mu-texel"
