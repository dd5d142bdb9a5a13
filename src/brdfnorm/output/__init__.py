"""The output layer: every file the product writes (:mod:`.files`, :mod:`.directories`) and every result
format it prints (:mod:`.formats`)."""

from __future__ import annotations

from .files import STDOUT, write_file

__all__ = ["STDOUT", "write_file"]
