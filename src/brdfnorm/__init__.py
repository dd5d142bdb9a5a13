"""brdfnorm: exact energy normalization of analytic BRDFs.

Directional albedo E(V) = ∫ f(L, V)(N·L) dL over the upper hemisphere (seed 002's statement), normalization
factors 1/E under a named convention, fits of cheap formulas, shader code, and checks of the seed articles.
Frame: N = +z, X = +x, Y = +y; angles in radians in the API, degrees on the command line.

>>> import brdfnorm as bn
>>> m = bn.load("blinn-phong", n=512)
>>> round(float(bn.albedo(m, 0.0, method="quadrature", rtol=1e-12).value[0]), 12)
0.048517341979
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from .errors import ArgumentTypeError, BrdfnormError, ModelNotFoundError, ParameterError
from .registry import lazy_exports
from .version import __version__ as __version__  # re-exported: brdfnorm.__version__

if TYPE_CHECKING:  # (imported on first use below: PEP 562's module __getattr__)
    from .engine.methods import AlbedoResult, albedo
    from .models import REGISTRY, Model
    from .normalization import NormalizationResult, normalize

__all__ = ["AlbedoResult", "BrdfnormError", "Model", "NormalizationResult", "REGISTRY", "albedo", "load",
           "load_text", "normalize"]

#: The public names imported on first use, by the module that defines them (PEP 562), and every subpackage
#: (``brdfnorm.materials``, ``brdfnorm.lut``, ...) as it is asked for.
__getattr__, __dir__ = lazy_exports(__name__, {
    "AlbedoResult": "engine.methods", "albedo": "engine.methods", "REGISTRY": "models", "Model": "models",
    "NormalizationResult": "normalization", "normalize": "normalization",
}, subpackages=True)


def load(name_or_path: str | Path, **params: object) -> Model:
    """A built-in model by name (``brdfnorm models`` lists them), a BRDF Explorer ``.brdf`` file by path, a
    material file (``.toml`` or ``.json``, :mod:`brdfnorm.materials.files`), or a
    Mitsuba 3 BSDF: ``mitsuba:PLUGIN`` with its properties as keywords, or a Mitsuba ``.xml`` file
    (:mod:`brdfnorm.models.mitsuba`, the ``mitsuba`` extra)."""
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise ArgumentTypeError(f"expected a model name or a path, got {type(name_or_path).__name__}",
                                where="model")
    key = os.fspath(name_or_path)
    if not isinstance(key, str):
        raise ArgumentTypeError("expected a text path, got bytes", where="model")
    from .models import REGISTRY

    if key in REGISTRY:
        return REGISTRY[key](**params)
    from .models import mitsuba

    if mitsuba.is_mitsuba(key):  # Mitsuba itself is imported only when such a model is asked for
        return mitsuba.load(key, **params)
    path = Path(key)
    from .materials import files as material_files

    if material_files.is_material_file(key):  # a material file: TOML or JSON naming a material model
        return material_files.load_material(key, REGISTRY, **params)
    if path.exists():
        if not path.is_file():  # a directory, FIFO (reading it would block), device or socket
            kind = "a directory" if path.is_dir() else "not a regular file (a FIFO, device or socket)"
            raise ModelNotFoundError(f"{kind}, not a .brdf file", where=key)
        from .brdffile import load_brdf  # the GLSL toolchain loads only when a file is asked for

        return load_brdf(path, **params)
    if path.suffix == ".brdf" or "/" in key or "\\" in key:
        raise ModelNotFoundError("no such file", where=key)
    from .validate import short_repr

    raise ModelNotFoundError(f"unknown model {short_repr(key)}: not a built-in ({', '.join(REGISTRY)}) and no "
                             "such file", where="model")


def load_text(text: str, path: str, **params: object) -> Model:
    """The model :func:`load` builds from the file ``path``, built from the file's ``text`` instead: what a
    worker receives with a table job (:class:`brdfnorm.parallel.ModelSource`), which may not see the file.
    A Mitsuba ``.xml`` path takes the ``<bsdf>`` element's text; any other path a ``.brdf`` file's text."""
    from .models import mitsuba

    if mitsuba.is_mitsuba(path):
        if params:
            raise ParameterError("a Mitsuba XML file's properties are set in the file", where=path)
        return mitsuba.load_string(text, path)
    from .brdffile import compile_brdf, parse_brdf  # the GLSL toolchain loads only when a file is asked for

    return compile_brdf(parse_brdf(text, path), **params)
