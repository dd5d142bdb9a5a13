"""The project's exceptions: every bad input ends in one of these, never in a bare traceback.

The CLI prints ``error: <where>: <message>`` on one line and exits 2 for a :class:`BrdfnormError`
(bad input or usage), 1 for anything else (an internal error).
"""

from __future__ import annotations


class BrdfnormError(Exception):
    """Base class: a problem with what the user gave us (a file, an argument, a parameter)."""

    def __init__(self, message: str, where: str | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.where = where

    def __str__(self) -> str:
        return f"{self.where}: {self.message}" if self.where else self.message

    def __reduce__(self):
        # Errors raised in a worker process (brdfnorm.parallel) travel back pickled; the subclasses' own
        # __init__ signatures differ, so rebuild from the attributes rather than by calling __init__.
        return _rebuild, (type(self), self.args, dict(self.__dict__))


def _rebuild(cls: type[BrdfnormError], args: tuple, state: dict) -> BrdfnormError:
    error = cls.__new__(cls)
    error.args = args
    error.__dict__.update(state)
    return error


class ParameterError(BrdfnormError, ValueError):
    """A model parameter is unknown, of the wrong type, or outside a hard limit."""


class ParameterTypeError(ParameterError, TypeError):
    """A model parameter of the wrong type (text, complex, a date): both a ValueError and a TypeError."""


class ArgumentError(BrdfnormError, ValueError):
    """A command-line or API argument is malformed (``where`` names the argument, e.g. ``--theta``)."""


class ArgumentTypeError(ArgumentError, TypeError):
    """An API argument of the wrong type (a list where a name goes, a complex angle): both a ValueError and a
    TypeError, so callers may catch either."""


class ModelNotFoundError(BrdfnormError, LookupError, ValueError):
    """Neither a built-in model name nor a readable file (a bad value, so also a ValueError)."""


class BrdfFileError(BrdfnormError):
    """A problem in a ``.brdf`` file, located at ``FILE:LINE:COL`` in the file's own numbering."""

    def __init__(self, message: str, path: str, line: int | None = None, column: int | None = None) -> None:
        where = str(path)
        if line is not None:
            where += f":{line}"
            if column is not None:
                where += f":{column}"
        super().__init__(message, where)
        self.path = str(path)
        self.line = line
        self.column = column


class MissingExtraError(BrdfnormError, ImportError):
    """An optional dependency is not installed; the message says which extra installs it
    (:func:`brdfnorm.extras.require`)."""

    def __init__(self, message: str, where: str | None = None, module: str | None = None) -> None:
        super().__init__(message, where)
        self.module = module


class EvaluationError(BrdfnormError, ArithmeticError):
    """A BRDF could not be evaluated (non-finite values, loop budget exhausted, ...)."""


class OutputError(BrdfnormError, OSError):
    """An output file or directory cannot be written."""


class TableFileError(BrdfFileError):
    """A lookup-table file (``brdfnorm.lut.load``) is not one brdfnorm wrote, or is damaged: ``FILE[:LINE]``."""
