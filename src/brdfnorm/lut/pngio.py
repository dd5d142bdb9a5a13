"""PNG images of tables, read and written: 8- or 16-bit, grey, grey + alpha, RGB or RGBA — brdfnorm's own
(:mod:`.images` writes them, :mod:`.readers` reads them back) and any an engine ships (``brdfnorm audit``).

PNG (ISO/IEC 15948, W3C PNG 2nd edition §11–12): chunks with CRCs, IHDR first; the image is the zlib stream of
the IDAT chunks, each row a filter byte (0 None, 1 Sub, 2 Up, 3 Average, 4 Paeth, §9.2) and the filtered bytes.
Bounded before inflating: the size of the decoded image follows from IHDR, is checked with
:func:`brdfnorm.inputs.element_count`, and the inflate is capped at that length plus one byte (a zlib bomb stops
there). Palette and interlaced images are refused (no LUT is stored that way). Written with filter 0 and a tEXt
chunk for metadata.
"""

from __future__ import annotations

import json
import struct
import zlib

import numpy as np

from ..errors import TableFileError
from ..inputs import element_count

SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: Most pixels × channels a table image may have.
MAX_SAMPLES = 64 * 1024 * 1024
CHANNELS = {0: 1, 4: 2, 2: 3, 6: 4}  # colour type -> channels
NAMES = {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}


def decode(data: bytes, where: str, max_samples: int = MAX_SAMPLES) -> tuple[np.ndarray, int, dict[str, str]]:
    """(codes (height, width, channels) as integers, bit depth, tEXt entries) of a PNG of at most
    ``max_samples`` pixels × channels."""
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
    element_count((height, width, channels), max_samples, where=where, what="the image (height × width × samples)")
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
    height, stride = rows.shape[0], rows.shape[1] - 1
    out = np.zeros((height, stride), dtype=np.uint8)
    previous = np.zeros(stride, dtype=np.int64)
    for y in range(height):
        kind, line = int(rows[y, 0]), rows[y, 1:].astype(np.int64)
        if kind == 0:
            current = line
        elif kind == 2:
            current = (line + previous) & 255
        elif kind == 1:  # Sub: a running sum per byte of the pixel
            current = np.cumsum(line.reshape(-1, bpp), axis=0).ravel() & 255
        elif kind in (3, 4):  # Average and Paeth depend on the reconstructed left byte: byte by byte
            current = np.zeros(stride, dtype=np.int64)
            for x in range(stride):
                a = int(current[x - bpp]) if x >= bpp else 0
                b = int(previous[x])
                if kind == 3:
                    current[x] = (line[x] + (a + b) // 2) & 255
                else:
                    c = int(previous[x - bpp]) if x >= bpp else 0
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    predictor = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                    current[x] = (line[x] + predictor) & 255
        else:
            raise TableFileError(f"unknown PNG filter type {kind} in row {y}", where)
        out[y] = current
        previous = current
    return out


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


def brdfnorm_scaling(text: dict[str, str]) -> tuple[np.ndarray, np.ndarray] | None:
    """(lo, hi) per channel of a PNG that ``brdfnorm lut`` wrote (value = lo + code/65535·(hi − lo)), else None.
    A channel without a table (B of a two-table RGB image) is lo = 0, hi = 1."""
    payload = text.get("brdfnorm-lut")
    if payload is None:
        return None
    try:
        info = json.loads(payload)["png"]
        if "channels" not in info:  # one greyscale table (before the R, G, B, A mapping)
            return np.array([float(info["lo"])]), np.array([float(info["hi"])])
        entries = list(info["channels"].values())
        count = 1 if len(entries) == 1 else 3 if len(entries) <= 3 else 4
        entries += [{"lo": 0.0, "hi": 1.0}] * (count - len(entries))
        return (np.array([float(e["lo"]) for e in entries]), np.array([float(e["hi"]) for e in entries]))
    except (KeyError, TypeError, ValueError, AttributeError):
        return None
