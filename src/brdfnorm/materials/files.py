"""Material files: a small TOML (``.toml``) or JSON (``.json``) file naming a material model and its parameters.

    # car paint
    model = "openpbr"            # the material model (brdfnorm materials: openpbr)
    name = "red car paint"       # optional, shown in reports

    [parameters]                 # any of the model's parameters; the rest keep their defaults
    base_color = [0.6, 0.05, 0.05]
    base_metalness = 0.2
    coat_weight = 1.0
    coat_roughness = 0.1
    layering = "view"

JSON has the same structure (``{"model": "openpbr", "parameters": {...}}``). The file is read through
:mod:`brdfnorm.inputs` (a regular file of at most 64 KiB); every error names the file and the line of the offending
key (TOML's and JSON's parsers report their own line for a syntax error). Keyword parameters given with the file
(``brdfnorm.load("paint.toml", coat_weight=0.5)``, ``-p`` on the command line) override the file's.
"""

from __future__ import annotations

import json
import os
import re
import tomllib
from pathlib import Path

from ..errors import BrdfFileError, BrdfnormError
from ..inputs import read_bounded
from ..models.base import Model

SUFFIXES = (".toml", ".json")
MAX_BYTES = 64 * 1024
TOP_KEYS = ("model", "name", "parameters")


class MaterialFileError(BrdfFileError):
    """A problem in a material file, at FILE:LINE."""


def is_material_file(path: str | os.PathLike) -> bool:
    return Path(os.fspath(path)).suffix.lower() in SUFFIXES


def _line_of(text: str, key: str, json_format: bool) -> int | None:
    """The first line that assigns ``key`` (``key =`` in TOML, ``"key":`` in JSON), for error messages."""
    pattern = (rf'"{re.escape(key)}"\s*:' if json_format else rf'^\s*("?){re.escape(key)}\1\s*=')
    for number, line in enumerate(text.splitlines(), start=1):
        if re.search(pattern, line):
            return number
    return None


def read_material(path: str | os.PathLike) -> tuple[str, str, dict, dict]:
    """(model name, display name, parameters, line of each parameter) from a material file."""
    where = os.fspath(path)
    data = read_bounded(path, MAX_BYTES, error=MaterialFileError)
    json_format = Path(where).suffix.lower() == ".json"
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as failure:
        raise MaterialFileError(f"not UTF-8 text (byte {failure.start})", where) from None
    try:
        document = json.loads(text) if json_format else tomllib.loads(text)
    except json.JSONDecodeError as failure:
        raise MaterialFileError(f"invalid JSON: {failure.msg}", where, failure.lineno, failure.colno) from None
    except tomllib.TOMLDecodeError as failure:
        match = re.search(r"\(at line (\d+), column (\d+)\)", str(failure))
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(failure))
        line, column = (int(match.group(1)), int(match.group(2))) if match else (None, None)
        raise MaterialFileError(f"invalid TOML: {message}", where, line, column) from None
    if not isinstance(document, dict):
        raise MaterialFileError("expected a table of keys (model, parameters)", where, 1)
    for key in document:
        if key not in TOP_KEYS:
            raise MaterialFileError(f"unknown key {key!r} (expected {', '.join(TOP_KEYS)})", where,
                                    _line_of(text, key, json_format))
    model = document.get("model")
    if not isinstance(model, str):
        raise MaterialFileError("the key 'model' must name the material model, e.g. model = \"openpbr\"", where,
                                _line_of(text, "model", json_format) or 1)
    name = document.get("name", Path(where).stem)
    if not isinstance(name, str):
        raise MaterialFileError("the key 'name' must be text", where, _line_of(text, "name", json_format))
    parameters = document.get("parameters", {})
    if not isinstance(parameters, dict):
        raise MaterialFileError("'parameters' must be a table of NAME = VALUE", where,
                                _line_of(text, "parameters", json_format))
    lines = {key: _line_of(text, key, json_format) for key in parameters}
    for key, value in parameters.items():
        if isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            parameters[key] = tuple(float(v) for v in value)
        elif not isinstance(value, (str, int, float, bool)):
            raise MaterialFileError(f"parameter {key!r}: expected a number, a list of 3 numbers or text, got "
                                    f"{type(value).__name__}", where, lines[key])
    return model, name, parameters, lines


def load_material(path: str | os.PathLike, registry, **overrides: object) -> Model:
    """The model a material file describes, bound to its parameters (``overrides`` win)."""
    where = os.fspath(path)
    model_name, name, parameters, lines = read_material(path)
    if model_name not in registry or not getattr(registry[model_name], "material", False):
        materials = ", ".join(n for n in registry if getattr(registry[n], "material", False))
        raise MaterialFileError(f"unknown material model {model_name!r} (materials: {materials})", where,
                                lines.get("model"))
    cls = registry[model_name]
    known = {p.name for p in cls.parameters}
    for key in parameters:
        if key not in known:
            model = cls()
            try:
                model.parameter(key)
            except BrdfnormError as failure:
                raise MaterialFileError(failure.message, where, lines[key]) from None
    try:
        model = cls(**parameters)
    except BrdfnormError as failure:
        bad = next((k for k in parameters if failure.where and k in failure.where), None)
        raise MaterialFileError(failure.message if bad is None else f"{bad}: {failure.message}", where,
                                lines.get(bad)) from None
    if overrides:
        model = model.with_params(**overrides)
    model.source_path = where
    model.material_name = name
    return model
