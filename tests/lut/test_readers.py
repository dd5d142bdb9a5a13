"""The table readers of the engine formats (issue 31: R, G, B, A channels, several EXR parts, float32 kept) under
the bounds and guards of issue 35 (brdfnorm.lut.readers): sizes counted before inflating, mappings checked, bad
cells named."""

from __future__ import annotations

import json
import re
import struct
import zlib

import numpy as np
import pytest

from brdfnorm import lut
from brdfnorm.errors import TableFileError
from brdfnorm.lut import formats

MU = [0.05, 0.3, 0.7, 1.0]
N = [2.0, 30.0, 400.0]


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def _png(meta: dict, codes: np.ndarray, colour: int = 0) -> bytes:
    """A 16-bit PNG written here, independently of brdfnorm's writer: ``codes`` of shape (rows, columns[, samples])."""
    codes = codes.reshape(codes.shape[0], codes.shape[1], -1).astype(">u2")
    height, width, _ = codes.shape
    raw = b"".join(b"\x00" + row.tobytes() for row in codes)
    text = b"brdfnorm-lut\x00" + json.dumps(meta).encode("latin-1")
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 16, colour, 0, 0, 0))
            + _chunk(b"tEXt", text) + _chunk(b"IDAT", zlib.compress(raw)) + _chunk(b"IEND", b""))


def _load_error(path, data: bytes) -> str:
    path.write_bytes(data)
    with pytest.raises(TableFileError) as caught:
        lut.load(path)
    assert caught.value.where == str(path)
    return caught.value.message


def test_png_size_counts_every_sample_before_inflating(bp_table, tmp_path):
    data = formats.dumps(bp_table, "png")  # E, DFG_f0, DFG_f90: RGB
    assert data[25] == 2
    for colour, expected in ((6, "height × width × samples"), (0, "image data holds")):
        header = _chunk(b"IHDR", struct.pack(">IIBBBBB", 3000, 3000, 16, colour, 0, 0, 0))
        message = _load_error(tmp_path / "t.png", data[:8] + header + data[8 + 25:])
        # 9 M pixels pass as greyscale (then the tiny IDAT is short); × 4 samples is past the 16 Mi cap
        # (brdfnorm.inputs.limits.MAX_ELEMENTS)
        assert expected in message, message


def test_png_old_greyscale_metadata_still_reads(tmp_path):
    codes = np.array([[0, 100, 65535], [7, 30000, 65535], [1, 2, 3], [9, 8, 60000]])  # rows μ, columns n
    meta = {"axes": ["mu", "n"], "tables": {"E": ["mu", "n"]}, "axis_values": {"mu": MU, "n": N},
            "png": {"table": "E", "lo": 0.25, "hi": 0.75}}
    (tmp_path / "old.png").write_bytes(_png(meta, codes))
    back = lut.load(tmp_path / "old.png")
    assert list(back) == ["E"] and back.table_axes["E"] == ("mu", "n")
    assert np.array_equal(back["E"], 0.25 + codes / 65535.0 * 0.5)


@pytest.mark.parametrize(("channels", "colour"), [({"R": "E", "G": "F", "B": "H"}, 0), ({"G": "E"}, 0)])
def test_png_mapping_must_fit_the_image(tmp_path, channels, colour):
    entry = {"lo": 0.0, "hi": 1.0}
    meta = {"axes": ["mu", "n"], "tables": {name: ["mu", "n"] for name in channels.values()},
            "axis_values": {"mu": MU, "n": N},
            "png": {"axes": ["mu", "n"], "channels": {c: {**entry, "table": t} for c, t in channels.items()}}}
    message = _load_error(tmp_path / "t.png", _png(meta, np.zeros((4, 3), dtype=int), colour))
    assert message.startswith("metadata does not describe the image"), message


def test_code_value_past_float32_is_named(bp_table, tmp_path):
    code = formats.dumps(bp_table, "h", tables=["E"])
    damaged, found = re.subn(r"(lut_E\[3\]\[4\] = \{\s*\{)[^,]+", r"\g<1>1e39f", code, count=1)
    assert found == 1
    message = _load_error(tmp_path / "t.h", damaged.encode())
    assert message.startswith("table E, cell [0, 0]: inf"), message
    back = lut.load(lut.save(bp_table, tmp_path / "ok.h", tables=["E"]))
    assert back["E"].dtype == np.float32 and np.array_equal(back["E"], bp_table["E"].astype(np.float32))


def test_exr_nan_pixel_is_named_and_float16_kept(bp_table, tmp_path):
    OpenEXR = pytest.importorskip("OpenEXR")  # noqa: N806
    path = lut.save(bp_table, tmp_path / "t.exr", tables=["E", "DFG_f0"])  # one part: R = E, G = DFG_f0
    with OpenEXR.File(str(path), separate_channels=True) as image:
        meta = image.header()["brdfnorm"]
        channels = {name: np.array(c.pixels) for name, c in image.channels().items()}
    channels["R"][1, 2] = np.nan  # row 1 (n[1]), column 2 (μ[2]) of the engine layout
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, "brdfnorm": meta}
    with OpenEXR.File(header, channels) as image:
        image.write(str(tmp_path / "nan.exr"))
    with pytest.raises(TableFileError) as caught:
        lut.load(tmp_path / "nan.exr")
    assert caught.value.message.startswith("table E, cell [1, 2]: nan"), caught.value.message
    half = lut.load(lut.save(bp_table, tmp_path / "h.exr", half=True))  # two parts: the grid, then E_avg
    assert half["E"].dtype == half["E_avg"].dtype == np.float16
    assert np.array_equal(half["E_avg"], bp_table["E_avg"].astype(np.float16))
