"""The release of brdfnorm (CHANGELOG.md lists them): ``pyproject.toml`` reads it, ``brdfnorm --version`` prints
it, and every file brdfnorm writes records it. A module of its own, importing nothing, so that any module can
read it without an import cycle through the package."""

__version__ = "0.4.0"
