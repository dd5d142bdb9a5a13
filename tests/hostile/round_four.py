"""Hostile cases of issues 41 (round four: the audit's readers and formulas, sizes checked before work) and 46
(round three's last cases), as data for ``test_hostile_cases.py``: each makes its input in a fresh directory and
names the command (or the API script) that reads it."""

from __future__ import annotations

import io
import json
import struct
import zlib
from pathlib import Path

import numpy as np

from brdfnorm.inputs.png import SIGNATURE, encode
from brdfnorm.lut.formats import dumps
from hostile.hostile_cases import Case, small_lut


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def _png(width: int, height: int, channels: int, rows: bytes) -> bytes:
    colour = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    return (SIGNATURE + _chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour, 0, 0, 0))
            + _chunk(b"IDAT", zlib.compress(rows, 9)) + _chunk(b"IEND", b""))


def _audit(path: Path, *extra: str) -> list[str]:
    return ["audit", str(path), *extra]


def _write(path: Path, data: bytes | str) -> Path:
    if isinstance(data, str):
        path.write_text(data)
    else:
        path.write_bytes(data)
    return path


# -- issue 46 ---------------------------------------------------------------------------------------------------

def _lut_npz(directory: Path, **axes: np.ndarray) -> list[str]:
    lut = small_lut()
    meta = json.dumps({"model": "ggx", "axes": ["mu", "alpha"], "tables": {"E": ["mu", "alpha"]}})
    buffer = io.BytesIO()
    np.savez(buffer, meta=np.array(meta), E=lut["E"], **{**lut.axes, **axes})
    return ["fit", "--lut", str(_write(directory / "t.npz", buffer.getvalue()))]


def npz_axis_2d(directory: Path) -> list[str]:
    return _lut_npz(directory, mu=np.array([[0.25, 0.5, 1.0]] * 3))


def npz_axis_repeated(directory: Path) -> list[str]:
    return _lut_npz(directory, alpha=np.array([0.1, 0.3, 0.3, 1.0]))


def png_declares_two_tables(directory: Path) -> list[str]:
    data = dumps(small_lut(), "png")
    at = data.index(b"tEXt") - 4
    (length,) = struct.unpack(">I", data[at:at + 4])
    key, _, text = data[at + 8:at + 8 + length].partition(b"\x00")
    meta = json.loads(text)
    meta["tables"]["F"] = ["mu"]  # a second table, over mu, that the image does not hold
    chunk = _chunk(b"tEXt", key + b"\x00" + json.dumps(meta).encode())
    return ["fit", "--lut", str(_write(directory / "t.png", data[:at] + chunk + data[at + 12 + length:]))]


def csv_one_column_51m_rows(directory: Path) -> list[str]:
    meta = {"model": "ggx", "axes": ["mu"], "tables": {}}
    path = directory / "t.csv"
    with open(path, "w") as handle:
        handle.write(f"# brdfnorm-lut {json.dumps(meta)}\nmu\n")
        block = "0\n" * 1_000_000
        for _ in range(51):
            handle.write(block)
    return ["fit", "--lut", str(path)]


# -- issue 41: work capped by a table's size ---------------------------------------------------------------------

def png_4096_rgba(directory: Path) -> list[str]:
    rows = bytes(4096 * (1 + 4096 * 4))
    return _audit(_write(directory / "t.png", _png(4096, 4096, 4, rows)))


def png_one_by_16m(directory: Path) -> list[str]:
    rows = bytes(1 + 16 * 1024 * 1024)
    return _audit(_write(directory / "t.png", _png(16 * 1024 * 1024, 1, 1, rows)))


def exr_1000_channels(directory: Path) -> list[str]:
    import OpenEXR

    channels = {f"c{k:04d}": np.zeros((2, 2), dtype=np.float32) for k in range(1000)}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    path = directory / "t.exr"
    with OpenEXR.File(header, channels) as image:
        image.write(str(path))
    return _audit(path)


def raw_8_8_1000(directory: Path) -> list[str]:
    path = _write(directory / "t.bin", np.full(8 * 8 * 1000, 0.5, dtype=np.float32).tobytes())
    return _audit(path, "--shape", "8,8,1000", "--channels")  # 1000 channels (as a grid axis: audit's speed)


def npz_4d(directory: Path) -> list[str]:
    buffer = io.BytesIO()
    np.savez(buffer, E=np.full((4, 4, 4, 4), 0.5))
    return _audit(_write(directory / "t.npz", buffer.getvalue()))


# -- issue 41: parsers bounded before they loop ------------------------------------------------------------------

def png_paeth_2048(directory: Path) -> list[str]:
    """A 2048² greyscale image every row of which is Paeth-filtered, decoded by the reader core (the old per-byte
    loop took > 40 s)."""
    rows = (b"\x04" + bytes(2048)) * 2048
    _write(directory / "t.png", _png(2048, 2048, 1, rows))
    return ["from brdfnorm.inputs import png; codes, _, _ = png.decode(open('t.png', 'rb').read(), 't.png')"
            .replace("t.png", str(directory / "t.png")) + "; assert codes.shape == (2048, 2048, 1) and not codes.any()"]


def h_nested_braces(directory: Path) -> list[str]:
    text = "const float t[] = " + "{" * 200_000 + "1, 2" + "}" * 200_000 + ";\n"
    return _audit(_write(directory / "t.h", text))


def h_30m_commas(directory: Path) -> list[str]:
    return _audit(_write(directory / "t.h", "const float t[] = {1" + "," * 30_000_000 + "2};\n"))


def h_empty_element(directory: Path) -> list[str]:
    return _audit(_write(directory / "t.h", "const float t[] = {1,,2, 3, 4, 5};\n"))


def h_8m_numbers(directory: Path) -> list[str]:
    return _audit(_write(directory / "t.h", "const float t[] = {" + "1," * 8_500_000 + "1};\n"))


def csv_30m_rows(directory: Path) -> list[str]:
    path = directory / "t.csv"
    with open(path, "w") as handle:
        block = "0.5,0.5\n" * 1_000_000
        for _ in range(30):
            handle.write(block)
    return _audit(path)


def csv_nul_in_first_row(directory: Path) -> list[str]:
    rows = [",".join("0.5" for _ in range(8)) for _ in range(8)]
    rows[0] = rows[0][:-3] + "0\x005"
    return _audit(_write(directory / "t.csv", "\n".join(rows) + "\n"))


def json_two_long_keys(directory: Path) -> list[str]:
    document = {"k" * 512 * 1024: [0.5, 0.5], "j" * 512 * 1024: [0.5, 0.5]}
    return _audit(_write(directory / "t.json", json.dumps(document)))


def json_5m_numbers(directory: Path) -> list[str]:
    return _audit(_write(directory / "t.json", '{"E": [' + "0," * 5_000_000 + "0]}"))


def h_size_expression(directory: Path) -> list[str]:
    """A C declaration whose size is an expression of factors: its shape (32, 32, 2), read without --shape."""
    lut = np.full((32, 32, 2), 0.5, dtype=np.float32)
    body = ", ".join(f"{v:.6f}f" for v in lut.ravel())
    path = _write(directory / "t.h", f"static const float g_dfg[32 * 32 * 2] = {{{body}}};\n")
    return [f"from brdfnorm.audit.readers import read_table; s = read_table({str(path)!r}); "
            "assert s.values.shape == (32, 32, 2), s.values.shape"]


def raw_offset_big_endian(directory: Path) -> list[str]:
    values = np.linspace(0.1, 0.9, 16 * 16 * 2).astype(">f4")
    path = _write(directory / "t.bin", b"HEADER16BYTES..." + values.tobytes())
    return [f"from brdfnorm.audit.readers import read_table; s = read_table({str(path)!r}, shape=(16, 16, 2), "
            "offset=16, byteorder='big'); import numpy as np; "
            "assert np.array_equal(s.values.ravel(), np.linspace(0.1, 0.9, 512).astype(np.float32))"]


def raw_big_endian_cli(directory: Path) -> list[str]:
    """An exact GGX E table (8 × 8, μ texels, α nodes) as big-endian float32 after a 16-byte header: the audit
    CLI's --offset and --byte-order read it, and it fits."""
    import brdfnorm as bn
    from brdfnorm import lut

    axes = {"mu": (np.arange(8) + 0.5) / 8, "alpha": np.maximum(np.linspace(0, 1, 8), 1e-8)}
    table = lut.compute(bn.load("ggx"), axes, average=False)["E"]
    path = _write(directory / "t.bin", b"X" * 16 + table.astype(">f4").tobytes())
    return _audit(path, "--shape", "8,8", "--offset", "16", "--byte-order", "big", "--as",
                  "shadowing=height-correlated", "--no-interpolation", "--no-sweep", "--json")


# -- issue 41: formulas ------------------------------------------------------------------------------------------

def formula(text: str):
    def make(directory: Path) -> list[str]:
        return ["audit", "--formula", text]
    return make


# -- issue 41: declared ranges, the API, output hygiene ----------------------------------------------------------

def ms_table_1024(directory: Path) -> list[str]:
    return ["albedo", "ggx", "-p", "ms=kulla-conty", "-p", "ms_table=1024", "--theta", "30"]


def api(body: str):
    def make(directory: Path) -> list[str]:
        return [body]
    return make


def npz_table(values: np.ndarray, name: str = "E"):
    def make(directory: Path) -> list[str]:
        buffer = io.BytesIO()
        np.savez(buffer, **{name: values})
        return _audit(_write(directory / "t.npz", buffer.getvalue()))
    return make


def audit_flag(*flags: str):
    def make(directory: Path) -> list[str]:
        mu = (np.arange(8) + 0.5) / 8
        buffer = io.BytesIO()
        np.savez(buffer, E=np.tile(0.5 + 0.1 * mu[:, None], (1, 8)))
        return _audit(_write(directory / "t.npz", buffer.getvalue()), "--no-interpolation", "--no-sweep", *flags)
    return make


def brdf_lut_png(directory: Path) -> list[str]:
    """An engine PNG in brdfnorm's own layout (as a check that a legal image still reads)."""
    return _audit(_write(directory / "t.png", encode(np.zeros((4, 4, 3), dtype=np.int64), 16)))


def lut_huge_values(directory: Path) -> list[str]:
    buffer = io.BytesIO()
    np.savez(buffer, E=np.full((8, 8), 1e300))
    return _audit(_write(directory / "t.npz", buffer.getvalue()), "--no-interpolation", "--no-sweep")


def xml_100000_deep(directory: Path) -> list[str]:
    text = '<bsdf type="diffuse">' + "<a>" * 100_000 + "</a>" * 100_000 + "</bsdf>"  # 700 KB, under the 1 MiB cap
    return ["albedo", str(_write(directory / "deep.xml", text))]


_BROADCAST = "np.broadcast_to(0.5, (10**5, 10**5))"

CASES = [
    # issue 46
    Case("fit-lut-npz-axis-2d", npz_axis_2d, extra={"contains": "axis mu"}, seconds=20),
    Case("fit-lut-npz-axis-repeated", npz_axis_repeated, extra={"contains": "axis alpha"}, seconds=20),
    Case("fit-lut-png-declares-two-tables", png_declares_two_tables, extra={"contains": "E, F"}, seconds=20),
    Case("fit-lut-csv-one-column-51m-rows", csv_one_column_51m_rows, slow=True, cpu_seconds=10),
    Case("albedo-phong-n-1e300-certified", lambda d: ["albedo", "phong", "-p", "n=1e300", "--method", "certified"],
         names="phong", seconds=20),
    # issue 41 (1): work capped by the table's size
    Case("audit-png-4096-rgba", png_4096_rgba, cpu_seconds=10, seconds=30, slow=True),
    Case("audit-png-1-by-16m", png_one_by_16m, cpu_seconds=10, seconds=30),
    Case("audit-exr-1000-channels", exr_1000_channels, cpu_seconds=10, seconds=30, slow=True),
    Case("audit-raw-8-8-1000", raw_8_8_1000, cpu_seconds=10, seconds=30),
    Case("audit-npz-4d", npz_4d, cpu_seconds=10, seconds=30),
    Case("api-audit-broadcast-1e10", api(f"from brdfnorm.audit import audit; audit({_BROADCAST}, 'ggx')"),
         names="table", api=True, cpu_seconds=10, seconds=30),
    # issue 41 (2): parsers bounded before they loop
    Case("png-paeth-2048-decoded", png_paeth_2048, exit=0, api=True, cpu_seconds=10, seconds=30, slow=True),
    Case("audit-h-200000-nested-braces", h_nested_braces, cpu_seconds=10, seconds=30, slow=True),
    Case("audit-h-30m-commas", h_30m_commas, cpu_seconds=10, seconds=30, slow=True),
    Case("audit-h-empty-element", h_empty_element, extra={"contains": "empty element"}),
    Case("audit-h-8.5m-numbers", h_8m_numbers, cpu_seconds=10, seconds=30, slow=True),
    Case("audit-csv-30m-rows", csv_30m_rows, cpu_seconds=10, seconds=30, slow=True),
    Case("audit-json-5m-numbers", json_5m_numbers, cpu_seconds=10, seconds=30, extra={"contains": "values"}, slow=True),
    Case("audit-h-size-expression-is-the-shape", h_size_expression, exit=0, api=True),
    Case("audit-raw-offset-big-endian", raw_offset_big_endian, exit=0, api=True),
    Case("audit-raw-offset-big-endian-cli", raw_big_endian_cli, exit=0, stdout_ok=True, seconds=30, slow=True),
    Case("audit-offset-of-a-npz", audit_flag("--offset", "8"), names="--offset"),
    # issue 41 (3, 6): formulas
    Case("formula-400-digit-integer", formula("mu*" + "9" * 400), names="--formula"),
    Case("formula-complex-exponent", formula("mu**2j"), names="--formula"),
    Case("formula-string-exponent", formula("mu**'a'"), names="--formula"),
    Case("formula-pow-string", formula("pow(mu,'x')"), names="--formula"),
    Case("formula-min-one-argument", formula("min(mu)"), names="--formula", extra={"contains": "min"}),
    Case("formula-exp-no-argument", formula("exp()"), names="--formula", extra={"contains": "exp"}),
    Case("formula-exp-two-arguments", formula("exp(mu, 1)"), names="--formula", extra={"contains": "exp"}),
    Case("formula-exp-out-argument", formula("exp(mu, mu)"), names="--formula", extra={"contains": "exp"}),
    Case("formula-tower-of-powers", formula("2**(2**(2**64))"), names="--formula"),
    Case("api-compile-expression-big-integer",
         api("from brdfnorm.audit.formula import compile_expression; compile_expression('1' * 400, ('mu',))"),
         names="--formula", api=True),
    # issue 41 (3): options and tables that raised internal errors
    Case("albedo-mitsuba-xml-100000-deep", xml_100000_deep, cpu_seconds=10, seconds=30),
    Case("audit-as-flip-abc", audit_flag("--as", "flip=abc"), names="--as"),
    Case("audit-channel-superscript-two", audit_flag("--channel", "²"), names="--channel"),
    Case("api-audit-all-nan", api("from brdfnorm.audit import audit; audit(np.full((8, 8), np.nan), 'ggx')"),
         names="table", api=True),
    Case("api-audit-all-inf", api("from brdfnorm.audit import audit; audit(np.full((8, 8), np.inf), 'ggx')"),
         names="table", api=True),
    # issue 41 (4, 5): declared ranges and broadcast inputs
    Case("albedo-ggx-ms-table-1024", ms_table_1024, names="ms_table", seconds=30),
    Case("api-albedo-broadcast-theta", api(f"bn.albedo(bn.load('ggx'), {_BROADCAST})"), names="theta", api=True,
         cpu_seconds=10, seconds=30),
    Case("api-albedo-broadcast-alpha", api(f"bn.albedo(bn.load('ggx', alpha={_BROADCAST}), 0.5)"), names="alpha",
         api=True, cpu_seconds=10, seconds=30),
    Case("api-lut-compute-broadcast-1e9-axis",
         api("from brdfnorm import lut; lut.compute(bn.load('ggx'), {'mu': np.broadcast_to(0.5, 10**9)})"),
         names="axes", api=True, cpu_seconds=10, seconds=30),
    # issue 41 (6, 7): silently wrong, output hygiene
    Case("audit-csv-nul-in-first-row", csv_nul_in_first_row, extra={"contains": "column 8"}),
    Case("audit-axis-theta-1e308", audit_flag("--axis", "theta=0:1e308:8"), names="--axis"),
    Case("audit-axis-mu-minus-5-to-7", audit_flag("--axis", "mu=-5:7:8"), names="--axis"),
    Case("audit-json-two-512k-keys", json_two_long_keys, extra={"contains": "…"}),
    Case("audit-scale-0", audit_flag("--scale", "0"), names="--scale"),
    Case("audit-table-of-1e300", lut_huge_values, exit=1, stdout_ok=True, stderr="", seconds=60, slow=True),
]
