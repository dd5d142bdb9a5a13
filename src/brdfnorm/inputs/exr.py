"""OpenEXR images (one or more parts, float32 or half channels), read through the ``OpenEXR`` bindings (an optional
extra), bounded from the headers before any pixel is read: every part's data window, the number of channels and
of values (:mod:`.limits`); the library's diagnostics kept off stdout and stderr."""

from __future__ import annotations

import io
import os
import sys
import tempfile
from contextlib import contextmanager

import numpy as np

from ..errors import TableFileError
from ..extras import require
from .guard import element_count, shorten
from .limits import MAX_AXIS, MAX_CHANNELS, MAX_ELEMENTS


@contextmanager
def _quiet_library():
    """File descriptors 1 and 2 pointed at a scratch file while a C library runs: OpenEXR prints its diagnostics
    on stdout (machine output only) and stderr, which would add lines to the one error line; what it says is in
    the exception it raises."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    try:
        with tempfile.TemporaryFile() as scratch:
            os.dup2(scratch.fileno(), 1)
            os.dup2(scratch.fileno(), 2)
            try:
                yield
            finally:
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
    finally:
        os.close(saved[0])
        os.close(saved[1])


def _exr_bounded(image, path: str) -> None:
    """Every part's data window (width and height from 1 to :data:`~.limits.MAX_AXIS`), the channels of all
    parts together (at most :data:`~.limits.MAX_CHANNELS`) and their values (at most
    :data:`~.limits.MAX_ELEMENTS`), from the headers, before any pixel is read."""
    parts = list(image.parts)
    values, channels = 0, 0
    for number, part in enumerate(parts):
        (x0, y0), (x1, y1) = (tuple(int(v) for v in corner) for corner in part.header["dataWindow"])
        what = "the image's data window" if len(parts) == 1 else f"the data window of part {number}"
        if x1 - x0 + 1 > MAX_AXIS or y1 - y0 + 1 > MAX_AXIS:
            raise TableFileError(f"{what} is {x1 - x0 + 1} × {y1 - y0 + 1} pixels; a table image has at most "
                                 f"{MAX_AXIS} a side", path)
        pixels = element_count([y1 - y0 + 1, x1 - x0 + 1], MAX_ELEMENTS, where=path, what=what)
        channels += len(part.header["channels"])
        if channels > MAX_CHANNELS:
            raise TableFileError(f"more than {MAX_CHANNELS} channels (a table image has a few)", path)
        values += pixels * len(part.header["channels"])
    if values > MAX_ELEMENTS:
        raise TableFileError(f"the image's {len(parts)} part(s) declare {values} values, more than "
                             f"{MAX_ELEMENTS}", path)


def exr_parts(data: bytes, path: str) -> tuple[list[dict], list[dict[str, np.ndarray]]]:
    """(header, {channel name: pixels}) of every part of an OpenEXR file, bounded from the headers before any
    pixel is read (:func:`_exr_bounded`), the library's diagnostics kept off stdout and stderr, any failure one
    :class:`~brdfnorm.errors.TableFileError` naming the file. Pixels keep their type (float32, or float16)."""
    OpenEXR = require("OpenEXR", "exr", where=".exr format")  # noqa: N806 - the module, by its own name

    if data[:4] != b"\x76\x2f\x31\x01":
        raise TableFileError("not an OpenEXR file", path)
    try:
        with _quiet_library():
            with OpenEXR.File(io.BytesIO(data), header_only=True) as image:
                _exr_bounded(image, path)  # inside the block: the headers' dicts are emptied when the file closes
            # separate_channels: otherwise the bindings merge R, G, B (and A) into one RGB(A) array
            with OpenEXR.File(io.BytesIO(data), separate_channels=True) as image:
                headers = [dict(part.header) for part in image.parts]
                images = [{n: np.array(c.pixels) for n, c in part.channels.items()} for part in image.parts]
    except TableFileError:
        raise
    except Exception as error:  # noqa: BLE001 — the bindings raise bare RuntimeErrors on bad files
        raise TableFileError(f"unreadable OpenEXR ({shorten(error, 200)})", path) from None
    return headers, images
