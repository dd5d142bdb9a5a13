"""PNG images of tables, read and written: 8- or 16-bit, grey, grey + alpha, RGB or RGBA — brdfnorm's own
(:mod:`brdfnorm.lut.images` writes them, :mod:`brdfnorm.lut.readers` reads them back) and any an engine ships
(``brdfnorm audit``).

PNG (ISO/IEC 15948, W3C PNG 2nd edition §11–12): chunks with CRCs, IHDR first; the image is the zlib stream of
the IDAT chunks, each row a filter byte (0 None, 1 Sub, 2 Up, 3 Average, 4 Paeth, §9.2) and the filtered bytes.
Bounded before inflating: the size of the decoded image follows from IHDR (width and height each at most
:data:`~.limits.MAX_AXIS`, their product × samples at most :data:`~.limits.MAX_ELEMENTS`), and the inflate is
capped at that length plus one byte (a zlib bomb stops there). Unfiltering is vectorized: rows of filters None,
Sub and Up one numpy step per row; an image with Average or Paeth rows by anti-diagonal wavefronts (a pixel depends
only on its left, upper and upper-left neighbours, all on earlier diagonals), height + width − 1 numpy steps.
Palette and interlaced images are refused (no LUT is stored that way). Written with filter 0 and a tEXt chunk for
metadata.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

from ..errors import TableFileError
from .guard import element_count
from .limits import MAX_AXIS, MAX_ELEMENTS

SIGNATURE = b"\x89PNG\r\n\x1a\n"
CHANNELS = {0: 1, 4: 2, 2: 3, 6: 4}  # colour type -> channels
NAMES = {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}


def decode(data: bytes, where: str) -> tuple[np.ndarray, int, dict[str, str]]:
    """(codes (height, width, channels) as integers, bit depth, tEXt entries) of a PNG within the limits."""
    if not data.startswith(SIGNATURE):
        raise TableFileError("not a PNG file", where)
    position, header, idat, text = len(SIGNATURE), None, [], {}
    while position + 12 <= len(data):
        (length,) = struct.unpack(">I", data[position:position + 4])
        kind, body = data[position + 4:position + 8], data[position + 8:position + 8 + length]
        crc_bytes = data[position + 8 + length:position + 12 + length]
        if len(body) != length or len(crc_bytes) != 4:
            raise TableFileError(f"truncated PNG chunk {kind!r} at byte {position}", where)
        if zlib.crc32(kind + body) & 0xFFFFFFFF != struct.unpack(">I", crc_bytes)[0]:
            raise TableFileError(f"corrupt PNG chunk {kind!r} at byte {position} (CRC)", where)
        if kind == b"IHDR":
            if length != 13:
                raise TableFileError("malformed IHDR", where)
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"tEXt" and b"\x00" in body:
            key, _, value = body.partition(b"\x00")
            text[key.decode("latin-1")] = value.decode("latin-1")
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
        position += 12 + length
    else:
        raise TableFileError("truncated PNG: no IEND chunk", where)
    if header is None:
        raise TableFileError("no IHDR chunk", where)
    width, height, depth, colour, _, _, interlace = header
    if colour not in CHANNELS:
        raise TableFileError(f"PNG colour type {colour} (palette) is not a table image", where)
    if depth not in (8, 16):
        raise TableFileError(f"PNG bit depth {depth}; tables are read at 8 or 16 bits", where)
    if interlace:
        raise TableFileError("interlaced PNG is not read", where)
    channels = CHANNELS[colour]
    if width > MAX_AXIS or height > MAX_AXIS:
        raise TableFileError(f"a {width} × {height} image: a table image has at most {MAX_AXIS} pixels a side",
                             where)
    element_count((height, width, channels), MAX_ELEMENTS, where=where,
                  what="the image (height × width × samples)")
    size = depth // 8
    stride = width * channels * size
    expected = height * (1 + stride)
    try:
        raw = zlib.decompressobj().decompress(b"".join(idat), expected + 1)
    except zlib.error as error:
        raise TableFileError(f"corrupt image data ({error})", where) from None
    if len(raw) != expected:
        raise TableFileError(f"image data holds {len(raw)} bytes, IHDR needs {expected} (truncated?)", where)
    rows = np.frombuffer(raw, dtype=np.uint8).reshape(height, 1 + stride)
    out = _unfilter(rows, channels * size, where)
    codes = out.view(">u2") if size == 2 else out
    return codes.reshape(height, width, channels).astype(np.int64), depth, text


def _unfilter(rows: np.ndarray, bpp: int, where: str) -> np.ndarray:
    """The image bytes of filtered ``rows`` (each a filter byte, then the row), PNG §9.2."""
    kinds = rows[:, 0]
    unknown = np.flatnonzero(kinds > 4)
    if unknown.size:
        raise TableFileError(f"unknown PNG filter type {int(kinds[unknown[0]])} in row {int(unknown[0])}", where)
    data = rows[:, 1:]
    if np.any(kinds >= 3):
        return _wavefront(data, kinds, bpp)
    out = np.empty_like(data)
    previous = np.zeros(data.shape[1], dtype=np.uint8)
    for y, kind in enumerate(kinds.tolist()):  # one numpy step per row
        line = data[y]
        if kind == 0:
            current = line
        elif kind == 2:
            current = line + previous  # uint8 arithmetic is modulo 256
        else:  # Sub: a running sum (mod 256) over the pixels, byte lane by byte lane
            current = np.cumsum(line.reshape(-1, bpp), axis=0, dtype=np.uint8).ravel()
        out[y] = current
        previous = current
    return out


def _wavefront(data: np.ndarray, kinds: np.ndarray, bpp: int) -> np.ndarray:
    """Unfiltering by anti-diagonals of pixels: pixel (y, x) needs (y, x − 1), (y − 1, x) and (y − 1, x − 1),
    all on diagonals before y + x, so each diagonal is one vectorized step whatever its rows' filters."""
    height, stride = data.shape
    width = stride // bpp
    pixels = data.reshape(height, width, bpp).astype(np.int16)
    out = np.zeros((height + 1, width + 1, bpp), dtype=np.int16)  # a zero row above, a zero column to the left
    kind = kinds.astype(np.int16)
    for k in range(height + width - 1):
        y = np.arange(max(0, k - width + 1), min(height - 1, k) + 1)
        x = k - y
        a, b, c = out[y + 1, x], out[y, x + 1], out[y, x]
        p = a + b - c
        pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
        paeth = np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))
        f = kind[y][:, None]
        predictor = np.select([f == 1, f == 2, f == 3, f == 4], [a, b, (a + b) >> 1, paeth], 0)
        out[y + 1, x + 1] = (pixels[y, x] + predictor) & 255
    return out[1:, 1:].reshape(height, stride).astype(np.uint8)


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def encode(codes: np.ndarray, depth: int, text: dict[str, str] | None = None) -> bytes:
    """A PNG of integer ``codes`` (height, width, channels 1–4) at ``depth`` 8 or 16 bits."""
    height, width, channels = codes.shape
    colour = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    dtype = ">u2" if depth == 16 else np.uint8
    raw = b"".join(b"\x00" + np.ascontiguousarray(row, dtype=dtype).tobytes() for row in codes)
    chunks = [_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0))]
    for key, value in (text or {}).items():
        chunks.append(_chunk(b"tEXt", key.encode("latin-1") + b"\x00" + value.encode("latin-1", "replace")))
    chunks += [_chunk(b"IDAT", zlib.compress(raw, 9)), _chunk(b"IEND", b"")]
    return SIGNATURE + b"".join(chunks)
