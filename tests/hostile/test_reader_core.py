"""The reader core's decoders (:mod:`brdfnorm.inputs`, issues 40 and 41) against independent references: PNG
unfiltering of every filter type against a filter written here from the PNG specification (§9.2), array literals
(empty elements, trailing commas, size expressions, deep nesting), the CSV header rule and row errors, raw binary
placement, and the vectorized number count as an upper bound of what the scanner reads."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from brdfnorm.errors import TableFileError
from brdfnorm.inputs import png
from brdfnorm.inputs.delimited import read_rows
from brdfnorm.inputs.literals import count_tokens, find_literals
from brdfnorm.inputs.raw import decode as raw_decode


def _filtered(image: np.ndarray, bpp: int, kinds: list[int]) -> bytes:
    """The PNG filter of ``image`` (rows of bytes) with filter ``kinds[y]`` on row y, pixel by pixel as the
    specification writes it (an independent route: plain Python integers, no numpy arithmetic)."""
    out, previous = [], [0] * image.shape[1]
    for y, kind in enumerate(kinds):
        row = [int(v) for v in image[y]]
        line = []
        for x, value in enumerate(row):
            a = row[x - bpp] if x >= bpp else 0
            b = previous[x]
            c = previous[x - bpp] if x >= bpp else 0
            p = a + b - c
            paeth = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else b if abs(p - b) <= abs(p - c) else c
            predictor = (0, a, b, (a + b) // 2, paeth)[kind]
            line.append((value - predictor) % 256)
        out.append(bytes([kind] + line))
        previous = row
    return b"".join(out)


@pytest.mark.parametrize("height, width, channels, depth", [(5, 7, 3, 8), (6, 4, 4, 16), (9, 3, 1, 16),
                                                            (3, 8, 2, 8), (1, 11, 1, 8), (7, 1, 3, 16)])
def test_png_unfiltering_matches_the_specification(height, width, channels, depth):
    rng = np.random.default_rng(height * 100 + width)
    codes = rng.integers(0, 2**depth, (height, width, channels))
    image = np.frombuffer(codes.astype(">u2" if depth == 16 else np.uint8).tobytes(), np.uint8).reshape(height, -1)
    colour = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    for kinds in ([4] * height, [3] * height, [1] * height, [2] * height, list(rng.integers(0, 5, height))):
        raw = _filtered(image, channels * depth // 8, kinds)
        data = (png.SIGNATURE + png._chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0))
                + png._chunk(b"IDAT", zlib.compress(raw)) + png._chunk(b"IEND", b""))
        decoded, read_depth, _ = png.decode(data, "t.png")
        assert read_depth == depth and np.array_equal(decoded, codes), kinds


def test_png_unknown_filter_names_its_row():
    raw = b"\x00\x07" + b"\x05\x07"
    data = (png.SIGNATURE + png._chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 2, 8, 0, 0, 0, 0))
            + png._chunk(b"IDAT", zlib.compress(raw)) + png._chunk(b"IEND", b""))
    with pytest.raises(TableFileError, match="filter type 5 in row 1"):
        png.decode(data, "t.png")


def test_png_side_longer_than_the_axis_limit_is_refused_from_ihdr():
    data = (png.SIGNATURE + png._chunk(b"IHDR", struct.pack(">IIBBBBB", 100_000, 1, 8, 0, 0, 0, 0))
            + png._chunk(b"IDAT", zlib.compress(b"")) + png._chunk(b"IEND", b""))
    with pytest.raises(TableFileError, match="65536 pixels a side"):
        png.decode(data, "t.png")


def test_literals_trailing_comma_is_c_and_empty_elements_are_refused():
    (literal,) = find_literals("const float t[2][2] = {{1, 2,}, {3, 4},};", "t.h")
    assert list(literal.values) == [1, 2, 3, 4] and literal.declared == (2, 2) and literal.nested == (2, 2)
    for text in ("const float t[] = {1,,2};", "const float t[] = {,1, 2};", "var t = [1, 2,, 3];"):
        with pytest.raises(TableFileError, match="empty element"):
            find_literals(text, "t.h")


def test_literals_size_expression_is_the_shape_and_other_expressions_are_not():
    body = ", ".join(["0.5"] * 8)
    (literal,) = find_literals(f"static const float g[2 * 2 * 2] = {{{body}}};", "t.h")
    assert literal.declared == (2, 2, 2)
    (literal,) = find_literals(f"static const float g[N + 2] = {{{body}}};", "t.h")
    assert literal.declared == ()


def test_literals_deep_nesting_is_linear_and_not_a_shape():
    text = "const float t[] = " + "{" * 50_000 + "1, 2" + "}" * 50_000 + ";"
    (literal,) = find_literals(text, "t.h")
    assert list(literal.values) == [1, 2] and literal.nested == (2,)


def test_literals_name_the_token_that_is_not_a_number():
    (literal,) = find_literals("const float t[3] = {1, nan, 2};", "t.h")
    assert "'nan'" in literal.problem and literal.line == 1


@pytest.mark.parametrize("text", ["float t[] = {1.5e-5, .25, 0x1F, 3u, 2.f, -7, +8};",
                                  "var a = [1e+10, 2E-3, 0.5]; // 12 34\n/* 5 */ let b = 6;",
                                  "x1 = y2 + 3.0 * z4;"])
def test_the_vectorized_count_bounds_the_numbers_scanned(text):
    numbers, tokens = count_tokens(text)
    scanned = sum(len(lit.values) for lit in find_literals(text, "t.js"))
    assert scanned <= numbers <= tokens


def test_csv_header_rule():
    rows = read_rows(b"# made by hand\nmu,E\n0.5,0.25\n1,0.5\n", "t.csv")
    assert rows.comments == ["made by hand"] and rows.header == ["mu", "E"] and rows.first_line == 3
    assert rows.values.tolist() == [[0.5, 0.25], [1.0, 0.5]]
    assert read_rows(b"0.5,0.25\n1,0.5\n", "t.csv").header is None
    with pytest.raises(TableFileError, match="column 2") as caught:
        read_rows(b"0.5,0\x005\n1,0.5\n", "t.csv")  # a NUL does not make a header
    assert caught.value.line == 1
    with pytest.raises(TableFileError, match="column 2"):
        read_rows(b"mu,0.5\n1,0.5\n", "t.csv")  # names and numbers mixed


def test_csv_row_errors_name_row_line_and_cell():
    with pytest.raises(TableFileError, match="row 2, column 2: '1\\+2j' is not a number") as caught:
        read_rows(b"a,b\n1,2\n3,1+2j\n", "t.csv")
    assert caught.value.line == 3
    with pytest.raises(TableFileError, match="row 2 has 3 cells, the first has 2"):
        read_rows(b"1,2\n3,4,5\n", "t.csv")


def test_csv_rows_are_counted_before_parsing():
    with pytest.raises(TableFileError, match="rows"):
        read_rows(b"x\n" + b"1\n" * (5 * 1024 * 1024), "t.csv")


def test_raw_offset_byte_order_and_memory_order():
    values = np.arange(6, dtype=">u2").reshape(2, 3)
    data = b"HEAD" + values.tobytes(order="F")
    got = raw_decode(data, "t.bin", shape=(2, 3), dtype="uint16", byteorder=">", offset=4, order="F",
                     max_elements=100)
    assert np.array_equal(got, values) and got.dtype.isnative
    with pytest.raises(TableFileError, match="after offset 2"):
        raw_decode(data, "t.bin", shape=(2, 3), dtype="uint16", byteorder=">", offset=2, max_elements=100)


def test_literals_names_and_comments_beyond_ascii():
    found = find_literals("const float é_t[2] = {1, 2}; // café²\nconst float u[2] = {3, 4};", "t.h")
    assert [(lit.name, list(lit.values)) for lit in found] == [("é_t", [1, 2]), ("u", [3, 4])]
