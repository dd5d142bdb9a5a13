"""The reader core (issue 40): one bounded decoder per file format, one set of limits, used by every command
that reads a user's file — ``lut`` and ``fit --lut`` (:mod:`brdfnorm.lut.readers`), ``audit``
(:mod:`brdfnorm.audit.readers`), ``check`` and the explorer through them, checkpoints and ``.brdf`` files.

* :mod:`.limits` — every limit, documented in one table;
* :mod:`.guard` — regular files only, the size from ``stat`` before a byte is read (:func:`read_bounded`),
  declared shapes counted without overflow (:func:`element_count`), every parse failure one error naming the file
  (:func:`parsing`), quoted text elided in the middle (:func:`shorten`);
* one decoder per format, each returning plain numpy arrays (what a table *means* is its command's business):
  :mod:`.npz` (numpy archives), :mod:`.png` (8/16-bit, vectorized unfiltering), :mod:`.exr` (OpenEXR parts and
  channels), :mod:`.delimited` (CSV), :mod:`.jsonio` (JSON), :mod:`.literals` (C/C++/GLSL/HLSL/JavaScript array
  literals) and :mod:`.raw` (raw binary: offset, shape, dtype, byte order, memory order).

A new format goes here as one module: it takes the file's bytes (from :func:`read_bounded` with its cap in
:data:`.limits.MAX_FILE_BYTES`), checks every size the file declares against :mod:`.limits` before allocating,
decodes with vectorized code, and raises :class:`~brdfnorm.errors.TableFileError` naming the file; then the
commands' readers map its arrays to their meaning.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..registry import lazy_exports
from .guard import element_count, parsing, read_bounded, regular_file, shorten

if TYPE_CHECKING:
    from .npz import npz_arrays

__all__ = ["element_count", "npz_arrays", "parsing", "read_bounded", "regular_file", "shorten"]


#: ``npz_arrays`` imported on first use (PEP 562): a ``.brdf`` file's load reads with :func:`read_bounded` and
#: needs no numpy archive decoder.
__getattr__, __dir__ = lazy_exports(__name__, {"npz_arrays": "npz"})
