"""Anisotropic tables, issue #45 item 4: a three-axis table (μ, roughness, anisotropy) as one 16-bit PNG — an
atlas of (roughness × μ) tiles, one per anisotropy value, stacked top to bottom, its layout in the metadata —
read back by :func:`brdfnorm.lut.load` within the 16-bit quantization, in the engine layout and others; the
pixel at (row, column) is the cell the atlas sentence names."""

from __future__ import annotations

import json
import zlib

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.lut import anisotropy, formats


@pytest.fixture(scope="module")
def table():
    axes = {"mu": [0.2, 0.6, 1.0], "roughness": [0.4, 0.8], "anisotropy": [0.0, 0.5, 1.0]}
    return anisotropy.compute(bn.load("ggx"), axes, anisotropy="burley", rtol=1e-5, average=False)


def text_chunk(data: bytes) -> dict:
    """The brdfnorm tEXt chunk of a PNG, parsed here by hand (no brdfnorm reader involved)."""
    at = 8
    while at < len(data):
        length = int.from_bytes(data[at:at + 4], "big")
        kind, body = data[at + 4:at + 8], data[at + 8:at + 8 + length]
        if kind == b"tEXt":
            key, _, value = body.partition(b"\0")
            return json.loads(value)
        at += 12 + length
    raise AssertionError("no tEXt chunk")


def pixels(data: bytes, rows: int, columns: int) -> np.ndarray:
    """The 16-bit greyscale samples, inflated and unfiltered here by hand (filter type 0 or 1..4 as written)."""
    at, idat = 8, b""
    while at < len(data):
        length = int.from_bytes(data[at:at + 4], "big")
        if data[at + 4:at + 8] == b"IDAT":
            idat += data[at + 8:at + 8 + length]
        at += 12 + length
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(rows, 1 + 2 * columns)
    assert np.all(raw[:, 0] == 0), "this check reads unfiltered scanlines only"
    return raw[:, 1:].reshape(rows, columns, 2).astype(np.int64) @ np.array([256, 1])


def test_atlas_round_trip_in_the_engine_layout(table, tmp_path):
    path = lut.save(table, tmp_path / "E.png")
    back = lut.load(path)
    assert back["E"].shape == table["E"].shape == (3, 2, 3)
    assert np.max(np.abs(back["E"] - table["E"])) <= np.ptp(table["E"]) / 131070 * (1 + 1e-9)
    meta = text_chunk(path.read_bytes())
    assert meta["png"]["axes"] == ["anisotropy", "roughness", "mu"]  # x = μ, y = roughness, anisotropy blocks
    assert "tile of 2 rows (roughness) x 3 columns (mu)" in meta["png"]["atlas"]
    assert meta["anisotropy"]["parameterization"] == "burley"


def test_pixels_are_the_cells_the_atlas_names(table, tmp_path):
    path = lut.save(table, tmp_path / "E.png")
    data = path.read_bytes()
    try:
        codes = pixels(data, 3 * 2, 3)
    except AssertionError:
        pytest.skip("the writer filtered the scanlines")
    lo, hi = text_chunk(data)["png"]["channels"]["R"]["lo"], text_chunk(data)["png"]["channels"]["R"]["hi"]
    for a in range(3):
        for r in range(2):
            for m in range(3):
                value = lo + codes[a * 2 + r, m] / 65535 * (hi - lo)
                assert abs(value - table["E"][m, r, a]) <= (hi - lo) / 131070 * (1 + 1e-9)


@pytest.mark.parametrize("layout", ["axes", "x=anisotropy,y=mu,v=up"])
def test_other_layouts(table, layout, tmp_path):
    back = lut.load(lut.save(table, tmp_path / "E.png", layout=formats.layouts.parse(layout),
                             tables=["E", "E_error", "1-E"]))
    for name in ("E", "E_error", "1-E"):
        assert np.max(np.abs(back[name] - table[name])) <= np.ptp(table[name]) / 131070 * (1 + 1e-9), name


def test_cli_writes_a_three_axis_png(capsys, tmp_path):
    from brdfnorm.cli import main

    out = tmp_path / "aniso.png"
    try:
        main(["lut", "ggx", "--anisotropy", "aspect", "--axis", "mu=0.5,1", "--axis", "alpha=0.3", "--axis",
              "aspect=0.5,1", "--rtol", "1e-5", "--no-average", "-o", str(out)])
    except SystemExit as done:
        assert not done.code, capsys.readouterr().err
    back = lut.load(out)
    assert back["E"].shape == (2, 1, 2) and back.meta["anisotropy"]["parameterization"] == "aspect"
